/* f3r_sim: one run of a model, integrated by SUNDIALS IDA. It owns the state, the integrator
 * memory, the caller's held forces and the outputs; a model may serve several simulations.
 * Nothing is allocated after f3r_sim_create. */
#ifndef FLEX3RPR_SIM_H
#define FLEX3RPR_SIM_H

#include "flex3rpr/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct f3r_sim f3r_sim;

typedef struct {
  f3r_formulation formulation;
  f3r_integrator integrator;
  double rtol, atol;       /* atol applies to positions (m, rad) and rates; see sim.c for others */
  double max_step;         /* s; 0: no limit */
  int max_order;           /* IDA: highest BDF order, 1..5 */
  int analytic_jacobian;   /* 1: f3r_residual_jacobian; 0: IDA's difference quotients */
  int stop_at_outputs;     /* 1: never step past the requested output time (for live input) */
  char rk_table[48];       /* erk, dirk: the Butcher table by name (f3r_rk_table_known); "":
                           * the integrator's default (Fehlberg 7(8); Kvaerno 7(4,5)) */
  int dense_linear_solver; /* IDA: 1 forces SUNDIALS' dense LU; 0 (default) uses the Schur
                           * complement on the kinematic rows when the Jacobian is analytic */
} f3r_solver_settings;

/* The scene's solver settings, analytic Jacobian, interpolated outputs. */
f3r_solver_settings f3r_solver_settings_from_scene(const f3r_scene* scene);

typedef struct {
  long steps, residual_evals, jacobian_evals;
  long error_test_failures, nonlinear_failures;
  long restarts;           /* integrator re-initialisations (force changes, resets) */
  long recoverable_errors; /* residual calls that asked IDA to cut the step */
  double last_step;        /* s */
  int last_order;
} f3r_sim_stats;

typedef struct {
  double t;                             /* s */
  int leg;                              /* 0..2 */
  int at_max;                           /* 1 at stroke_max, 0 at stroke_min */
  double rho;                           /* m, where it happened */
  double rate_before, rate_after;       /* rho_i' (m/s) */
  double impulse;                       /* N s along rho_i */
  double kinetic_before, kinetic_after; /* T (J) */
  double q[F3R_MAX_Q];                  /* configuration at the impact */
} f3r_impact_record;

typedef struct {
  double t;                      /* s */
  double q[F3R_MAX_Q];           /* generalized coordinates (model.h layout) */
  double v[F3R_MAX_Q];           /* their rates */
  double forces[F3R_MAX_Q];      /* applied generalized forces Q at t */
  double actuator[6];            /* effort of the six actuators, as ros_control reports it:
                                  * [0..2] leg force on rho_i (N), [3..5] cylinder torque on
                                  * theta_i (N m); the held force plus the scene's scripted input
                                  * at t, or for the legs with actuator lag the lag state (the
                                  * force the actuator delivers) */
  double passive[6];             /* forces[j] - actuator[j] on the same six joints: joint
                                  * friction, in-plane gravity and the other effects (N, N m) */
  double lambda[F3R_NCON];       /* multipliers: constraint force on the loop (x, y per link), N */
  double tip_deflection[3];      /* w_i(l), m */
  double tip_deflection_rate[3]; /* m/s */
  double kinetic_energy;         /* J */
  double potential_energy;       /* J */
  double external_work;          /* J, work of Q since t = 0 */
  double energy_balance_error;   /* |T + V - W + impact losses - (T0 + V0)|, J */
  long impacts;                  /* end-stop impacts so far */
  double impact_loss;            /* J of kinetic energy the impacts took */
  f3r_impact_record last_impact;
  int stop_locked[3];         /* leg i held at its stop: -1 at stroke_min, +1 at stroke_max, 0 */
  double stop_force[3];       /* the stop's force on leg i along rho_i (N; + pushes outwards):
                               * the contact's Lagrange multiplier, zero on a free leg; in neither
                               * forces nor passive */
  double constraint_residual; /* max |g_k(q)|, m */
  double velocity_residual;   /* max |(G v)_k|, m/s */
  double actuation_condition; /* condition number of the map from the three leg forces to the
                                  * platform wrench (moment scaled by r_PC), capped at 1e16: it is
                                  * infinite at a type-II singularity such as the home pose */
  f3r_sim_stats stats;
} f3r_outputs;

f3r_status f3r_sim_create(const f3r_model* model, const f3r_solver_settings* settings,
                          f3r_sim** sim, f3r_error* err);
void f3r_sim_destroy(f3r_sim* sim);

