/* The run API: initial state, held forces with clean restarts, outputs. The integration itself
 * is a stepper's (stepper_ida.c, stepper_erk.c). Nothing is allocated after f3r_sim_create. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/sim.h"
#include "residual.h"
#include "queries.h"
#include "contacts.h"
#include "stepper.h"
#include "workspace.h"

/* The largest state y: dae's 2 nq + 12 multipliers + 3 actuator lag states + W. */
#define F3R_MAX_STATE (2 * F3R_MAX_Q + 16)

struct f3r_sim {
  const f3r_model* model;
  f3r_solver_settings settings;
  const f3r_stepper_ops* ops;
  f3r_stepper stepper;
  int ny;
  N_Vector y, yp;
  N_Vector y_attempt; /* the consistent state an advance of the stepper starts from, for a retry */
  f3r_workspace* out_ws; /* scratch for outputs, so outputs never disturb the residual's */
  double held[F3R_MAX_Q];
  double t;            /* time of the current state */
  double t_restart;    /* the last restart's time, where the outputs take the forces' right limit
                        * as the state did */
  double energy0;      /* T + V at t = 0 (W = 0 there) */
  double* impact_work; /* f3r_impact_work_size */
  long impacts;
  double impact_loss;
  f3r_impact_record last_impact;
  f3r_impact_window impact_window; /* impacts in the last ms (events.h) */
  int locked[3];                   /* the legs held at their stops (equations.h f3r_stop_locks) */
  f3r_outputs out;
};

/* The legs held at their stops, for the residual's and the outputs' workspaces and the roots. */
static void set_locks(f3r_sim* s, const int* locked) {
  for (int i = 0; i < 3; ++i) s->locked[i] = s->stepper.locked[i] = locked[i];
  f3r_workspace_set_locks(s->stepper.ws, locked);
  f3r_workspace_set_locks(s->out_ws, locked);
}

f3r_solver_settings f3r_solver_settings_from_scene(const f3r_scene* scene) {
  f3r_solver_settings st;
  st.formulation = scene->formulation;
  st.integrator = scene->integrator;
  st.rtol = scene->rtol;
  st.atol = scene->atol;
  st.max_step = scene->max_step;
  st.max_order = scene->max_order;
  st.analytic_jacobian = 1;
  st.stop_at_outputs = 0;
  st.dense_linear_solver = 0;
  snprintf(st.rk_table, sizeof st.rk_table, "%s", scene->table);
  return st;
}

/* The actuator lag states of the current y, copied into lag (NULL when the model has none). */
static const double* lag_states(const f3r_sim* s, double* lag) {
  if (!s->model->n_lag) return NULL;
  const double* y = N_VGetArrayPointer(s->y);
  for (int i = 0; i < 3; ++i) lag[i] = y[f3r_lag_index(s->model, s->settings.formulation) + i];
  return lag;
}

/* y, y' at s->t from full coordinates and work W, consistent by construction. The forces are
 * their right limit at s->t: a scripted jump at a breakpoint t_b belongs to (t_b, ...). */
static f3r_status consistent_once(f3r_sim* s, const double* q, const double* v, const double* lag,
                                  double work, f3r_error* err) {
  const double t_forces = nextafter(s->t, INFINITY);
  const f3r_status st = f3r_consistent_state(s->model, s->settings.formulation, t_forces, q, v,
                                             s->held, lag, work, N_VGetArrayPointer(s->y),
                                             N_VGetArrayPointer(s->yp), NULL, s->stepper.ws);
  s->stepper.yp_stale = 0;
  if (st != F3R_OK)
    return f3r_error_set(
        err, st, "no consistent state at t = %.9g: %s", s->t,
        st == F3R_ERR_SINGULAR ? "the constrained mass matrix is singular" : "non-finite values");
  return F3R_OK;
}

/* y, y' at s->t from full coordinates and work W, consistent by construction, after the end
 * stops' contacts there (contacts.h: the legs in contact put on their stops, the impact, which
 * legs stay locked); q and v change with them. roots: the roots that stopped the integrator, or
 * NULL at a restart. */
