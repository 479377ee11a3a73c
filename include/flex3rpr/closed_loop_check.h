/* The closed-loop measurement of a session's accuracy request: the check configuration
 * (f3r_accuracy_check_scene: one more mode, the static shapes, a tenth of the tolerance) stepped
 * on the commands the run was given, period by period, and the largest end-effector distance
 * between the two at the periods' ends. That is a controller's accuracy, measured as it runs,
 * where no estimate can know the commands ahead.
 *
 * The session (session.h) steps it beside the run, or leaves it to the shell (options
 * measure_apart): the node runs it on a thread of its own, so that the check's cost never
 * slows the real-time loop. Every call here touches the check alone, never the run: one thread
 * may drive it while another steps the session. Nothing allocates after create. */
#ifndef FLEX3RPR_CLOSED_LOOP_CHECK_H
#define FLEX3RPR_CLOSED_LOOP_CHECK_H

#include "flex3rpr/model.h"
#include "flex3rpr/scene.h"
#include "flex3rpr/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct f3r_closed_loop_check f3r_closed_loop_check;

/* The check of a run of `scene` (resolved, with its accuracy request) on `run_model`, which
 * must outlive the check. */
f3r_status f3r_closed_loop_check_create(const f3r_scene* scene, const f3r_model* run_model,
                                        f3r_closed_loop_check** check, f3r_error* err);
void f3r_closed_loop_check_destroy(f3r_closed_loop_check* check);

/* One period: the run held `forces` (the run model's nq values, model.h layout) until t and its
 * end-effector reached run_xy there. A check that cannot follow ends the measurement (NaN, and
 * why), never the run. */
void f3r_closed_loop_check_period(f3r_closed_loop_check* check, const double* forces, double t,
                                  const double run_xy[2]);

/* The run was set to a new platform pose and twist (and, with has_modal, a modal state, which
 * the check's richer basis cannot take: the measurement then ends). */
void f3r_closed_loop_check_set_state(f3r_closed_loop_check* check, const double pose[3],
                                     const double twist[3], int has_modal);

/* The measurement ends here, with the reason (a run that failed or left the periods' grid). */
void f3r_closed_loop_check_lose(f3r_closed_loop_check* check, const char* why);

/* Back to t = 0 and a measurement of 0. */
f3r_status f3r_closed_loop_check_reset(f3r_closed_loop_check* check, f3r_error* err);

/* Keeps the check as it is, and puts it back: a session's failed step undoes its check too. */
void f3r_closed_loop_check_save(f3r_closed_loop_check* check);
void f3r_closed_loop_check_restore(f3r_closed_loop_check* check);

/* The largest end-effector distance so far (m; NaN once the check could not follow, *lost then
 * saying why, else ""), and whether it meets the request within F3R_CHECK_MARGIN. */
double f3r_closed_loop_check_measured(const f3r_closed_loop_check* check, int* request_met,
                                      const char** lost);
/* The request (m) the check measures against. */
double f3r_closed_loop_check_request(const f3r_closed_loop_check* check);

#ifdef __cplusplus
}
#endif
#endif
