/* The forward pass: f3r_forward runs the stages a caller asks for on the inputs in f3r_data
 * (data.h). Private. */
#ifndef FLEX3RPR_FORWARD_H
#define FLEX3RPR_FORWARD_H

#include "data.h"

/* Runs the stages in `what` (F3R_FWD_*) on the inputs in d, in order. Returns F3R_ERR_SINGULAR
 * when the closed position stage finds a leg that cannot reach its joint, else F3R_OK. */
f3r_status f3r_forward(const f3r_model* m, f3r_data* d, unsigned what);

#endif