static f3r_status consistent(f3r_sim* s, double* q, double* v, const double* lag, double work,
                             const int* roots, f3r_error* err) {
  int locked[3], legs_hit = 0;
  double lost = 0.0;
  memcpy(locked, s->locked, sizeof locked);
  f3r_status st =
      f3r_contacts_resolve(s->model, s->t, s->held, lag, roots, q, v, locked, &s->impact_window,
                           &s->last_impact, &legs_hit, &lost, s->impact_work, err);
  if (st != F3R_OK) return st;
  s->impacts += legs_hit;
  s->impact_loss += lost;
  s->t_restart = s->t;
  set_locks(s, locked);
  return consistent_once(s, q, v, lag, work, err);
}

/* With end stops, why the closed q's strokes are beyond them (naming the pose and the leg), or
 * 0. */
static f3r_status stroke_error(const f3r_model* m, const double* q, f3r_error* err) {
  if (!m->end_stops) return F3R_OK;
  const double* P = q + F3R_Q_X;
  for (int i = 0; i < 3; ++i) {
    const double rho = q[F3R_Q_RHO + i];
    if (rho < m->stroke_min || rho > m->stroke_max)
      return f3r_error_set(err, F3R_ERR_ARGUMENT,
                           "pose (%g, %g, %g) beyond the end stops: leg %d would need rho_%d = "
                           "%.6g m, outside [%.6g, %.6g] m",
                           P[0], P[1], P[2], i + 1, i + 1, rho, m->stroke_min, m->stroke_max);
  }
  return F3R_OK;
}

f3r_status f3r_sim_create(const f3r_model* model, const f3r_solver_settings* settings,
                          f3r_sim** out, f3r_error* err) {
  if (!model || !out) return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_sim_create: NULL argument");
  *out = NULL;
  f3r_sim* s = calloc(1, sizeof *s);
  if (!s) return f3r_error_set(err, F3R_ERR_MEMORY, "f3r_sim_create: out of memory");
  s->model = model;
  s->settings = settings ? *settings : f3r_solver_settings_from_scene(&model->scene);
  s->ops = f3r_stepper_ops_of((int)s->settings.integrator);
  if (!s->ops) {
    const int integrator = (int)s->settings.integrator;
    free(s);
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_sim_create: integrator %d is not one of %d",
                         integrator, f3r_integrator_kind_count());
  }
  s->ny = f3r_state_size(model, s->settings.formulation);
  f3r_stepper* stp = &s->stepper;
  stp->model = model;
  stp->settings = s->settings;
  stp->held = s->held;
  f3r_status st = F3R_OK;
  double q[F3R_MAX_Q], v[F3R_MAX_Q];
  if (s->settings.formulation != F3R_FORMULATION_DAE &&
      s->settings.formulation != F3R_FORMULATION_MINIMAL) {
    st = f3r_error_set(err, F3R_ERR_ARGUMENT,
                       "formulation %d: a simulation integrates dae or minimal (index3 is for "
                       "external solvers)",
                       (int)s->settings.formulation);
    goto fail;
  }
  if (!(s->settings.rtol > 0.0) || !(s->settings.atol > 0.0)) {
    st = f3r_error_set(err, F3R_ERR_ARGUMENT, "rtol %g and atol %g must be positive",
                       s->settings.rtol, s->settings.atol);
    goto fail;
  }
  if (SUNContext_Create(NULL, &stp->ctx) != 0) {
    st = f3r_error_set(err, F3R_ERR_SOLVER, "SUNContext_Create failed");
    goto fail;
  }
  s->y = N_VNew_Serial(s->ny, stp->ctx);
  s->yp = N_VNew_Serial(s->ny, stp->ctx);
  s->y_attempt = N_VNew_Serial(s->ny, stp->ctx);
  stp->ws = f3r_workspace_create(model);
  s->out_ws = f3r_workspace_create(model);
  s->impact_work = calloc(f3r_impact_work_size(model), sizeof(double));
  if (!s->y || !s->yp || !s->y_attempt || !stp->ws || !s->out_ws || !s->impact_work) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "f3r_sim_create: out of memory");
    goto fail;
  }
  /* Fused vector operations: IDA and ARKODE combine several vectors in one pass instead of one
   * call per term (the predictor, the error test, the stage sums), with each sum in the order the
   * single operations take it, so every result keeps its bits. The integrators' own vectors are
   * clones of y and inherit it. */
  if (N_VEnableFusedOps_Serial(s->y, SUNTRUE) != 0 ||
      N_VEnableFusedOps_Serial(s->yp, SUNTRUE) != 0) {
    st = f3r_error_set(err, F3R_ERR_SOLVER, "f3r_sim_create: fused vector operations failed");
    goto fail;
  }
  if (f3r_model_initial_state(model, q, v) != F3R_OK) {
    st = f3r_error_set(err, F3R_ERR_SCENE, "initial.platform_pose: the legs cannot reach it");
    goto fail;
  }
  if ((st = stroke_error(model, q, err)) != F3R_OK) goto fail;
  s->energy0 = f3r_kinetic_energy(model, q, v) + f3r_potential_energy(model, q);
  if ((st = consistent(s, q, v, NULL, 0.0, NULL, err)) != F3R_OK) goto fail;
  if ((st = s->ops->setup(stp, s->y, s->yp, 0.0, err)) != F3R_OK) goto fail;
  *out = s;
  return F3R_OK;
