/* Modal analysis of the constrained, linearised system: K and M in the minimal coordinates,
 * reduced to a symmetric standard problem by Cholesky, solved by cyclic Jacobi rotations. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dense.h"
#include "flex3rpr/modal.h"
#include "flex3rpr/residual.h"

static void jacobi_eigenvalues(double* A, int n, double* eig) {
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0.0, diag = 0.0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (i == j) diag += F3R_AT(A, n, i, i) * F3R_AT(A, n, i, i);
        else off += F3R_AT(A, n, i, j) * F3R_AT(A, n, i, j);
      }
    if (off <= 1e-30 * diag) break;
    for (int p = 0; p < n; ++p)
      for (int r = p + 1; r < n; ++r) {
        const double apr = F3R_AT(A, n, p, r);
        if (apr == 0.0) continue;
        const double theta = (F3R_AT(A, n, r, r) - F3R_AT(A, n, p, p)) / (2.0 * apr);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
        const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) { /* columns p, r */
          const double akp = F3R_AT(A, n, k, p), akr = F3R_AT(A, n, k, r);
          F3R_AT(A, n, k, p) = c * akp - s * akr;
          F3R_AT(A, n, k, r) = s * akp + c * akr;
        }
        for (int k = 0; k < n; ++k) { /* rows p, r */
          const double apk = F3R_AT(A, n, p, k), ark = F3R_AT(A, n, r, k);
          F3R_AT(A, n, p, k) = c * apk - s * ark;
          F3R_AT(A, n, r, k) = s * apk + c * ark;
        }
      }
  }
  for (int i = 0; i < n; ++i) eig[i] = F3R_AT(A, n, i, i);
}

static int compare_doubles(const void* a, const void* b) {
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

f3r_status f3r_modal_frequencies(const f3r_model* model, double* hz, int* count, f3r_error* err) {
  f3r_model m = *model; /* linearise without the scene's scripted inputs */
  memset(m.scene.inputs, 0, sizeof m.scene.inputs);
  m.n_lag = 0; /* linearise without actuator dynamics */
  const int nz = m.n_independent, ny = f3r_state_size(&m, F3R_FORMULATION_MINIMAL);
  f3r_workspace* ws = f3r_workspace_create(&m);
  double* y = calloc((size_t)ny, sizeof(double));
  double* yp = calloc((size_t)ny, sizeof(double));
  double* J = calloc((size_t)ny * ny, sizeof(double));
  double* K = calloc((size_t)nz * nz, sizeof(double));
  double* M = calloc((size_t)nz * nz, sizeof(double));
  double* eig = calloc((size_t)nz, sizeof(double));
  f3r_status st = F3R_OK;
  if (!ws || !y || !yp || !J || !K || !M || !eig) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "modal analysis: out of memory");
    goto done;
  }
  for (int k = 0; k < 3; ++k) y[k] = m.scene.platform_pose0[k];
  /* dF/dz (stiffness) and dF/du' (mass) of the minimal residual at rest: cj = 0 gives dF/dy;
   * the mass block is (J(cj = 1) - J(cj = 0)) on the u columns. */
  st = f3r_residual_jacobian(&m, F3R_FORMULATION_MINIMAL, 0.0, 0.0, y, yp, NULL, J, ny, ws);
  if (st != F3R_OK) goto fail_singular;
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nz; ++i) F3R_AT(K, nz, i, j) = F3R_AT(J, ny, nz + i, j);
  st = f3r_residual_jacobian(&m, F3R_FORMULATION_MINIMAL, 0.0, 1.0, y, yp, NULL, J, ny, ws);
  if (st != F3R_OK) goto fail_singular;
  double* J0 = calloc((size_t)ny * ny, sizeof(double));
  if (!J0) { st = f3r_error_set(err, F3R_ERR_MEMORY, "modal analysis: out of memory"); goto done; }
  f3r_residual_jacobian(&m, F3R_FORMULATION_MINIMAL, 0.0, 0.0, y, yp, NULL, J0, ny, ws);
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nz; ++i)
      F3R_AT(M, nz, i, j) = F3R_AT(J, ny, nz + i, nz + j) - F3R_AT(J0, ny, nz + i, nz + j);
  free(J0);
  for (int j = 0; j < nz; ++j) /* symmetrise the difference quotients */
    for (int i = 0; i < j; ++i) {
      const double k = 0.5 * (F3R_AT(K, nz, i, j) + F3R_AT(K, nz, j, i));
      F3R_AT(K, nz, i, j) = F3R_AT(K, nz, j, i) = k;
      const double mm = 0.5 * (F3R_AT(M, nz, i, j) + F3R_AT(M, nz, j, i));
      F3R_AT(M, nz, i, j) = F3R_AT(M, nz, j, i) = mm;
    }
  if (f3r_cholesky_factor(M, nz)) {
    st = f3r_error_set(err, F3R_ERR_SINGULAR, "modal analysis: the reduced mass matrix is not positive definite");
    goto done;
  }
  /* C = L^-1 K L^-T: solve L X = K, then L C^T = X^T. */
  for (int pass = 0; pass < 2; ++pass) {
    for (int j = 0; j < nz; ++j)
      for (int i = 0; i < nz; ++i) {
        double s = F3R_AT(K, nz, i, j);
        for (int k = 0; k < i; ++k) s -= F3R_AT(M, nz, i, k) * F3R_AT(K, nz, k, j);
        F3R_AT(K, nz, i, j) = s / F3R_AT(M, nz, i, i);
      }
    for (int j = 0; j < nz; ++j) /* transpose */
      for (int i = 0; i < j; ++i) {
        const double t = F3R_AT(K, nz, i, j);
        F3R_AT(K, nz, i, j) = F3R_AT(K, nz, j, i);
        F3R_AT(K, nz, j, i) = t;
      }
  }
  jacobi_eigenvalues(K, nz, eig);
  qsort(eig, (size_t)nz, sizeof(double), compare_doubles);
  for (int k = 0; k < nz; ++k) hz[k] = sqrt(fmax(eig[k], 0.0)) / (2.0 * M_PI);
  *count = nz;
  goto done;
fail_singular:
  st = f3r_error_set(err, st, "modal analysis: the initial pose cannot be linearised");
done:
  f3r_workspace_destroy(ws);
  free(y), free(yp), free(J), free(K), free(M), free(eig);
  return st;
}
