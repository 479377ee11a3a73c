/* The velocity stage of the forward pass (forward.c): per link the rates, the velocity-dependent
 * forces h(q, v) and the constraint bias gamma = (dG/dt) v, from the position and mass stages.
 * Private. */
#ifndef FLEX3RPR_VELOCITY_H
#define FLEX3RPR_VELOCITY_H

#include "data.h"

/* From d->v; `closed`: from d->u, with rho_i' and theta_i' from G v = 0 into d->v_closed (d->v
 * points there). */
void f3r_velocity_stage(const f3r_model* m, f3r_data* d, int closed);

#endif