fail:
  f3r_sim_destroy(s);
  return st;
}

void f3r_sim_destroy(f3r_sim* s) {
  if (!s) return;
  s->ops->release(&s->stepper);
  if (s->y) N_VDestroy(s->y);
  if (s->yp) N_VDestroy(s->yp);
  if (s->y_attempt) N_VDestroy(s->y_attempt);
  f3r_workspace_destroy(s->stepper.ws);
  f3r_workspace_destroy(s->out_ws);
  free(s->impact_work);
  if (s->stepper.ctx) SUNContext_Free(&s->stepper.ctx);
  free(s);
}

f3r_status f3r_sim_reset(f3r_sim* s, f3r_error* err) {
  double q[F3R_MAX_Q], v[F3R_MAX_Q];
  f3r_status st = f3r_model_initial_state(s->model, q, v);
  if (st != F3R_OK) return f3r_error_set(err, st, "the initial pose cannot be reached");
  memset(s->held, 0, sizeof s->held);
  s->t = 0.0;
  s->impacts = 0;
  s->impact_loss = 0.0;
  memset(&s->impact_window, 0, sizeof s->impact_window);
  memset(&s->last_impact, 0, sizeof s->last_impact);
  set_locks(s, (const int[3]){0, 0, 0});
  if ((st = consistent(s, q, v, NULL, 0.0, NULL, err)) != F3R_OK) return st;
  st = s->ops->restart(&s->stepper, s->y, s->yp, 0.0, err);
  memset(&s->stepper.base, 0, sizeof s->stepper.base); /* a reset starts the count anew */
  s->stepper.recoverable = 0;
  return st;
}

f3r_status f3r_sim_set_forces(f3r_sim* s, const double* held, f3r_error* err) {
  const int nq = s->model->nq;
  int changed = 0;
  for (int n = 0; n < nq; ++n) {
    if (!isfinite(held[n]))
      return f3r_error_set(err, F3R_ERR_ARGUMENT, "force[%d] is %g, not finite", n, held[n]);
    changed |= held[n] != s->held[n];
  }
  if (!changed) return F3R_OK;
  double q[F3R_MAX_Q], v[F3R_MAX_Q], keep[F3R_MAX_Q], lag[3];
  const double* y = N_VGetArrayPointer(s->y);
  f3r_status st = f3r_state_to_full(s->model, s->settings.formulation, y, q, v);
  if (st != F3R_OK) return f3r_error_set(err, st, "the current state cannot be closed");
  memcpy(keep, s->held, sizeof keep);
  memcpy(s->held, held, (size_t)nq * sizeof(double));
  int keep_locks[3]; /* a new force may release a leg from its stop, or press one into it */
  memcpy(keep_locks, s->locked, sizeof keep_locks);
  const long keep_impacts = s->impacts;
  const double keep_loss = s->impact_loss;
  const f3r_impact_window keep_window = s->impact_window;
  const f3r_impact_record keep_record = s->last_impact;
  st = consistent(s, q, v, lag_states(s, lag), y[s->ny - 1], NULL, err);
  if (st == F3R_OK) st = s->ops->restart(&s->stepper, s->y, s->yp, s->t, err);
  if (st != F3R_OK) {
    memcpy(s->held, keep, sizeof keep);
    set_locks(s, keep_locks);
    s->impacts = keep_impacts;
    s->impact_loss = keep_loss;
    s->impact_window = keep_window;
    s->last_impact = keep_record;
  }
  return st;
}

