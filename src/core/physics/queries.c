/* The queries: each takes (q, v), runs the stages it needs (forward.c) into a local f3r_data and
 * reads them, or the equations assembled from them (equations.c). The stage files never call
 * back here; the solve layer, the tests and the benchmark call in. */
#include <string.h>

#include "dense.h"
#include "queries.h"

/* A cleared d with inputs q and v (either may be NULL when no stage asked for reads it), through
 * the stages in `what`; returns d. */
static const f3r_data* forward_at(const f3r_model* m, const double* q, const double* v,
                                  unsigned what, f3r_data* d) {
  *d = (f3r_data){.q = q, .v = v};
  f3r_forward(m, d, what);
  return d;
}

enum {
  AT_Q = F3R_FWD_POSITION,
  AT_QV = F3R_FWD_POSITION | F3R_FWD_VELOCITY,
  AT_QVF = F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES
};

/* --- inertia and forces ------------------------------------------------------------------------ */

void f3r_add_mass_matrix(const f3r_model* m, const double* q, double scale, double* A, int ld) {
  f3r_data d;
  f3r_data_add_mass_matrix(m, forward_at(m, q, NULL, AT_Q, &d), scale, A, ld);
}

void f3r_mass_times(const f3r_model* m, const double* q, const double* a, double* out) {
  f3r_data d;
  f3r_data_mass_times(m, forward_at(m, q, NULL, AT_Q, &d), a, out);
}

void f3r_velocity_forces(const f3r_model* m, const double* q, const double* v, double* h) {
  f3r_data d;
  memcpy(h, forward_at(m, q, v, AT_QV, &d)->h, (size_t)m->nq * sizeof(double));
}

void f3r_add_velocity_forces_dv(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  f3r_data d;
  f3r_data_add_velocity_forces_dv(m, forward_at(m, q, v, AT_QV, &d), q, scale, A, ld);
}

void f3r_generalized_forces(const f3r_model* m, double t, const double* held, const double* q,
                            const double* v, double* Q) {
  f3r_data d;
  forward_at(m, q, v, F3R_FWD_POSITION, &d);
  d.t = t;
  for (int n = 0; n < m->nq; ++n) Q[n] = held ? held[n] : 0.0;
  f3r_effects_add_forces(m, &d, Q);
}

void f3r_applied_forces(const f3r_model* m, double t, const double* held, const double* q,
                        const double* v, const double* lag, double* Q, double* commanded) {
  f3r_data d = {.t = t, .q = q, .v = v, .held = held, .lag = lag};
  f3r_forward(m, &d, F3R_FWD_POSITION | F3R_FWD_FORCES);
  memcpy(Q, d.Q, (size_t)m->nq * sizeof(double));
  if (commanded && m->n_lag) memcpy(commanded, d.commanded, sizeof d.commanded);
}

void f3r_add_generalized_forces_dq(const f3r_model* m, const double* q, const double* v,
                                   double scale, double* A, int ld) {
  f3r_data d;
  f3r_effects_add_derivatives(m, forward_at(m, q, v, F3R_FWD_POSITION, &d), scale, A, NULL, ld);
}

void f3r_add_generalized_forces_dv(const f3r_model* m, const double* q, const double* v,
                                   double scale, double* A, int ld) {
  f3r_data d = {.q = q, .v = v}; /* no effect's dQ/dv needs a stage */
  f3r_effects_add_derivatives(m, &d, scale, NULL, A, ld);
}

/* --- constraints -------------------------------------------------------------------------------- */

void f3r_constraints(const f3r_model* m, const double* q, double* g) {
  f3r_data d;
  memcpy(g, forward_at(m, q, NULL, AT_Q, &d)->g, sizeof d.g);
}

void f3r_constraint_bias(const f3r_model* m, const double* q, const double* v, double* gamma) {
  f3r_data d;
  memcpy(gamma, forward_at(m, q, v, AT_QV, &d)->gamma, sizeof d.gamma);
}

void f3r_add_constraint_jacobian(const f3r_model* m, const double* q, double scale, double* A,
                                 int ld) {
  f3r_data d;
  f3r_data_add_constraint_jacobian(m, forward_at(m, q, NULL, AT_Q, &d), scale, A, ld);
}

void f3r_add_constraint_jacobian_transpose(const f3r_model* m, const double* q, double scale,
                                           double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_jacobian_transpose(m, forward_at(m, q, NULL, AT_Q, &d), scale, A, ld);
}

void f3r_constraint_times(const f3r_model* m, const double* q, const double* v, double* out) {
  f3r_data d;
  f3r_data_constraint_times(m, forward_at(m, q, NULL, AT_Q, &d), v, out);
}

void f3r_constraint_transpose_times(const f3r_model* m, const double* q, const double* lambda,
                                    double* out) {
  f3r_data d;
  f3r_data_constraint_transpose_times(m, forward_at(m, q, NULL, AT_Q, &d), lambda, out);
}

void f3r_add_constraint_transpose_times_dq(const f3r_model* m, const double* q,
                                           const double* lambda, double scale, double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_transpose_times_dq(m, forward_at(m, q, NULL, AT_Q, &d), lambda, scale, A,
                                             ld);
}

void f3r_add_constraint_times_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                 double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_times_dq(m, forward_at(m, q, v, AT_QV, &d), v, scale, A, ld);
}

void f3r_add_constraint_bias_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_bias_dq(m, forward_at(m, q, v, AT_QV, &d), v, scale, A, ld);
}

void f3r_add_constraint_bias_dv(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_bias_dv(m, forward_at(m, q, v, AT_QV, &d), v, scale, A, ld);
}

/* --- energy ------------------------------------------------------------------------------------- */

