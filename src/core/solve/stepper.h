/* The integrators behind f3r_sim: one interface, three SUNDIALS back ends. Private.
 *   IDA (variable-order BDF, implicit; both formulations)
 *   ARKODE ERKStep (explicit Runge-Kutta, Fehlberg 7(8) by default; minimal formulation only)
 *   ARKODE ARKStep (diagonally implicit Runge-Kutta, ESDIRK; minimal formulation only) */
#ifndef FLEX3RPR_STEPPER_H
#define FLEX3RPR_STEPPER_H

#include <math.h>
#include <stdio.h> /* arkode_butcher.h uses FILE without including it */

#include <arkode/arkode.h>
#include <arkode/arkode_butcher.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/sim.h"

#include "events.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const f3r_model* model;
  f3r_solver_settings settings;
  const double* held; /* the simulation's held forces */
  f3r_workspace* ws;  /* residual scratch */
  SUNContext ctx;
  void* mem;                             /* IDA or ERKStep memory */
  const struct f3r_arkode_calls* arkode; /* ERK, DIRK: their ARKODE calls (stepper.c) */
  N_Vector id, atol;                     /* IDA only */
  SUNMatrix J;                           /* IDA, DIRK */
  SUNLinearSolver ls;                    /* IDA, DIRK */
  f3r_sim_stats base;                    /* statistics accumulated before the last restart */
  f3r_sim_stats counted;     /* ERK, DIRK: the solver's own counters at the last restart, which
                              * base holds already: ARKODE's Reset keeps counting (stepper.c) */
  int root_info[F3R_NROOTS]; /* -1 where a root was found: 2i, 2i+1 end stops of leg i (min, max);
                            * F3R_COLLAPSE_ROOT + i: leg i reached the collapse guard */
  long recoverable;          /* right-hand side calls that asked for a smaller step */
  long residual_calls;       /* calls of the residual (IDA) or the right-hand side (ERK, DIRK, the
                              * DIRK Jacobian's included) since creation: the tests' own count,
                              * beside the solvers' counters that the statistics read */
  long jacobian_rhs_evals;   /* DIRK: right-hand sides of its difference-quotient Jacobian, since
                              * creation */
  int ida_counters_folded;   /* IDA: 1 from a restart to the next IDASolve, whose set-up zeroes
                              * the linear solver's counters (IDAReInit only IDA's), which base
                              * holds already */
  double jacobian_cj;        /* IDA: cj of the last Jacobian, for the Schur solver's setup */
  double t_segment;          /* the last (re)start. An explicit stage at exactly this time takes
                           * the forces' right limit (f3r_stepper_force_time), as the consistent
                           * state there did: a held force that jumps at a breakpoint belongs to
                           * the segment after it */
  double output_interval;    /* t_out - t of the simulation's current f3r_sim_advance: ERK and
                              * DIRK interpolate outputs, so they cap their step at a few */
  double step_cap;           /* ERK, DIRK: the largest step ARKODE was given (0: none) */
  int yp_stale;              /* 1: advance left y' unset (an explicit method needs no y'); the
                           * simulation evaluates it only when outputs ask for it */
  int locked[3];             /* the legs held at their stops (equations.h f3r_stop_locks), as the
                              * simulation set them in ws too: the roots watch their forces */
  char message[256];         /* the solver's last error message: the core never prints */
} f3r_stepper;

typedef struct {
  /* Creates the solver at t0 from a consistent y, y'. */
  f3r_status (*setup)(f3r_stepper* st, N_Vector y, N_Vector yp, double t0, f3r_error* err);
  /* Restarts at t from a consistent y, y' (after a jump in the forces). */
  f3r_status (*restart)(f3r_stepper* st, N_Vector y, N_Vector yp, double t, f3r_error* err);
  /* Integrates to tout; y (and y', unless it sets yp_stale) receive the state there, or the
   * last good one on failure.
   * tstop >= tout: never step past it (a force changes there); tstop = tout stops exactly at
   * tout, a later one lets the output at tout be interpolated. *event = 1 when it stopped early
   * at an end stop (root_info says which). */
  f3r_status (*advance)(f3r_stepper* st, double tout, double tstop, N_Vector y, N_Vector yp,
                        double* t_reached, int* event, f3r_error* err);
  /* Statistics since creation (base plus the current solver's counters). */
  void (*stats)(const f3r_stepper* st, f3r_sim_stats* out);
  void (*release)(f3r_stepper* st);
} f3r_stepper_ops;