/* Why pose and modal coordinates in q cannot be closed, or 0 when they can be: the first leg
 * whose root would have to reach A_i (the closure's F3R_ERR_SINGULAR) or come closer to it than
 * the collapse guard (a run would stop there at once), or, with end stops, whose stroke lies
 * outside them. q holds the pose and the modal coordinates; rho and theta are filled. */
static f3r_status closure_error(const f3r_model* m, double* q, f3r_error* err) {
  const double* P = q + F3R_Q_X;
  if (f3r_model_close_loops(m, q) != F3R_OK) {
    for (int i = 0; i < 3; ++i) { /* the closure's test, leg by leg, to name the leg */
      const double angle = m->platform_angle[i] + P[2];
      const double dx = P[0] + m->platform_radius * cos(angle) - m->base_joint[i][0];
      const double dy = P[1] + m->platform_radius * sin(angle) - m->base_joint[i][1];
      const double w = f3r_model_tip_deflection(m, q, i);
      if (dx * dx + dy * dy - w * w <= 1e-6 * m->link_length * m->link_length)
        return f3r_error_set(err, F3R_ERR_SINGULAR,
                             "pose (%g, %g, %g) unreachable: leg %d would need rho_%d + l <= 0 "
                             "(|C_%d - A_%d| = %.4g m, tip deflection %.4g m)",
                             P[0], P[1], P[2], i + 1, i + 1, i + 1, i + 1, hypot(dx, dy), w);
    }
    return f3r_error_set(err, F3R_ERR_SINGULAR, "pose (%g, %g, %g) unreachable by the legs", P[0],
                         P[1], P[2]);
  }
  for (int i = 0; i < 3; ++i) {
    const double len = q[F3R_Q_RHO + i] + m->link_length;
    if (len < F3R_COLLAPSE_LEG_FRACTION * m->link_length)
      return f3r_error_set(err, F3R_ERR_SINGULAR,
                           "pose (%g, %g, %g) unreachable: leg %d would need rho_%d + l = %.4g m, "
                           "below the collapse guard %.2g l where a run stops",
                           P[0], P[1], P[2], i + 1, i + 1, len, F3R_COLLAPSE_LEG_FRACTION);
  }
  return stroke_error(m, q, err);
}

static f3r_status check_finite_values(const double* x, int count, const char* what,
                                      f3r_error* err) {
  for (int k = 0; k < count; ++k)
    if (!isfinite(x[k]))
      return f3r_error_set(err, F3R_ERR_ARGUMENT, "%s[%d] is %g, not finite", what, k, x[k]);
  return F3R_OK;
}

