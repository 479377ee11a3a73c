/* The position stage of the forward pass (forward.c): per link the direction, length, modal sums
 * and constraint blocks, and g, from the full coordinates q or, closed, from the independent ones z
 * by the loop closure. Private. */
#ifndef FLEX3RPR_POSITION_H
#define FLEX3RPR_POSITION_H

#include "data.h"

/* Legs whose beam root comes closer than this fraction of l to A_i are degenerate: there the
 * constraint Jacobian loses rank (det of the leg's 2x2 block is rho + l), and the loop closure
 * refuses them. A run stops long before, at the collapse guard (events.h,
 * F3R_COLLAPSE_LEG_FRACTION = 0.1); this bound only keeps the closure itself finite. */
#define F3R_CLOSURE_MIN_LEG_FRACTION 1e-3

/* From d->q: per link c, s, L, w and the modal sums, the platform joints' directions, G's
 * direction-dependent blocks and g. */
void f3r_position_stage(const f3r_model* m, f3r_data* d);
/* From d->z: the same with rho_i and each leg's direction from the loop closure, into
 * d->q_closed (d->q points there; theta_i are not filled: f3r_fwd_leg_angles gives them), and
 * g = 0. F3R_ERR_SINGULAR when a leg cannot reach its joint. */
f3r_status f3r_position_stage_closed(const f3r_model* m, f3r_data* d);

/* The leg strokes rho_i alone from the platform pose and modal coordinates in q, by the same
 * closure and arithmetic as the closed stage (the same values to the last bit), without its
 * constraint blocks: what the event roots, evaluated once a step, need. */
f3r_status f3r_fwd_leg_strokes(const f3r_model* m, const double* q, double rho[3]);
/* theta_i in q from the closed directions of the position stage, on the model's branch. */
void f3r_fwd_leg_angles(const f3r_model* m, const f3r_data* d, double* q);
/* f3r_model_actuation_condition at q from the position stage's platform joints. */
double f3r_data_actuation_condition(const f3r_model* m, const f3r_data* d, const double* q);

#endif
