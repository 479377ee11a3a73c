/* The minimal formulation's Schur-complement linear solver for IDA (linsol_schur.h). */
#include "linsol_schur.h"

#include <stdlib.h>
#include <string.h>

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "dense.h"

typedef struct {
  int nz, nr;      /* kinematic rows; the rest (nr = ny - nz) */
  double cj;       /* of the last setup */
  double* S;       /* nr x nr, the factored Schur complement */
  int* piv;        /* nr */
  double* bz;      /* nz: b_z kept, since IDA may pass x == b */
  int last_flag;
} schur_content;

#define CONTENT(LS) ((schur_content*)(LS)->content)

static SUNLinearSolver_Type schur_type(SUNLinearSolver LS) {
  (void)LS;
  return SUNLINEARSOLVER_DIRECT;
}

static SUNLinearSolver_ID schur_id(SUNLinearSolver LS) {
  (void)LS;
  return SUNLINEARSOLVER_CUSTOM;
}

static int schur_initialize(SUNLinearSolver LS) {
  CONTENT(LS)->last_flag = SUNLS_SUCCESS;
  return SUNLS_SUCCESS;
}

/* S = J_rr + J_rz E / cj, factored. */
static int schur_setup(SUNLinearSolver LS, SUNMatrix A) {
  schur_content* c = CONTENT(LS);
  const int nz = c->nz, nr = c->nr;
  const int ld = (int)SM_LDATA_D(A) / (int)SM_COLUMNS_D(A);
  const double* J = SM_DATA_D(A);
  c->cj = F3R_AT(J, ld, 0, 0);
  if (!(c->cj != 0.0)) return c->last_flag = SUNLS_PACKAGE_FAIL_UNREC;
  const double inv_cj = 1.0 / c->cj;
  for (int j = 0; j < nr; ++j) {
    const double* col = J + (size_t)(nz + j) * (size_t)ld + nz;
    double* s = c->S + (size_t)j * (size_t)nr;
    memcpy(s, col, (size_t)nr * sizeof(double));
    if (j < nz) { /* column u_j: x_z = (b_z + x_u) / cj feeds J_rz's column z_j */
      const double* jz = J + (size_t)j * (size_t)ld + nz;
      for (int i = 0; i < nr; ++i) s[i] += jz[i] * inv_cj;
    }
  }
  /* a zero pivot is recoverable: IDA retries with a smaller step */
  return c->last_flag = f3r_lu_factor(c->S, nr, c->piv) ? SUNLS_LUFACT_FAIL : SUNLS_SUCCESS;
}

/* x_r = S^{-1} (b_r - J_rz b_z / cj), then x_z = (b_z + x_u) / cj. */
static int schur_solve(SUNLinearSolver LS, SUNMatrix A, N_Vector x, N_Vector b, realtype tol) {
  (void)tol;
  schur_content* c = CONTENT(LS);
  const int nz = c->nz, nr = c->nr;
  const int ld = (int)SM_LDATA_D(A) / (int)SM_COLUMNS_D(A);
  const double* J = SM_DATA_D(A);
  const double* bb = N_VGetArrayPointer(b);
  double* xx = N_VGetArrayPointer(x);
  const double inv_cj = 1.0 / c->cj;
  double* xr = xx + nz;
  double* keep = c->bz;
  memcpy(keep, bb, (size_t)nz * sizeof(double));
  if (xr != bb + nz) memcpy(xr, bb + nz, (size_t)nr * sizeof(double));
  for (int j = 0; j < nz; ++j) {
    const double f = keep[j] * inv_cj;
    if (f == 0.0) continue;
    const double* jz = J + (size_t)j * (size_t)ld + nz;
    for (int i = 0; i < nr; ++i) xr[i] -= jz[i] * f;
  }
  f3r_lu_solve(c->S, nr, c->piv, xr);
  for (int j = 0; j < nz; ++j) xx[j] = (keep[j] + xr[j]) * inv_cj;
  return c->last_flag = SUNLS_SUCCESS;
}

static sunindextype schur_last_flag(SUNLinearSolver LS) { return CONTENT(LS)->last_flag; }

static int schur_space(SUNLinearSolver LS, long* lenrw, long* leniw) {
  const schur_content* c = CONTENT(LS);
  *lenrw = (long)c->nr * c->nr + 1;
  *leniw = c->nr + 3;
  return SUNLS_SUCCESS;
}

static int schur_free(SUNLinearSolver LS) {
  if (!LS) return SUNLS_SUCCESS;
  if (LS->content) {
    free(CONTENT(LS)->S);
    free(CONTENT(LS)->piv);
    free(CONTENT(LS)->bz);
    free(LS->content);
    LS->content = NULL;
  }
  SUNLinSolFreeEmpty(LS);
  return SUNLS_SUCCESS;
}

SUNLinearSolver f3r_schur_linsol_create(SUNContext ctx, int nz, int ny) {
  if (nz <= 0 || ny <= 2 * nz) return NULL;
  SUNLinearSolver LS = SUNLinSolNewEmpty(ctx);
  if (!LS) return NULL;
  LS->ops->gettype = schur_type;
  LS->ops->getid = schur_id;
  LS->ops->initialize = schur_initialize;
  LS->ops->setup = schur_setup;
  LS->ops->solve = schur_solve;
  LS->ops->lastflag = schur_last_flag;
  LS->ops->space = schur_space;
  LS->ops->free = schur_free;
  schur_content* c = calloc(1, sizeof *c);
  LS->content = c;
  if (!c) {
    schur_free(LS);
    return NULL;
  }
  c->nz = nz;
  c->nr = ny - nz;
  c->S = calloc((size_t)c->nr * (size_t)c->nr, sizeof(double));
  c->piv = calloc((size_t)c->nr, sizeof(int));
  c->bz = calloc((size_t)nz, sizeof(double));
  if (!c->S || !c->piv || !c->bz) {
    schur_free(LS);
    return NULL;
  }
  return LS;
}