f3r_status f3r_sim_set_state(f3r_sim* s, const double pose[3], const double twist[3],
                             const double* modal, const double* modal_rate, f3r_error* err) {
  if (!s || !pose || !twist)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_sim_set_state: NULL argument");
  const f3r_model* m = s->model;
  const int n_modal = m->nq - F3R_Q_MODAL;
  f3r_status st;
  if ((st = check_finite_values(pose, 3, "pose", err)) ||
      (st = check_finite_values(twist, 3, "twist", err)) ||
      (modal && (st = check_finite_values(modal, n_modal, "modal", err))) ||
      (modal_rate && (st = check_finite_values(modal_rate, n_modal, "modal_rate", err))))
    return st;
  double q[F3R_MAX_Q] = {0}, v[F3R_MAX_Q] = {0}, lag[3];
  memcpy(q + F3R_Q_X, pose, 3 * sizeof(double));
  memcpy(v + F3R_Q_X, twist, 3 * sizeof(double));
  if (modal) memcpy(q + F3R_Q_MODAL, modal, (size_t)n_modal * sizeof(double));
  if (modal_rate) memcpy(v + F3R_Q_MODAL, modal_rate, (size_t)n_modal * sizeof(double));
  if ((st = closure_error(m, q, err)) != F3R_OK) return st;
  f3r_model_close_loop_rates(m, q, v);
  /* The consistent state goes to scratch first (the outputs' workspace, which the integrator
   * never reads), so that a failure leaves the simulation as it was. */
  double y[F3R_MAX_STATE], yp[F3R_MAX_STATE];
  /* The new state's contacts: a leg set on its stop and pressed into it locks there, one set
   * moving into it rebounds. */
  int locks[3] = {0, 0, 0}, legs_hit = 0;
  double lost = 0.0; /* the balance starts anew from the state after it */
  f3r_impact_window window = {0};
  f3r_impact_record record;
  if ((st = f3r_contacts_resolve(m, s->t, s->held, lag_states(s, lag), NULL, q, v, locks, &window,
                                 &record, &legs_hit, &lost, s->impact_work, err)) != F3R_OK)
    return st;
  int keep_locks[3];
  memcpy(keep_locks, s->locked, sizeof keep_locks);
  set_locks(s, locks);
  st = f3r_consistent_state(m, s->settings.formulation, nextafter(s->t, INFINITY), q, v, s->held,
                            lag_states(s, lag), 0.0, y, yp, NULL, s->out_ws);
  if (st != F3R_OK) {
    set_locks(s, keep_locks);
    return f3r_error_set(
        err, st, "no consistent state at pose (%g, %g, %g): %s", pose[0], pose[1], pose[2],
        st == F3R_ERR_SINGULAR ? "the constrained mass matrix is singular" : "non-finite values");
  }
  double* sy = N_VGetArrayPointer(s->y);
  double* syp = N_VGetArrayPointer(s->yp);
  double keep_y[F3R_MAX_STATE], keep_yp[F3R_MAX_STATE];
  memcpy(keep_y, sy, (size_t)s->ny * sizeof(double));
  memcpy(keep_yp, syp, (size_t)s->ny * sizeof(double));
  memcpy(sy, y, (size_t)s->ny * sizeof(double));
  memcpy(syp, yp, (size_t)s->ny * sizeof(double));
  const int keep_stale = s->stepper.yp_stale;
  s->stepper.yp_stale = 0;
  if ((st = s->ops->restart(&s->stepper, s->y, s->yp, s->t, err)) != F3R_OK) {
    memcpy(sy, keep_y, (size_t)s->ny * sizeof(double));
    memcpy(syp, keep_yp, (size_t)s->ny * sizeof(double));
    s->stepper.yp_stale = keep_stale;
    set_locks(s, keep_locks);
    s->ops->restart(&s->stepper, s->y, s->yp, s->t, NULL);
    return st;
  }
  /* The balance starts anew: W = 0 in the new state, and T + V less the impact losses so far
   * (which the balance adds back) is the reference. */
  s->energy0 = f3r_kinetic_energy(m, q, v) + f3r_potential_energy(m, q) + s->impact_loss;
  memset(&s->impact_window, 0, sizeof s->impact_window);
  return F3R_OK;
}

/* At an end-stop event: the contacts there (contacts.h), then a restart. */
static f3r_status handle_stop_event(f3r_sim* s, f3r_error* err) {
  const double* y = N_VGetArrayPointer(s->y);
  double q[F3R_MAX_Q], v[F3R_MAX_Q], lag[3];
  f3r_status st = f3r_state_to_full(s->model, s->settings.formulation, y, q, v);
  if (st != F3R_OK)
    return f3r_error_set(err, st, "end stop at t = %.9g: the loops do not close", s->t);
  st = consistent(s, q, v, lag_states(s, lag), y[s->ny - 1], s->stepper.root_info, err);
  if (st == F3R_OK) st = s->ops->restart(&s->stepper, s->y, s->yp, s->t, err);
  return st;
}

