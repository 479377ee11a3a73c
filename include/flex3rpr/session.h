/* The session: a scene opened for a run, and the calls a shell makes on it. The CLI, the node and
 * the Python module each open one, so that a scene gives one physics, one set of checks and
 * limits, and one set of defaults wherever it runs; no shell checks a command or a state itself.
 *
 *   open       the scene file with its overrides ("FIELD=VALUE") and an accuracy request, the
 *              accuracy knob's choice, the model, a simulation at t = 0 and the scene's sensors
 *   step       commands held over whole periods, as a controller's (the node's
 *              ~step_with_command, flex3rpr.Sim.step): length, finiteness and the scene's limits
 *              (limits.force, .torque, .modal_force) checked first; a refused command or a step
 *              that fails leaves the session exactly as it was (state, time, held forces,
 *              outputs, sensors) and says why
 *   set_state  a new platform pose, twist and modal state, checked against the ranges the scene
 *              file's own initial state must keep
 *   reset      back to t = 0 and zero commands
 *   measure    with an accuracy request (and accuracy.verify, on by default), the check
 *              configuration (f3r_accuracy_check_scene) is stepped on the same commands, period
 *              by period, and the largest end-effector distance between the two at the periods'
 *              ends is the measured error: a closed loop's accuracy, measured as it runs
 *
 * A session owns its scene, model, simulation and sensors; nothing here allocates after open. */
#ifndef FLEX3RPR_SESSION_H
#define FLEX3RPR_SESSION_H

#include "flex3rpr/accuracy.h"
#include "flex3rpr/closed_loop_check.h"
#include "flex3rpr/scene.h"
#include "flex3rpr/sensors.h"
#include "flex3rpr/sim.h"
#include "flex3rpr/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct f3r_session f3r_session;

typedef struct {
  double accuracy;              /* > 0: an accuracy request (m), over the scene's own */
  const char* const* overrides; /* "FIELD=VALUE", as the CLI's --set, applied in order */
  int override_count;
  int commanded;     /* 1: commands come from outside and are held over periods (the node, Python's
                  * step): the knob's solver relation is the commanded one, and its model is sized
                  * for accuracy.excitation (accuracy.h); 0: scripted only */
  int measure_apart; /* 1: the session creates the closed-loop check but never steps it: the
                      * shell drives it (f3r_session_closed_loop_check), on a thread of its own
                      * (the node) */
  int model_only;    /* 1: the scene, the knob's choice and the model only, no simulation, sensors
                   * or check: for a shell that runs configurations of its own (the CLI's
                   * measured run, measured_run.h); then only the accessors up to
                   * f3r_session_choose_cpu may be called */
} f3r_session_options;

/* Opens scene_path (NULL options: none). On failure *session is NULL and err names the file, the
 * field and the allowed range. */
f3r_status f3r_session_open(const char* scene_path, const f3r_session_options* options,
                            f3r_session** session, f3r_error* err);
/* The same from a scene loaded already (copied; options' accuracy and overrides unused): a
 * shell that loads with its own names for the overrides' sources (the node's parameters). */
f3r_status f3r_session_open_scene(const f3r_scene* scene, const f3r_session_options* options,
                                  f3r_session** session, f3r_error* err);
void f3r_session_close(f3r_session* session);

const f3r_scene* f3r_session_scene(const f3r_session* session);
const f3r_model* f3r_session_model(const f3r_session* session);
const f3r_accuracy_choice* f3r_session_choice(const f3r_session* session);
/* s of process CPU time the accuracy knob's choice took at open (0 without a choice to make). */
double f3r_session_choose_cpu(const f3r_session* session);
f3r_sim* f3r_session_sim(f3r_session* session);
/* The scene's sensors, sampled at every period's end; NULL when the scene enables none. */
const f3r_sensors* f3r_session_sensors(const f3r_session* session);
/* Periods stepped since t = 0 (open or reset): period k ends at exactly k * period. */
long f3r_session_periods(const f3r_session* session);

