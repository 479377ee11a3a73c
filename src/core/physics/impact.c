/* Impacts at the cylinders' end stops (the end_stops effect). See f3r_impact in stages.h. */
#include "dense.h"
#include "model_layout.h"
#include "stages.h"

size_t f3r_impact_work_size(const f3r_model* m) {
  const size_t n = (size_t)m->nq + F3R_NCON + 3;
  return n * n + 2 * n;
}

f3r_status f3r_impact(const f3r_model* m, const double* q, const double* v, const int* legs,
                      int count, double restitution, double* v_out, double* impulse, double* work) {
  const int nq = m->nq, n = nq + F3R_NCON + count;
  double* K = work;
  double* b = K + (size_t)n * n;
  int* piv = (int*)(b + n);
  for (size_t z = 0; z < (size_t)n * n; ++z) K[z] = 0.0;
  f3r_add_mass_matrix(m, q, 1.0, K, n);
  f3r_add_constraint_jacobian_transpose(m, q, -1.0, K + (size_t)nq * n, n);
  f3r_add_constraint_jacobian(m, q, 1.0, K + nq, n);
  for (int c = 0; c < count; ++c) {
    F3R_AT(K, n, legs[c], nq + F3R_NCON + c) = -1.0; /* -E in the momentum rows */
    F3R_AT(K, n, nq + F3R_NCON + c, legs[c]) = 1.0;  /* E^T dv */
  }
  for (int r = 0; r < n; ++r) b[r] = 0.0;
  for (int c = 0; c < count; ++c) b[nq + F3R_NCON + c] = -(1.0 + restitution) * v[legs[c]];
  if (f3r_lu_factor(K, n, piv)) return F3R_ERR_SINGULAR;
  f3r_lu_solve(K, n, piv, b);
  for (int r = 0; r < nq; ++r) v_out[r] = v[r] + b[r];
  for (int c = 0; c < count; ++c) impulse[c] = b[nq + F3R_NCON + c];
  return F3R_OK;
}