/* The run's guard on the end stops: an error where a stroke of the state passes a stop. */
static f3r_status check_strokes(const f3r_sim* s, double t, f3r_error* err) {
  if (!s->model->end_stops) return F3R_OK;
  double q[F3R_MAX_Q], v[F3R_MAX_Q];
  if (f3r_state_to_full(s->model, s->settings.formulation, N_VGetArrayPointer(s->y), q, v) !=
      F3R_OK)
    return F3R_OK; /* a state that does not close fails elsewhere, with its own message */
  return f3r_contacts_check_strokes(s->model, q, t, err);
}

/* Integrates to t_out without crossing a breakpoint of the scripted inputs: at each one it stops
 * exactly and restarts from a consistent state with the forces' right limit. An attempt whose
 * stage the right-hand side refused is made again from its start (f3r_arkode_retry_refused). */
f3r_status f3r_sim_advance(f3r_sim* s, double t_out, f3r_error* err) {
  const f3r_model* m = s->model;
  s->stepper.output_interval = t_out - s->t;
  int retries = 0;
  while (t_out > s->t) {
    if (t_out - s->t <= 1e-13 * fmax(1.0, fabs(t_out))) { /* closer than IDA can step */
      s->t = t_out;
      break;
    }
    double t_stop = t_out;
    const int at_break = f3r_event_next_breakpoint(m, s->t, t_out, &t_stop);
    /* Where the solver must stop: here, or, where the output may be interpolated, at the next
     * breakpoint beyond it. A step past that breakpoint would integrate across a jump in the
     * forces and leave the solver ahead of the stop the next call needs. */
    double limit = t_stop;
    if (!at_break && !s->settings.stop_at_outputs &&
        !f3r_event_next_breakpoint(m, s->t, INFINITY, &limit))
      limit = 1e300;
    double t_reached = s->t;
    int event = 0;
    const long asked_before = s->stepper.recoverable;
    if (s->stepper.arkode) N_VScale(1.0, s->y, s->y_attempt); /* only ARKODE's attempts retry */
    f3r_status st =
        s->ops->advance(&s->stepper, t_stop, limit, s->y, s->yp, &t_reached, &event, err);
    if (st != F3R_OK && f3r_arkode_retry_refused(&s->stepper, asked_before, &retries, s->y_attempt,
                                                 s->y, s->t, err))
      continue;
    if (st != F3R_OK) {
      s->t = t_reached;
      return st;
    }
    if ((st = check_strokes(s, t_reached, err)) != F3R_OK) {
      s->t = t_reached;
      return st;
    }
    if (event) {
      s->t = t_reached;
      const int collapsed = f3r_event_collapsed_leg(s->stepper.root_info);
      if (collapsed >= 0)
        return f3r_event_collapse_error(m, s->settings.formulation, N_VGetArrayPointer(s->y),
                                        collapsed, s->t, err);
      if ((st = handle_stop_event(s, err)) != F3R_OK) return st;
      continue;
    }
    const double* y = N_VGetArrayPointer(s->y);
    for (int n = 0; n < s->ny; ++n)
      if (!isfinite(y[n]))
        return f3r_error_set(err, F3R_ERR_NONFINITE, "non-finite state at t = %.9g", t_reached);
    s->t = t_stop;
    if (at_break) {
      double q[F3R_MAX_Q], v[F3R_MAX_Q];
      st = f3r_state_to_full(m, s->settings.formulation, y, q, v);
      double lag[3];
      if (st == F3R_OK) st = consistent(s, q, v, lag_states(s, lag), y[s->ny - 1], NULL, err);
      if (st == F3R_OK) st = s->ops->restart(&s->stepper, s->y, s->yp, s->t, err);
      if (st != F3R_OK) return st;
    }
  }
  return F3R_OK;
}