/* With options.measure_apart, the check for the shell to drive (closed_loop_check.h); else NULL
 * (the session steps its check itself, or has none). */
struct f3r_closed_loop_check* f3r_session_closed_loop_check(f3r_session* session);

/* The closed-loop measurement: 1 when the session measures (an accuracy request with
 * accuracy.verify), with *measured (m, the largest end-effector distance from the check so far
 * since t = 0; NaN once the check could not follow, *lost saying why) and *request_met
 * (measured within F3R_CHECK_MARGIN of the request); 0 when it does not measure (or the shell
 * measures apart). */
int f3r_session_measurement(const f3r_session* session, double* measured, int* request_met,
                            const char** lost);

/* F3R_OK when forces (count values) is a command the session takes: count is the model's nq,
 * every value finite, and each within its limit (limits.force for the leg forces and the
 * platform's force components, limits.torque for the cylinder torques and the platform torque,
 * limits.modal_force for the modal forces). Else F3R_ERR_ARGUMENT with a message naming the
 * value ("leg_force_2", "platform_torque", "modal_force[4]"), what it is and the allowed range. */
f3r_status f3r_session_check_forces(const f3r_session* session, const double* forces, int count,
                                    f3r_error* err);
/* The same check on a scene's limits and a model's layout alone, its message the bare reason
 * ("leg_force_2 is 1200, out of range -1000..1000 (the scene's limits.force)"): for the node's
 * decoding of a message into forces, which must name the same values without a session. */
f3r_status f3r_command_check(const f3r_scene* scene, const f3r_model* model, const double* forces,
                             int count, f3r_error* err);

/* F3R_OK for a step of `periods` (a whole number, 1..1e9) periods of `period` s (finite,
 * 1e-9..1e3 s); else F3R_ERR_ARGUMENT naming which. */
f3r_status f3r_session_check_step(double periods, double period, f3r_error* err);

/* Holds forces (nq values, model.h layout, checked as above) for `periods` periods of `period`
 * s, as the node's ~step_with_command: the forces set, then the integration to the period's end,
 * k * period since t = 0, the sensors sampled there. On any error the session is as it was
 * before the call. */
f3r_status f3r_session_step(f3r_session* session, const double* forces, int count, double periods,
                            double period, f3r_error* err);

/* One period of forces a shell has checked piece by piece (the node sums its topics, each
 * checked on arrival with f3r_session_check_forces, so the sum may reach the sum of their
 * limits): only the count and finiteness are checked here. On any error the session is as it
 * was before the call. */
f3r_status f3r_session_advance(f3r_session* session, const double* forces, int count, double period,
                               f3r_error* err);

/* The platform pose (X_p, Y_p, phi_p) and twist in the base frame and the modal coordinates and
 * rates (modal_count values each: 0 gives zeros, else the model's nq - 9), as
 * f3r_sim_set_state, within the ranges of a scene's initial state (|X_p|, |Y_p| <= 1 m,
 * |phi_p| <= 1e3 rad, twist within 1e3, modal coordinates within 0.1 m and their rates within
 * 100 m/s). Time and held forces stay. On any error nothing changes. */
f3r_status f3r_session_set_state(f3r_session* session, const double pose[3], const double twist[3],
                                 const double* modal, const double* modal_rate, int modal_count,
                                 f3r_error* err);

/* The checks of f3r_session_set_state alone. */
f3r_status f3r_session_check_state(const f3r_model* model, const double pose[3],
                                   const double twist[3], const double* modal,
                                   const double* modal_rate, int modal_count, f3r_error* err);

/* Back to the scene's initial state at t = 0 with zero commands and fresh sensors. */
f3r_status f3r_session_reset(f3r_session* session, f3r_error* err);

#ifdef __cplusplus
}
#endif
#endif