double f3r_kinetic_energy(const f3r_model* m, const double* q, const double* v) {
  f3r_data d;
  return forward_at(m, q, v, F3R_FWD_POSITION | F3R_FWD_ENERGY, &d)->kinetic;
}

double f3r_potential_energy(const f3r_model* m, const double* q) {
  static const double at_rest[F3R_MAX_Q] = {0};
  f3r_data d;
  return forward_at(m, q, at_rest, F3R_FWD_POSITION | F3R_FWD_ENERGY, &d)->potential;
}

/* --- accelerations, end stops and impacts ------------------------------------------------------ */

f3r_status f3r_solve_accelerations(const f3r_model* m, const double* q, const double* v,
                                   const double* Q, double* a, double* lambda, double* work) {
  f3r_data d;
  return f3r_data_solve_accelerations(m, forward_at(m, q, v, AT_QVF, &d), Q, a, lambda, work);
}

f3r_status f3r_stop_forces(const f3r_model* m, const f3r_stop_locks* locks, const double* q,
                           const double* v, const double* Q, double* f, double* work) {
  f3r_data d;
  return f3r_data_stop_forces(m, forward_at(m, q, v, AT_QVF, &d), locks, Q, f, work);
}

f3r_status f3r_contact_accelerations(const f3r_model* m, const f3r_stop_locks* locks,
                                     const double* q, const double* v, const double* Q, double* f,
                                     double* a, double* work) {
  f3r_data d;
  return f3r_data_contact_solve(m, forward_at(m, q, v, AT_QVF, &d), locks, Q, f, a, work);
}

size_t f3r_impact_work_size(const f3r_model* m) {
  const size_t n = (size_t)m->nq + F3R_NCON + 3;
  return n * n + 2 * n;
}

f3r_status f3r_impact(const f3r_model* m, const double* q, const double* v, const int* legs,
                      int count, const double* rates, double* v_out, double* impulse,
                      double* work) {
  const int nq = m->nq, n = nq + F3R_NCON + count;
  double* K = work;
  double* b = K + (size_t)n * n;
  int* piv = (int*)(b + n);
  f3r_data d;
  forward_at(m, q, NULL, AT_Q, &d);
  for (size_t z = 0; z < (size_t)n * n; ++z) K[z] = 0.0;
  f3r_data_add_mass_matrix(m, &d, 1.0, K, n);
  f3r_data_add_constraint_jacobian_transpose(m, &d, -1.0, K + (size_t)nq * n, n);
  f3r_data_add_constraint_jacobian(m, &d, 1.0, K + nq, n);
  for (int c = 0; c < count; ++c) {
    F3R_AT(K, n, legs[c], nq + F3R_NCON + c) = -1.0; /* -E in the momentum rows */
    F3R_AT(K, n, nq + F3R_NCON + c, legs[c]) = 1.0;  /* E^T dv */
  }
  for (int r = 0; r < n; ++r) b[r] = 0.0;
  for (int c = 0; c < count; ++c) b[nq + F3R_NCON + c] = rates[c] - v[legs[c]];
  if (f3r_lu_factor(K, n, piv)) return F3R_ERR_SINGULAR;
  f3r_lu_solve(K, n, piv, b);
  for (int r = 0; r < nq; ++r) v_out[r] = v[r] + b[r];
  for (int c = 0; c < count; ++c) impulse[c] = b[nq + F3R_NCON + c];
  return F3R_OK;
}

/* --- the model's configuration ----------------------------------------------------------------- */

/* The closed-form loop closure and its rates are the minimal formulation's position and
 * velocity stages (position.c, velocity.c). */
f3r_status f3r_model_close_loops(const f3r_model* m, double* q) {
  f3r_data d = {.z = q + F3R_Q_INDEPENDENT};
  const f3r_status st = f3r_forward(m, &d, F3R_FWD_POSITION_CLOSED);
  if (st != F3R_OK) return st;
  for (int i = 0; i < 3; ++i) q[F3R_Q_RHO + i] = d.q_closed[F3R_Q_RHO + i];
  f3r_fwd_leg_angles(m, &d, q);
  return F3R_OK;
}

void f3r_model_close_loop_rates(const f3r_model* m, const double* q, double* qdot) {
  f3r_data d = {.q = q, .u = qdot + F3R_Q_INDEPENDENT};
  f3r_forward(m, &d, F3R_FWD_POSITION | F3R_FWD_VELOCITY_CLOSED);
  for (int n = 0; n < F3R_Q_LEG_JOINTS; ++n) qdot[n] = d.v_closed[n];
}

f3r_status f3r_model_initial_state(const f3r_model* m, double* q, double* v) {
  const f3r_scene* sc = &m->scene;
  memset(q, 0, F3R_MAX_Q * sizeof(double));
  memset(v, 0, F3R_MAX_Q * sizeof(double));
  for (int k = 0; k < 3; ++k) {
    q[F3R_Q_X + k] = sc->platform_pose0[k];
    v[F3R_Q_X + k] = sc->platform_velocity0[k];
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < m->link[i].modes; ++j) {
      q[m->link[i].eta_index + j] = sc->links[i].eta0[j];
      v[m->link[i].eta_index + j] = sc->links[i].eta_rate0[j];
    }
  const f3r_status st = f3r_model_close_loops(m, q);
  if (st != F3R_OK) return st;
  f3r_model_close_loop_rates(m, q, v);
  return F3R_OK;
}

double f3r_model_actuation_condition(const f3r_model* m, const double* q) {
  f3r_data d;
  return f3r_data_actuation_condition(m, forward_at(m, q, NULL, F3R_FWD_POSITION, &d), q);
}
