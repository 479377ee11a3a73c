/* The mass stage of the forward pass (forward.c): each link's blocks of the mass matrix M(q),
 * from the position stage. Private. */
#ifndef FLEX3RPR_MASS_H
#define FLEX3RPR_MASS_H

#include "data.h"

void f3r_mass_stage(const f3r_model* m, f3r_data* d);

#endif
