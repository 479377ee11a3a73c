/* End stops held as contact: the locked legs' forces as Lagrange multipliers. See f3r_stop_forces
 * in stages.h. */
#include <string.h>

#include "dense.h"
#include "model_layout.h"
#include "workspace.h"

int f3r_stop_locks_any(const f3r_stop_locks* locks) {
  return locks->side[0] || locks->side[1] || locks->side[2];
}

size_t f3r_stop_forces_work_size(const f3r_model* m) {
  const size_t n = (size_t)m->nq + F3R_NCON + 3;
  return n * n + 2 * n + (size_t)F3R_MAX_Q;
}

f3r_status f3r_stop_forces(const f3r_model* m, const f3r_stop_locks* locks, const double* q,
                           const double* v, const double* Q, double* f, double* work) {
  int legs[3], count = 0;
  for (int i = 0; i < 3; ++i) {
    f[i] = 0.0;
    if (locks->side[i]) legs[count++] = i;
  }
  if (!count) return F3R_OK;
  const int nq = m->nq, n = nq + F3R_NCON + count;
  const double rate = F3R_STOP_BAUMGARTE_RATE;
  double* K = work;
  double* b = K + (size_t)n * n;
  int* piv = (int*)(b + n);                               /* n ints fit in n doubles */
  f3r_constrained_system(m, q, v, Q, n, K, b, b + 2 * n); /* its E rows and columns below */
  for (int c = 0; c < count; ++c) {
    const int leg = legs[c], row = nq + F3R_NCON + c;
    const double stop = locks->side[leg] < 0 ? m->stroke_min : m->stroke_max;
    F3R_AT(K, n, leg, row) = -1.0; /* -E in the dynamic rows */
    F3R_AT(K, n, row, leg) = 1.0;  /* E^T a */
    b[row] = -(2.0 * rate * v[leg] + rate * rate * (q[leg] - stop));
  }
  if (f3r_lu_factor(K, n, piv)) return F3R_ERR_SINGULAR;
  f3r_lu_solve(K, n, piv, b);
  for (int c = 0; c < count; ++c) f[legs[c]] = b[nq + F3R_NCON + c];
  return F3R_OK;
}

f3r_status f3r_workspace_add_stop_forces(const f3r_model* m, f3r_workspace* ws, int closed) {
  f3r_data* d = &ws->data;
  double* f = ws->stop_force;
  if (!f3r_stop_locks_any(&ws->locks)) {
    f[0] = f[1] = f[2] = 0.0;
    return F3R_OK;
  }
  double q[F3R_MAX_Q];
  const double* full = d->q;
  if (closed) { /* the closed position stage leaves theta out: its directions give it */
    memcpy(q, d->q, (size_t)m->nq * sizeof(double));
    f3r_fwd_leg_angles(m, d, q);
    full = q;
  }
  const f3r_status st = f3r_stop_forces(m, &ws->locks, full, d->v, d->Q, f, ws->stop_work);
  if (st != F3R_OK) return st;
  for (int i = 0; i < 3; ++i) {
    d->Q[i] += f[i];
    d->power += f[i] * d->v[i];
  }
  return F3R_OK;
}
