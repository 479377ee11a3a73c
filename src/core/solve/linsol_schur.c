/* The Schur-complement linear solver for IDA (linsol_schur.h). */
#include "linsol_schur.h"

#include <stdlib.h>
#include <string.h>

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "dense.h"

/* The nonzero rows of each column of J_kr, recorded at setup: J_kr is -I on the rates (minimal)
 * or G^T on mu (dae), so each solve's x_k = (b_k - J_kr x_r) / cj runs over those only (at
 * r = 3, 12 of 156 entries; the same sums, the zeros' products skipped). J_rk and S's factors
 * are denser: their dense loops (vectorised) measured faster at r = 20 than a gather. */
typedef struct {
  int* start; /* columns + 1: column j's rows are rows[start[j] .. start[j + 1]) */
  int* rows;
} column_pattern;

typedef struct {
  int nz, nr;              /* kinematic rows; the rest (nr = ny - nz) */
  const double* cj_source; /* where the stepper keeps the current cj */
  double cj;               /* of the last setup */
  column_pattern kr;       /* J_kr (nz x nr): its nonzero rows k per column r_j */
  double* S;               /* nr x nr, the factored Schur complement */
  int* piv;                /* nr */
  double* bz;              /* nz: b_z kept, since IDA may pass x == b */
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

/* S = J_rr - J_rk J_kr / cj, factored, and the patterns the solve uses. */
static int schur_setup(SUNLinearSolver LS, SUNMatrix A) {
  schur_content* c = CONTENT(LS);
  const int nz = c->nz, nr = c->nr;
  const int ld = (int)SM_LDATA_D(A) / (int)SM_COLUMNS_D(A);
  const double* J = SM_DATA_D(A);
  c->cj = *c->cj_source;
  if (!(c->cj != 0.0)) return c->last_flag = SUNLS_PACKAGE_FAIL_UNREC;
  const double inv_cj = 1.0 / c->cj;
  int n = 0;
  for (int j = 0; j < nr; ++j) {
    const double* col = J + (size_t)(nz + j) * (size_t)ld; /* column r_j: J_kr above J_rr */
    double* s = c->S + (size_t)j * (size_t)nr;
    memcpy(s, col + nz, (size_t)nr * sizeof(double));
    c->kr.start[j] = n;
    for (int k = 0; k < nz; ++k) {
      if (col[k] == 0.0) continue;
      c->kr.rows[n++] = k;
      const double a = col[k] * inv_cj;
      if (a == 0.0) continue;                              /* underflow */
      const double* jrk = J + (size_t)k * (size_t)ld + nz; /* column k of J_rk */
      for (int i = 0; i < nr; ++i) s[i] -= jrk[i] * a;
    }
  }
  c->kr.start[nr] = n;
  /* a zero pivot is recoverable: IDA retries with a smaller step */
  return c->last_flag = f3r_lu_factor(c->S, nr, c->piv) ? SUNLS_LUFACT_FAIL : SUNLS_SUCCESS;
}

/* x_r = S^{-1} (b_r - J_rk b_k / cj), then x_k = (b_k - J_kr x_r) / cj. */
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
  double* keep = c->bz; /* b and x may be the same vector: keep b_k */
  memcpy(keep, bb, (size_t)nz * sizeof(double));
  if (xr != bb + nz) memcpy(xr, bb + nz, (size_t)nr * sizeof(double));
  for (int k = 0; k < nz; ++k) {
    const double f = keep[k] * inv_cj;
    if (f == 0.0) continue;
    const double* jrk = J + (size_t)k * (size_t)ld + nz;
    for (int i = 0; i < nr; ++i) xr[i] -= jrk[i] * f;
  }
  f3r_lu_solve(c->S, nr, c->piv, xr);
  for (int k = 0; k < nz; ++k) xx[k] = keep[k];
  for (int j = 0; j < nr; ++j) {
    if (xr[j] == 0.0) continue;
    const double* col = J + (size_t)(nz + j) * (size_t)ld;
    for (int n = c->kr.start[j]; n < c->kr.start[j + 1]; ++n) {
      const int k = c->kr.rows[n];
      xx[k] -= col[k] * xr[j];
    }
  }
  for (int k = 0; k < nz; ++k) xx[k] *= inv_cj;
  return c->last_flag = SUNLS_SUCCESS;
}

static sunindextype schur_last_flag(SUNLinearSolver LS) { return CONTENT(LS)->last_flag; }

static int schur_space(SUNLinearSolver LS, long* lenrw, long* leniw) {
  const schur_content* c = CONTENT(LS);
  *lenrw = (long)c->nr * c->nr + 1;
  *leniw = c->nr + 3 + (c->nr + 1) + c->nz * c->nr;
  return SUNLS_SUCCESS;
}

static int schur_free(SUNLinearSolver LS) {
  if (!LS) return SUNLS_SUCCESS;
  if (LS->content) {
    free(CONTENT(LS)->S);
    free(CONTENT(LS)->piv);
    free(CONTENT(LS)->bz);
    free(CONTENT(LS)->kr.start), free(CONTENT(LS)->kr.rows);
    free(LS->content);
    LS->content = NULL;
  }
  SUNLinSolFreeEmpty(LS);
  return SUNLS_SUCCESS;
}

SUNLinearSolver f3r_schur_linsol_create(SUNContext ctx, int nz, int ny, const double* cj) {
  if (nz <= 0 || ny <= nz || !cj) return NULL;
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
  c->cj_source = cj;
  c->S = calloc((size_t)c->nr * (size_t)c->nr, sizeof(double));
  c->piv = calloc((size_t)c->nr, sizeof(int));
  c->bz = calloc((size_t)nz, sizeof(double));
  c->kr.start = calloc((size_t)c->nr + 1, sizeof(int));
  c->kr.rows = calloc((size_t)nz * (size_t)c->nr, sizeof(int));
  if (!c->S || !c->piv || !c->bz || !c->kr.start || !c->kr.rows) {
    schur_free(LS);
    return NULL;
  }
  return LS;
}