/* Back to the scene's initial state at t = 0 with no held forces. */
f3r_status f3r_sim_reset(f3r_sim* sim, f3r_error* err);

/* Held generalized forces (nq values, model.h layout), added to the scene's scripted inputs from
 * the current time on. The integrator restarts there, so it never integrates across the jump.
 * Non-finite values are rejected and change nothing. */
f3r_status f3r_sim_set_forces(f3r_sim* sim, const double* held, f3r_error* err);

/* Puts the run in a given state at the current time, as a node's "set state" service or a
 * test's initial condition would: the platform pose (X_p, Y_p, phi_p) (m, m, rad) and its rate
 * (X_p', Y_p', phi_p') (m/s, m/s, rad/s), both in the world (base) frame, and the modal
 * coordinates eta (m) and their rates (m/s), nq - 9 values each in model.h order (link 1, 2, 3);
 * NULL for either gives zero. rho_i, theta_i and their rates follow from the loop closure
 * (f3r_model_close_loops, f3r_model_close_loop_rates), so the state is consistent
 * (constraint_residual and velocity_residual at rounding level). Time, held forces, actuator lag
 * states and the impact count are kept; the integrator restarts as after f3r_sim_set_forces; the
 * energy balance restarts: external work 0, and T + V of the new state (less the impact losses
 * so far) is its reference, so energy_balance_error measures the run from here.
 * Errors change nothing (state, time, energy reference): F3R_ERR_ARGUMENT for non-finite values
 * or, with end stops, a stroke rho_i outside [stroke_min, stroke_max] (the message names the leg,
 * its stroke and the range); F3R_ERR_SINGULAR for a pose the legs cannot reach (a leg would need
 * rho_i + l <= 0, or below the collapse guard 0.1 l where a run stops at once). */
f3r_status f3r_sim_set_state(f3r_sim* sim, const double pose[3], const double twist[3],
                             const double* modal, const double* modal_rate, f3r_error* err);

/* Integrates to t_out (> current time). On failure the last good state is kept. */
f3r_status f3r_sim_advance(f3r_sim* sim, double t_out, f3r_error* err);

/* A run's state as f3r_sim_save found it: time, state vector, held forces, the legs locked at
 * their stops, the impacts and the energy balance's reference. f3r_sim_restore puts it back and
 * restarts the integrator there, so that a caller can undo a step that failed (a session's step
 * leaves the run as it was). Allocated once for its run; saving and restoring allocate nothing. */
typedef struct f3r_sim_snapshot f3r_sim_snapshot;
f3r_status f3r_sim_snapshot_create(const f3r_sim* sim, f3r_sim_snapshot** snapshot, f3r_error* err);
void f3r_sim_snapshot_destroy(f3r_sim_snapshot* snapshot);
void f3r_sim_save(const f3r_sim* sim, f3r_sim_snapshot* snapshot);
f3r_status f3r_sim_restore(f3r_sim* sim, const f3r_sim_snapshot* snapshot, f3r_error* err);

double f3r_sim_time(const f3r_sim* sim);
const f3r_model* f3r_sim_model(const f3r_sim* sim);
f3r_formulation f3r_sim_formulation(const f3r_sim* sim);

/* Outputs at the current time, computed from the state on request. */
const f3r_outputs* f3r_sim_outputs(f3r_sim* sim);

/* The guard against silent garbage: a run whose energy balance error passes this fraction of the
 * largest T + V so far is suspect. Correct runs of the shipped scenes at their settings stay at or
 * below 2.6e-2 (free_vibration_long: 60 s of undamped vibration, BDF's numerical damping; the
 * others below 3.2e-4); Verner 8(5)6 on undamped fast modes and IDA held to BDF order 3 exit 0
 * at 0.90 and 0.998 with paths millimetres to decimetres off (docs/solvers.md). */
#define F3R_ENERGY_GUARD 0.1
/* An error below this (J) is rounding, whatever the fraction: a mechanism at rest whose T + V is
 * 5e-30 J balances to 1e-29 J (and a node would latch its warning on that). */
#define F3R_ENERGY_GUARD_FLOOR 1e-9

/* 1 when energy_balance_error (J) passes F3R_ENERGY_GUARD of largest_energy (J, the largest
 * T + V seen so far) and F3R_ENERGY_GUARD_FLOOR. */
int f3r_energy_guard_tripped(double energy_balance_error, double largest_energy);

/* Current state vector y of the formulation (f3r_state_size values). */
const double* f3r_sim_state(const f3r_sim* sim);

#ifdef __cplusplus
}
#endif
#endif
