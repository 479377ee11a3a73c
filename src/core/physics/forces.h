/* The force stage of the forward pass (forward.c): the elastic forces k = dV/dq, the generalized
 * forces Q (the caller's held forces, the scene's effects, the actuator lag) and their power.
 * Private. */
#ifndef FLEX3RPR_FORCES_H
#define FLEX3RPR_FORCES_H

#include "data.h"

/* From d->t, d->held, d->lag and the stages before: d->k, d->Q, d->input, d->commanded (with
 * actuator lag) and d->power. */
void f3r_force_stage(const f3r_model* m, f3r_data* d);

/* k(q) (nq) alone, for the queries and the tests. */
void f3r_elastic_forces(const f3r_model* m, const double* q, double* k);

#endif
