/* The end stops' contacts at an event or a restart of a run: which legs touch a stop, the impact
 * that keeps every one of them out of it, and which of them stay held. One function decides all
 * of it for every leg at once, so that a push on one leg, an impact of another and a third held
 * at its stop are one problem, not three. Private. */
#ifndef FLEX3RPR_CONTACTS_H
#define FLEX3RPR_CONTACTS_H

#include "events.h"

/* No state a run accepts passes a stop by more than this (m): past it, the run fails with an
 * error naming the leg (f3r_contacts_check_strokes). */
#define F3R_STROKE_TOLERANCE 1e-9
/* A free leg closer to a stop than this (m), or past it, is in contact with it. */
#define F3R_CONTACT_GAP 1e-12

/* The contacts at time t (forces at their right limit) in the full state q, v, with the held
 * forces held (nq) and the actuator lag states lag (or NULL). root_info: the roots the
 * integrator found (events.h; NULL at a restart). locked (3) holds the legs locked at their stops
 * on entry (-1 at stroke_min, +1 at stroke_max) and on return.
 *   1. contact: the locked legs, the legs whose stop root fired, and the free legs within
 *      F3R_CONTACT_GAP of a stop or past it (by at most F3R_STROKE_TOLERANCE: further is an
 *      error);
 *   2. the legs in contact are put exactly on their stops (the least change of the platform's
 *      pose, the loops kept closed);
 *   3. the impact, where a free leg approaches its stop: the impulses p_i >= 0 into the stroke
 *      and the rates after it u_i >= c u_i^- (c the restitution; 0 for a leg that was not
 *      approaching, or that would rebound slower than F3R_RESTING_SPEED, or past
 *      F3R_MAX_IMPACTS_PER_MS) with p_i (u_i - c u_i^-) = 0: the complementarity problem over at
 *      most three legs, solved by trying each active set; then, impact or not, every leg in
 *      contact that leaves its stop slower than F3R_RESTING_SPEED rests on it;
 *   4. the legs left at rest on a stop lock where their stop forces push and every released one
 *      accelerates into the stroke (the same problem for forces); a leg whose force root fired is
 *      released wherever both are consistent.
 * Fills the impact's record and *legs_hit (the free legs that were approaching a stop; 0: no
 * impact), and *energy_lost (J, the kinetic energy the impact and the rest took). work holds
 * f3r_impact_work_size doubles. */
f3r_status f3r_contacts_resolve(const f3r_model* m, double t, const double* held, const double* lag,
                                const int* root_info, double* q, double* v, int* locked,
                                f3r_impact_window* window, f3r_impact_record* record, int* legs_hit,
                                double* energy_lost, double* work, f3r_error* err);

/* F3R_ERR_SOLVER, naming the leg, when a stroke in q passes a stop by more than
 * F3R_STROKE_TOLERANCE at t; else F3R_OK. */
f3r_status f3r_contacts_check_strokes(const f3r_model* m, const double* q, double t,
                                      f3r_error* err);

#endif