extern const f3r_stepper_ops f3r_ida_stepper;

extern const f3r_stepper_ops f3r_erk_stepper;
extern const f3r_stepper_ops f3r_dirk_stepper;

/* The stepper of integrator kind k (kinds.h: built-ins in F3R_INTEGRATOR_* order, then those
 * registered); NULL when there is none. */
const f3r_stepper_ops* f3r_stepper_ops_of(int kind);
/* Adds an integrator: its descriptor to the scene layer's table (f3r_integrator_kind_add) and
 * its stepper here, at the same index, which it returns (the f3r_integrator a scene names it
 * by); F3R_ERR_ARGUMENT when the table refuses it. Not thread-safe: before the first scene. */
f3r_status f3r_integrators_register(const f3r_integrator_kind* kind, const f3r_stepper_ops* ops,
                                    int* index, f3r_error* err);

/* The simulation's stepper (sim.c), for the tests. */
const f3r_stepper* f3r_sim_stepper(const f3r_sim* sim);

/* Both back ends (stepper.c): the SUNDIALS error handler, which stores the message in the
 * stepper (its user data) since the core never prints, and the root functions (events.c) at y. */
void f3r_stepper_error_handler(int code, const char* module, const char* function, char* msg,
                               void* user);
int f3r_stepper_roots(const f3r_stepper* st, double t, const double* y, double* g);
/* The ARKODE back ends' (ERKStep, ARKStep) right-hand side and root functions: the minimal
 * formulation's explicit ODE, forces at their right limit at a restart; user is the stepper. */
int f3r_stepper_explicit_rhs(realtype t, N_Vector y, N_Vector ydot, void* user);
int f3r_stepper_explicit_roots(realtype t, N_Vector y, realtype* g, void* user);
/* The time at which the right-hand side evaluates the forces for a stage at t. */
static inline double f3r_stepper_force_time(const f3r_stepper* st, double t) {
  return t <= st->t_segment ? nextafter(st->t_segment, INFINITY) : t;
}
/* A failed SUNDIALS call as F3R_ERR_SOLVER: the call, its flag's name (flag_name, which SUNDIALS
 * allocates: freed here) and the solver's last message. */
f3r_status f3r_stepper_failed(const f3r_stepper* st, f3r_error* err, const char* call,
                              char* flag_name);
/* Returns f3r_stepper_failed from the enclosing function (which has st and err) when call
 * returns a negative flag; name_of is the back end's GetReturnFlagName. */
