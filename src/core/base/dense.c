#include "dense.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int f3r_lu_factor(double* A, int n, int* piv) {
  for (int k = 0; k < n; ++k) {
    int p = k;
    double best = fabs(F3R_AT(A, n, k, k));
    for (int i = k + 1; i < n; ++i) {
      const double v = fabs(F3R_AT(A, n, i, k));
      if (v > best) {
        best = v;
        p = i;
      }
    }
    if (!(best > 0.0) || !isfinite(best)) return 1;
    piv[k] = p;
    if (p != k) {
      for (int j = 0; j < n; ++j) {
        const double t = F3R_AT(A, n, k, j);
        F3R_AT(A, n, k, j) = F3R_AT(A, n, p, j);
        F3R_AT(A, n, p, j) = t;
      }
    }
    const double inv = 1.0 / F3R_AT(A, n, k, k);
    for (int i = k + 1; i < n; ++i) F3R_AT(A, n, i, k) *= inv;
    for (int j = k + 1; j < n; ++j) {
      const double akj = F3R_AT(A, n, k, j);
      if (akj == 0.0) continue;
      for (int i = k + 1; i < n; ++i) F3R_AT(A, n, i, j) -= F3R_AT(A, n, i, k) * akj;
    }
  }
  return 0;
}

void f3r_lu_solve(const double* A, int n, const int* piv, double* b) {
  /* The factorisation swapped whole rows, so all swaps apply to b before substitution. */
  for (int k = 0; k < n; ++k) {
    const int p = piv[k];
    if (p != k) {
      const double t = b[k];
      b[k] = b[p];
      b[p] = t;
    }
  }
  for (int k = 0; k < n; ++k)
    for (int i = k + 1; i < n; ++i) b[i] -= F3R_AT(A, n, i, k) * b[k];
  for (int k = n - 1; k >= 0; --k) {
    b[k] /= F3R_AT(A, n, k, k);
    for (int i = 0; i < k; ++i) b[i] -= F3R_AT(A, n, i, k) * b[k];
  }
}

int f3r_cholesky_factor(double* A, int n) {
  for (int j = 0; j < n; ++j) {
    double d = F3R_AT(A, n, j, j);
    for (int k = 0; k < j; ++k) d -= F3R_AT(A, n, j, k) * F3R_AT(A, n, j, k);
    if (!(d > 0.0) || !isfinite(d)) return 1;
    const double ljj = sqrt(d);
    F3R_AT(A, n, j, j) = ljj;
    for (int i = j + 1; i < n; ++i) {
      double s = F3R_AT(A, n, i, j);
      for (int k = 0; k < j; ++k) s -= F3R_AT(A, n, i, k) * F3R_AT(A, n, j, k);
      F3R_AT(A, n, i, j) = s / ljj;
    }
  }
  return 0;
}

void f3r_cholesky_solve(const double* L, int n, double* b) {
  for (int i = 0; i < n; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= F3R_AT(L, n, i, k) * b[k];
    b[i] = s / F3R_AT(L, n, i, i);
  }
  for (int i = n - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < n; ++k) s -= F3R_AT(L, n, k, i) * b[k];
    b[i] = s / F3R_AT(L, n, i, i);
  }
}

/* Cholesky L L^T of the small symmetric positive definite n x n A (column-major, lower triangle
 * overwritten), keeping 1 / L_jj in inv: the solves then multiply instead of divide, which is
 * what a few 3 x 3 systems cost. Returns 1 when A is not numerically positive definite. */
int f3r_cholesky_factor_inv(double* A, int n, double* inv) {
  for (int j = 0; j < n; ++j) {
    double d = A[j + n * j];
    for (int k = 0; k < j; ++k) d -= A[j + n * k] * A[j + n * k];
    if (!(d > 0.0) || !isfinite(d)) return 1;
    const double l = sqrt(d);
    A[j + n * j] = l;
    inv[j] = 1.0 / l;
    for (int i = j + 1; i < n; ++i) {
      double s = A[i + n * j];
      for (int k = 0; k < j; ++k) s -= A[i + n * k] * A[j + n * k];
      A[i + n * j] = s * inv[j];
    }
  }
  return 0;
}

/* X = A^{-1} X for the nrhs columns of X (leading dimension n), A factored by f3r_cholesky_factor_inv. */
void f3r_cholesky_solve_inv(const double* L, int n, const double* inv, double* X, int nrhs) {
  for (int c = 0; c < nrhs; ++c) {
    double* x = X + n * c;
    for (int i = 0; i < n; ++i) {
      double s = x[i];
      for (int k = 0; k < i; ++k) s -= L[i + n * k] * x[k];
      x[i] = s * inv[i];
    }
    for (int i = n - 1; i >= 0; --i) {
      double s = x[i];
      for (int k = i + 1; k < n; ++k) s -= L[k + n * i] * x[k];
      x[i] = s * inv[i];
    }
  }
}

/* Householder reduction of the symmetric A (lower triangle read) to tridiagonal form
 * T = Q^T A Q: diagonal d, subdiagonal e (e[0] = 0, e[i] couples i - 1 and i), Q into A. */