/* What f3r_sim_restore puts back: the fields of f3r_sim that a step, a force or an impact
 * changes, and y, y' (ny each, in values). The integrator's own history is not kept: the restore
 * restarts it, as new forces do. */
struct f3r_sim_snapshot {
  const f3r_sim* sim;
  double t, t_restart, energy0, impact_loss;
  double held[F3R_MAX_Q];
  long impacts;
  f3r_impact_record last_impact;
  f3r_impact_window impact_window;
  int locked[3];
  int yp_stale;
  double* values; /* y then y' */
};

f3r_status f3r_sim_snapshot_create(const f3r_sim* s, f3r_sim_snapshot** out, f3r_error* err) {
  f3r_sim_snapshot* snap = calloc(1, sizeof *snap);
  if (snap) snap->values = calloc(2 * (size_t)s->ny, sizeof(double));
  if (!snap || !snap->values) {
    f3r_sim_snapshot_destroy(snap);
    return f3r_error_set(err, F3R_ERR_MEMORY, "no memory for a snapshot of the run");
  }
  snap->sim = s;
  f3r_sim_save(s, snap);
  *out = snap;
  return F3R_OK;
}

void f3r_sim_snapshot_destroy(f3r_sim_snapshot* snap) {
  if (!snap) return;
  free(snap->values);
  free(snap);
}

void f3r_sim_save(const f3r_sim* s, f3r_sim_snapshot* snap) {
  snap->t = s->t, snap->t_restart = s->t_restart, snap->energy0 = s->energy0;
  snap->impact_loss = s->impact_loss, snap->impacts = s->impacts;
  snap->last_impact = s->last_impact, snap->impact_window = s->impact_window;
  memcpy(snap->held, s->held, sizeof snap->held);
  memcpy(snap->locked, s->locked, sizeof snap->locked);
  snap->yp_stale = s->stepper.yp_stale;
  memcpy(snap->values, N_VGetArrayPointer(s->y), (size_t)s->ny * sizeof(double));
  memcpy(snap->values + s->ny, N_VGetArrayPointer(s->yp), (size_t)s->ny * sizeof(double));
}

f3r_status f3r_sim_restore(f3r_sim* s, const f3r_sim_snapshot* snap, f3r_error* err) {
  if (snap->sim != s)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_sim_restore: a snapshot of another run");
  s->t = snap->t, s->t_restart = snap->t_restart, s->energy0 = snap->energy0;
  s->impact_loss = snap->impact_loss, s->impacts = snap->impacts;
  s->last_impact = snap->last_impact, s->impact_window = snap->impact_window;
  memcpy(s->held, snap->held, sizeof s->held);
  set_locks(s, snap->locked);
  memcpy(N_VGetArrayPointer(s->y), snap->values, (size_t)s->ny * sizeof(double));
  memcpy(N_VGetArrayPointer(s->yp), snap->values + s->ny, (size_t)s->ny * sizeof(double));
  const f3r_status st = s->ops->restart(&s->stepper, s->y, s->yp, s->t, err);
  s->stepper.yp_stale = snap->yp_stale;
  return st;
}

double f3r_sim_time(const f3r_sim* s) { return s->t; }
const f3r_stepper* f3r_sim_stepper(const f3r_sim* s) { return &s->stepper; }
const f3r_model* f3r_sim_model(const f3r_sim* s) { return s->model; }
f3r_formulation f3r_sim_formulation(const f3r_sim* s) { return s->settings.formulation; }
const double* f3r_sim_state(const f3r_sim* s) { return N_VGetArrayPointer(s->y); }

/* One forward pass at the current state (position, velocity, forces) gives every output; the
 * multipliers are the state's own (dae) or follow from its accelerations y' (minimal). */
