/* Column-major dense helpers shared by the core. Private. */
#ifndef FLEX3RPR_DENSE_H
#define FLEX3RPR_DENSE_H

#include <stddef.h>

#define F3R_AT(A, ld, i, j) ((A)[(size_t)(j) * (size_t)(ld) + (size_t)(i)])

/* LU factorisation with partial pivoting of the n x n matrix A (column-major, leading dimension
 * n) in place; pivots in piv. Returns 0, or 1 if a pivot is zero or not finite. */
int f3r_lu_factor(double* A, int n, int* piv);
/* Solves with the factors of f3r_lu_factor; b is overwritten with the solution. */
void f3r_lu_solve(const double* A, int n, const int* piv, double* b);
/* Cholesky factorisation A = L L^T of the symmetric positive definite n x n matrix A (lower
 * triangle used, L written over it). Returns 0, or 1 if A is not numerically positive definite. */
int f3r_cholesky_factor(double* A, int n);
/* Solves L L^T x = b with the factor of f3r_cholesky_factor; b is overwritten with x. */
void f3r_cholesky_solve(const double* L, int n, double* b);
/* The same factorisation keeping 1 / L_jj in inv[n], and its solve for nrhs columns of X
 * (leading dimension n): multiplications instead of divisions, for many small systems. */
int f3r_cholesky_factor_inv(double* A, int n, double* inv);
void f3r_cholesky_solve_inv(const double* L, int n, const double* inv, double* X, int nrhs);

/* Eigenvalues (eig[n], unordered) and, when V is not NULL, orthonormal eigenvectors (columns of
 * V, n x n) of the symmetric n x n matrix A by cyclic Jacobi rotations; A is destroyed. */
void f3r_symmetric_eigen(double* A, int n, double* eig, double* V);

#endif
