/* The Schur-complement linear solver for IDA (linsol_schur.h). */
#include "linsol_schur.h"

#include <stdlib.h>
#include <string.h>

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "dense.h"

/* The nonzero rows of each column of a block, recorded at setup: the solves then skip the exact
 * zeros (J_kr is -I on the rates, J_rk zero between two links' modes, U's last column empty on
 * the minimal formulation at r = 3: 40 % of the products) and still sum every entry in the order
 * of the dense loops. */
typedef struct {
  int* start; /* columns + 1: column j's rows are rows[start[j] .. start[j + 1]) */
  int* rows;
} column_pattern;

typedef struct {
  int nz, nr;              /* kinematic rows; the rest (nr = ny - nz) */
  const double* cj_source; /* where the stepper keeps the current cj */
  double cj;               /* of the last setup */
  column_pattern kr;       /* J_kr (nz x nr): its nonzero rows k per column r_j */
  column_pattern rk;       /* J_rk (nr x nz): its nonzero rows per column k */
  column_pattern upper;    /* S's factor U: its nonzero rows above the diagonal per column */
  double* S;               /* nr x nr, the factored Schur complement */
  int* piv;                /* nr */
  double* bz;              /* nz: b_z kept, since IDA may pass x == b */
  int last_flag;
} schur_content;

/* The pattern of the columns of a (rows x cols, leading dimension ld) above row `below` of each
 * column when `triangular` (U: rows 0 .. j - 1 of column j), else all rows. */
static void record_pattern(const double* a, int rows, int cols, int ld, int triangular,
                           column_pattern* p) {
  int n = 0;
  for (int j = 0; j < cols; ++j) {
    p->start[j] = n;
    const int end = triangular ? j : rows;
    for (int i = 0; i < end; ++i)
      if (a[(size_t)j * (size_t)ld + i] != 0.0) p->rows[n++] = i;
  }
  p->start[cols] = n;
}

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
  record_pattern(J + (size_t)nz * (size_t)ld, nz, nr, ld, 0, &c->kr);
  record_pattern(J + nz, nr, nz, ld, 0, &c->rk);
  for (int j = 0; j < nr; ++j) {
    const double* col = J + (size_t)(nz + j) * (size_t)ld; /* column r_j: J_kr above J_rr */
    double* s = c->S + (size_t)j * (size_t)nr;
    memcpy(s, col + nz, (size_t)nr * sizeof(double));
    for (int n = c->kr.start[j]; n < c->kr.start[j + 1]; ++n) {
      const int k = c->kr.rows[n];
      const double a = col[k] * inv_cj;
      if (a == 0.0) continue;                              /* underflow */
      const double* jrk = J + (size_t)k * (size_t)ld + nz; /* column k of J_rk */
      for (int i = 0; i < nr; ++i) s[i] -= jrk[i] * a;
    }
  }
  /* a zero pivot is recoverable: IDA retries with a smaller step */
  if (f3r_lu_factor(c->S, nr, c->piv)) return c->last_flag = SUNLS_LUFACT_FAIL;
  record_pattern(c->S, nr, nr, nr, 1, &c->upper);
  return c->last_flag = SUNLS_SUCCESS;
}

/* b = U^{-1} L^{-1} P b with S's factors (f3r_lu_solve's order, U's zeros skipped). */
static void factored_solve(const schur_content* c, double* b) {
  const int n = c->nr;
  const double* S = c->S;
  f3r_lu_solve_lower(S, n, c->piv, b);
  for (int k = n - 1; k >= 0; --k) {
    b[k] /= F3R_AT(S, n, k, k);
    for (int m = c->upper.start[k]; m < c->upper.start[k + 1]; ++m) {
      const int i = c->upper.rows[m];
      b[i] -= F3R_AT(S, n, i, k) * b[k];
    }
  }
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
    for (int n = c->rk.start[k]; n < c->rk.start[k + 1]; ++n) {
      const int i = c->rk.rows[n];
      xr[i] -= jrk[i] * f;
    }
  }
  factored_solve(c, xr);
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
  *leniw = c->nr + 3 + 2 * (c->nr + 1) + (c->nz + 1) + 2 * c->nz * c->nr + c->nr * c->nr;
  return SUNLS_SUCCESS;
}

static int schur_free(SUNLinearSolver LS) {
  if (!LS) return SUNLS_SUCCESS;
  if (LS->content) {
    free(CONTENT(LS)->S);
    free(CONTENT(LS)->piv);
    free(CONTENT(LS)->bz);
    free(CONTENT(LS)->kr.start), free(CONTENT(LS)->kr.rows);
    free(CONTENT(LS)->rk.start), free(CONTENT(LS)->rk.rows);
    free(CONTENT(LS)->upper.start), free(CONTENT(LS)->upper.rows);
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
  const size_t nz_nr = (size_t)nz * (size_t)c->nr;
  c->kr.start = calloc((size_t)c->nr + 1, sizeof(int));
  c->kr.rows = calloc(nz_nr, sizeof(int));
  c->rk.start = calloc((size_t)nz + 1, sizeof(int));
  c->rk.rows = calloc(nz_nr, sizeof(int));
  c->upper.start = calloc((size_t)c->nr + 1, sizeof(int));
  c->upper.rows = calloc((size_t)c->nr * (size_t)c->nr, sizeof(int));
  if (!c->S || !c->piv || !c->bz || !c->kr.start || !c->kr.rows || !c->rk.start || !c->rk.rows ||
      !c->upper.start || !c->upper.rows) {
    schur_free(LS);
    return NULL;
  }
  return LS;
}