#define F3R_STEPPER_CHECK(call, name_of)                                      \
  do {                                                                        \
    const int flag_ = (call);                                                 \
    if (flag_ < 0) return f3r_stepper_failed(st, err, #call, name_of(flag_)); \
  } while (0)
/* Every root only when moving into a stop or the guard (direction -1). */
void f3r_stepper_root_directions(int directions[F3R_NROOTS]);
/* The ARKODE back ends' shared start: t0 as the segment's start, the minimal formulation
 * required, and the settings' Butcher table (or default_table) loaded; integrator names the back
 * end in errors ("erk", "dirk"). *table is NULL on error; the caller frees it. */
f3r_status f3r_stepper_explicit_start(f3r_stepper* st, double t0, int implicit,
                                      const char* default_table, ARKodeButcherTable* table,
                                      f3r_error* err);
typedef struct f3r_arkode_calls f3r_arkode_calls;

/* The calls ERKStep and ARKStep share, by back end, so that one restart, advance and set-up serve
 * both (stepper.c). */
struct f3r_arkode_calls {
  const char* evolve_name; /* "ERKStepEvolve", for errors */
  char* (*flag_name)(long flag);
  int (*set_err_handler)(void* mem, ARKErrHandlerFn handler, void* user);
  int (*ss_tolerances)(void* mem, realtype rtol, realtype atol);
  int (*set_user_data)(void* mem, void* user);
  int (*set_max_num_steps)(void* mem, long steps);
  int (*set_interpolant_degree)(void* mem, int degree);
  int (*set_max_step)(void* mem, realtype h);
  int (*root_init)(void* mem, int count, ARKRootFn g);
  int (*set_root_direction)(void* mem, int* directions);
  int (*set_stop_time)(void* mem, realtype t);
  int (*evolve)(void* mem, realtype tout, N_Vector y, realtype* t, int task);
  int (*get_root_info)(void* mem, int* roots);
  int (*get_dky)(void* mem, realtype t, int k, N_Vector dky);
  int (*reset)(void* mem, realtype t, N_Vector y);
  int (*get_num_steps)(void* mem, long* steps);
  int (*get_num_err_test_fails)(void* mem, long* fails);
  int (*get_last_step)(void* mem, realtype* h);
  int (*set_init_step)(void* mem, realtype h);
  /* The back end's counters as the solver holds them, since its creation (all of
   * f3r_sim_stats but restarts and recoverable_errors); f3r_arkode_counters fills the shared
   * ones. */
  void (*counters)(const f3r_stepper* st, f3r_sim_stats* raw);
};
/* The calls of one back end by its prefix (ERKStep, ARKStep), whose functions are named alike. */
#define F3R_ARKODE_CALLS(prefix, counters)                                                       \
  {                                                                                              \
#prefix "Evolve", prefix##GetReturnFlagName, prefix##SetErrHandlerFn, prefix##SStolerances,  \
        prefix##SetUserData, prefix##SetMaxNumSteps, prefix##SetInterpolantDegree,               \
        prefix##SetMaxStep, prefix##RootInit, prefix##SetRootDirection, prefix##SetStopTime,     \
        prefix##Evolve, prefix##GetRootInfo, prefix##GetDky, prefix##Reset, prefix##GetNumSteps, \
        prefix##GetNumErrTestFails, prefix##GetLastStep, prefix##SetInitStep, counters           \
  }
/* The options both ARKODE back ends set once their memory and table exist: the error handler,
 * tolerances, user data, step limits, quartic Hermite output and the roots. */
f3r_status f3r_arkode_configure(f3r_stepper* st, const f3r_arkode_calls* calls, f3r_error* err);
/* ops->restart, ops->advance and ops->stats of both ARKODE back ends, through st->arkode. */
f3r_status f3r_arkode_restart(f3r_stepper* st, N_Vector y, N_Vector yp, double t, f3r_error* err);
/* After an advance that failed: 1 when it was an ARKODE back end's attempt whose stage the
 * right-hand side refused (st->recoverable grew past asked_before), and the stepper has been
 * restarted from start (copied into y) at t with a hundredth of the step, at most three times
 * per *retries (stepper.c); the caller then advances again. */
int f3r_arkode_retry_refused(f3r_stepper* st, long asked_before, int* retries, N_Vector start,
                             N_Vector y, double t, f3r_error* err);
f3r_status f3r_arkode_advance(f3r_stepper* st, double tout, double tstop, N_Vector y, N_Vector yp,
                              double* t_reached, int* event, f3r_error* err);
void f3r_arkode_stats(const f3r_stepper* st, f3r_sim_stats* out);
/* raw = the counters every ARKODE back end has (steps, error test failures, last step; a failed
 * getter counts 0), the others 0: the start of a back end's counters. */
void f3r_arkode_counters(const f3r_stepper* st, f3r_sim_stats* raw);
/* A Butcher table by name (ARKODE's, e.g. ARKODE_FEHLBERG_13_7_8, or erk_tables.c's), explicit
 * or diagonally implicit; NULL when there is none by that name. The caller frees it. A last c of
 * 1 whose row of A is not b is moved 1e-9 below 1, so that ARKODE evaluates each step's first
 * stage instead of reusing the last (stepper.c). */
ARKodeButcherTable f3r_stepper_load_table(int implicit, const char* name);

#ifdef __cplusplus
}
#endif
#endif
