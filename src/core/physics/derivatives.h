/* The derivatives of the equations of motion, from q and v directly or from the forward pass's
 * stages in d (the comment of each says which). Matrices column-major with leading dimension ld;
 * each adds scale times its derivative into A. Private. */
#ifndef FLEX3RPR_DERIVATIVES_H
#define FLEX3RPR_DERIVATIVES_H

#include "data.h"

/* d(M(q) a)/dq (nq x nq), a held fixed. */
void f3r_add_mass_times_dq(const f3r_model* m, const double* q, const double* a, double scale,
                           double* A, int ld);
/* dh/dq at (q, v); dh/dv at the position and velocity stages in d (q: d's coordinates). */
void f3r_add_velocity_forces_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld);
void f3r_data_add_velocity_forces_dv(const f3r_model* m, const f3r_data* d, const double* q,
                                     double scale, double* A, int ld);
/* dk/dq, constant. */
void f3r_add_elastic_forces_dq(const f3r_model* m, double scale, double* A, int ld);
/* At the position stage: d(G^T y)/dq (nq x nq) for a 6-vector y, and d(G x)/dq (6 x nq). */
void f3r_data_add_constraint_transpose_times_dq(const f3r_model* m, const f3r_data* d,
                                                const double* y, double scale, double* A, int ld);
void f3r_data_add_constraint_times_dq(const f3r_model* m, const f3r_data* d, const double* x,
                                      double scale, double* A, int ld);
/* At the position and velocity stages of v: d(gamma)/dq and d(gamma)/dv (6 x nq). */
void f3r_data_add_constraint_bias_dq(const f3r_model* m, const f3r_data* d, const double* v,
                                     double scale, double* A, int ld);
void f3r_data_add_constraint_bias_dv(const f3r_model* m, const f3r_data* d, const double* v,
                                     double scale, double* A, int ld);

#endif