static void tridiagonalise(double* A, int n, double* d, double* e) {
#define A_(i, j) F3R_AT(A, n, i, j)
  for (int i = n - 1; i > 0; --i) {
    const int l = i - 1;
    double h = 0.0;
    if (l > 0) {
      double scale = 0.0;
      for (int k = 0; k <= l; ++k) scale += fabs(A_(i, k));
      if (scale == 0.0) {
        e[i] = A_(i, l);
      } else {
        for (int k = 0; k <= l; ++k) {
          A_(i, k) /= scale;
          h += A_(i, k) * A_(i, k);
        }
        double f = A_(i, l);
        double g = f >= 0.0 ? -sqrt(h) : sqrt(h);
        e[i] = scale * g;
        h -= f * g;
        A_(i, l) = f - g;
        f = 0.0;
        for (int j = 0; j <= l; ++j) {
          A_(j, i) = A_(i, j) / h;
          g = 0.0;
          for (int k = 0; k <= j; ++k) g += A_(j, k) * A_(i, k);
          for (int k = j + 1; k <= l; ++k) g += A_(k, j) * A_(i, k);
          e[j] = g / h;
          f += e[j] * A_(i, j);
        }
        const double hh = f / (h + h);
        for (int j = 0; j <= l; ++j) {
          f = A_(i, j);
          e[j] = g = e[j] - hh * f;
          for (int k = 0; k <= j; ++k) A_(j, k) -= f * e[k] + g * A_(i, k);
        }
      }
    } else {
      e[i] = A_(i, l);
    }
    d[i] = h;
  }
  d[0] = 0.0;
  e[0] = 0.0;
  for (int i = 0; i < n; ++i) { /* accumulate Q */
    const int l = i - 1;
    if (d[i] != 0.0)
      for (int j = 0; j <= l; ++j) {
        double g = 0.0;
        for (int k = 0; k <= l; ++k) g += A_(i, k) * A_(k, j);
        for (int k = 0; k <= l; ++k) A_(k, j) -= g * A_(k, i);
      }
    d[i] = A_(i, i);
    A_(i, i) = 1.0;
    for (int j = 0; j <= l; ++j) A_(j, i) = A_(i, j) = 0.0;
  }
#undef A_
}

/* Implicit QL with Wilkinson-type shifts on the tridiagonal (d, e), rotating the columns of Z. */
static int tridiagonal_ql(double* d, double* e, int n, double* Z) {
  for (int i = 1; i < n; ++i) e[i - 1] = e[i];
  e[n - 1] = 0.0;
  for (int l = 0; l < n; ++l) {
    int iterations = 0, m;
    do {
      for (m = l; m < n - 1; ++m) {
        const double dd = fabs(d[m]) + fabs(d[m + 1]);
        if (fabs(e[m]) <= 1e-15 * dd) break;
      }
      if (m == l) break;
      if (++iterations > 60) return 1;
      double g = (d[l + 1] - d[l]) / (2.0 * e[l]);
      double r = hypot(g, 1.0);
      g = d[m] - d[l] + e[l] / (g + (g >= 0.0 ? fabs(r) : -fabs(r)));
      double s = 1.0, c = 1.0, p = 0.0;
      int i;
      for (i = m - 1; i >= l; --i) {
        double f = s * e[i];
        const double b = c * e[i];
        e[i + 1] = r = hypot(f, g);
        if (r == 0.0) {
          d[i + 1] -= p;
          e[m] = 0.0;
          break;
        }
        s = f / r;
        c = g / r;
        g = d[i + 1] - p;
        r = (d[i] - g) * s + 2.0 * c * b;
        d[i + 1] = g + (p = s * r);
        g = c * r - b;
        for (int k = 0; k < n; ++k) {
          f = F3R_AT(Z, n, k, i + 1);
          F3R_AT(Z, n, k, i + 1) = s * F3R_AT(Z, n, k, i) + c * f;
          F3R_AT(Z, n, k, i) = c * F3R_AT(Z, n, k, i) - s * f;
        }
      }
      if (r == 0.0 && i >= l) continue;
      d[l] -= p;
      e[l] = g;
      e[m] = 0.0;
    } while (m != l);
  }
  return 0;
}

/* Cyclic Jacobi rotations: slower, kept as the fallback should QL not converge. */
static void jacobi(double* A, int n, double* eig, double* V) {
  if (V)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) F3R_AT(V, n, i, j) = i == j ? 1.0 : 0.0;
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0.0, diag = 0.0;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (i == j)
          diag += F3R_AT(A, n, i, i) * F3R_AT(A, n, i, i);
        else
          off += F3R_AT(A, n, i, j) * F3R_AT(A, n, i, j);
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
        if (V)
          for (int k = 0; k < n; ++k) {
            const double vkp = F3R_AT(V, n, k, p), vkr = F3R_AT(V, n, k, r);
            F3R_AT(V, n, k, p) = c * vkp - s * vkr;
            F3R_AT(V, n, k, r) = s * vkp + c * vkr;
          }
      }
  }
  for (int i = 0; i < n; ++i) eig[i] = F3R_AT(A, n, i, i);
}

void f3r_symmetric_eigen(double* A, int n, double* eig, double* V) {
  if (V && n > 1) {
    double* e = malloc((size_t)n * sizeof(double));
    double* copy = malloc((size_t)n * n * sizeof(double));
    if (e && copy) {
      memcpy(copy, A, (size_t)n * n * sizeof(double));
      memcpy(V, A, (size_t)n * n * sizeof(double));
      tridiagonalise(V, n, eig, e);
      const int failed = tridiagonal_ql(eig, e, n, V);
      if (!failed) {
        free(e), free(copy);
        return;
      }
      memcpy(A, copy, (size_t)n * n * sizeof(double));
    }
    free(e), free(copy);
  }
  jacobi(A, n, eig, V);
}