const f3r_outputs* f3r_sim_outputs(f3r_sim* s) {
  const f3r_model* m = s->model;
  const int nq = m->nq;
  f3r_outputs* o = &s->out;
  const double* y = N_VGetArrayPointer(s->y);
  f3r_data* d = &s->out_ws->data;
  o->t = s->t;
  if (f3r_state_to_full(m, s->settings.formulation, y, o->q, o->v) != F3R_OK) return o;
  /* At a restart (a breakpoint's jump in the inputs, new forces) the state, its locks and its
   * accelerations follow the forces after it: so do the outputs. */
  const double t_forces = s->t <= s->t_restart ? nextafter(s->t, INFINITY) : s->t;
  if (s->stepper.yp_stale) { /* an explicit stepper's y' at the state: one right-hand side */
    if (f3r_explicit_rhs(m, t_forces, y, s->held, N_VGetArrayPointer(s->yp), s->out_ws) != F3R_OK)
      return o;
    s->stepper.yp_stale = 0;
  }
  double lag[3];
  d->t = t_forces, d->q = o->q, d->v = o->v, d->held = s->held, d->lag = lag_states(s, lag);
  f3r_forward(m, d, F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES | F3R_FWD_ENERGY);
  memcpy(o->forces, d->Q, (size_t)nq * sizeof(double));
  /* The actuators' share of Q on the leg joints: what the force stage applied for them (the lag
   * states, or the held force plus the scripted input it commanded), the rest is passive. */
  for (int i = 0; i < 3; ++i) {
    const int leg = F3R_FORCE_RHO + i, cylinder = F3R_FORCE_THETA + i;
    o->actuator[leg] =
        m->n_lag ? lag[i] : s->held[leg] + f3r_input_value(&m->scene.inputs[leg], t_forces);
    o->actuator[cylinder] =
        s->held[cylinder] + f3r_input_value(&m->scene.inputs[cylinder], t_forces);
  }
  for (int j = 0; j < F3R_Q_LEG_JOINTS; ++j) o->passive[j] = d->Q[j] - o->actuator[j];
  /* the stops' reactions: reported apart, in neither forces nor passive, but in the balance of
   * forces that the multipliers follow from */
  const int minimal = s->settings.formulation == F3R_FORMULATION_MINIMAL;
  d->locks = &s->out_ws->locks, d->stop_work = s->out_ws->stop_work;
  d->udot = N_VGetArrayPointer(s->yp) + m->n_independent; /* the minimal form's multipliers */
  d->reduced = NULL;
  if (f3r_forward(m, d, F3R_FWD_STOPS | (minimal ? F3R_FWD_ACCELERATION_CLOSED : 0)) != F3R_OK)
    return o;
  for (int i = 0; i < 3; ++i) {
    o->stop_locked[i] = s->locked[i];
    o->stop_force[i] = d->stop_force[i];
  }
  memcpy(o->lambda, minimal ? d->lambda : y + 2 * nq, sizeof o->lambda);
  o->kinetic_energy = d->kinetic;
  o->potential_energy = d->potential;
  for (int i = 0; i < 3; ++i) {
    o->tip_deflection[i] = d->link[i].w;
    o->tip_deflection_rate[i] = d->link[i].w_dot;
  }
  o->external_work = y[s->ny - 1];
  o->energy_balance_error = fabs(o->kinetic_energy + o->potential_energy - o->external_work +
                                 s->impact_loss - s->energy0);
  o->impacts = s->impacts;
  o->impact_loss = s->impact_loss;
  o->last_impact = s->last_impact;
  double gv[F3R_NCON];
  f3r_data_constraint_times(m, d, o->v, gv);
  o->actuation_condition = f3r_data_actuation_condition(m, d, o->q);
  o->constraint_residual = o->velocity_residual = 0.0;
  for (int c = 0; c < F3R_NCON; ++c) {
    o->constraint_residual = fmax(o->constraint_residual, fabs(d->g[c]));
    o->velocity_residual = fmax(o->velocity_residual, fabs(gv[c]));
  }
  s->ops->stats(&s->stepper, &o->stats);
  return o;
}

int f3r_energy_guard_tripped(double energy_balance_error, double largest_energy) {
  return largest_energy > 0.0 && energy_balance_error > F3R_ENERGY_GUARD * largest_energy &&
         energy_balance_error > F3R_ENERGY_GUARD_FLOOR;
}
