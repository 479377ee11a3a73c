/* The scene's optional force effects, each a stage with its own derivatives (effects.c). The
 * model keeps a list of the enabled ones only, so an effect that is off costs nothing. Private. */
#ifndef FLEX3RPR_EFFECTS_H
#define FLEX3RPR_EFFECTS_H

#include "data.h"

/* Fills m->effects with the effects the scene enables, in a fixed order. */
void f3r_model_compile_effects(f3r_model* m);
/* Q (nq) += the effects' forces at d->t, d->q, d->v and the position stage in d (the scripted
 * inputs' into d->input too). */
void f3r_effects_add_forces(const f3r_model* m, f3r_data* d, double* Q);
/* 1 when an effect has derivatives: only then do the Jacobians form dQ/dq and dQ/dv. */
int f3r_effects_have_derivatives(const f3r_model* m);
/* scale dQ/dq into dQ_dq and scale dQ/dv into dQ_dv (leading dimension ld; either NULL to
 * skip) at d's inputs and position stage. */
void f3r_effects_add_derivatives(const f3r_model* m, const f3r_data* d, double scale, double* dQ_dq,
                                 double* dQ_dv, int ld);

#endif
