/* The physics layer's edge: the query functions that take (q, v), run the forward pass
 * (forward.c) into a local f3r_data for the caller, and read its stages (queries.c); with the
 * kernels that take (q, v) directly (derivatives.h, forces.h) and the assembled equations
 * (equations.h), the whole private interface in one include, in the redundant coordinates q of
 * model.h. Private (flex3rpr_core_private): the tests, the benchmark and the peer library assemble
 * the same model from them.
 *
 * Equations of motion (paper eq. 18-19, derived from eqs. 8-17, docs/model.md):
 *   M(q) a + h(q, v) + k(q) = Q(t, q, v) + G(q)^T lambda,     g(q) = 0
 * with v = dq/dt, a = dv/dt, M the mass matrix, h = dM/dt v - dT/dq the velocity-dependent
 * (Coriolis and centrifugal) forces, k = dV/dq the elastic forces, Q the generalized forces,
 * g the six loop-closure constraints (two per link, eqs. 14-17) and G = dg/dq.
 *
 * Matrices are dense and column-major with a leading dimension `ld` (as SUNDIALS' dense
 * matrices): element (i, j) is at A[j*ld + i]. Functions named `f3r_add_*` add `scale` times
 * their matrix into A, so that a Jacobian can be assembled block by block in place. */
#ifndef FLEX3RPR_QUERIES_H
#define FLEX3RPR_QUERIES_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" { /* the private headers below are C's alone */
#endif

#include "derivatives.h"
#include "effects.h"
#include "equations.h"
#include "forces.h"
#include "forward.h"
#include "position.h"

/* The two shapes most functions below share: out = a matrix at q times x (x is a, v or lambda),
 * and scale * the derivative of such a product (x held fixed) added into A. */
typedef void f3r_product_fn(const f3r_model* m, const double* q, const double* x, double* out);
typedef void f3r_add_derivative_fn(const f3r_model* m, const double* q, const double* x,
                                   double scale, double* A, int ld);

/* --- inertia ------------------------------------------------------------------------------- */
/* scale * M(q) (nq x nq) added into A; out = M(q) a (nq). d(M a)/dq: derivatives.h. */
void f3r_add_mass_matrix(const f3r_model* m, const double* q, double scale, double* A, int ld);
f3r_product_fn f3r_mass_times;

/* --- velocity-dependent forces h(q, v) --------------------------------------------------------- */
/* h (nq) at (q, v); scale * dh/dv (nq x nq) added into A. dh/dq: derivatives.h. */
f3r_product_fn f3r_velocity_forces;
f3r_add_derivative_fn f3r_add_velocity_forces_dv;

/* --- generalized forces Q = held + the scene's effects (inputs, gravity, friction, damping) ----- */
/* held (nq) are the caller's forces (may be NULL for none). */
void f3r_generalized_forces(const f3r_model* m, double t, const double* held, const double* q,
                            const double* v, double* Q);
/* Q with actuator lag: the leg forces applied are the lag states `lag` (3), not the commanded
 * ones; lag may be NULL when the model has none. commanded (3, may be NULL) receives the command. */
void f3r_applied_forces(const f3r_model* m, double t, const double* held, const double* q,
                        const double* v, const double* lag, double* Q, double* commanded);
/* scale * dQ/dq, dQ/dv of the effects at (q, v) added into A (nq x nq). */
f3r_add_derivative_fn f3r_add_generalized_forces_dq, f3r_add_generalized_forces_dv;

/* --- constraints -------------------------------------------------------------------------------- */
void f3r_constraints(const f3r_model* m, const double* q, double* g); /* g (6) */
void f3r_add_constraint_jacobian(const f3r_model* m, const double* q, double scale, double* A,
                                 int ld); /* G (6 x nq) */
void f3r_add_constraint_jacobian_transpose(const f3r_model* m, const double* q, double scale,
                                           double* A, int ld); /* G^T (nq x 6) */
/* G(q) v (6) and G(q)^T lambda (nq); d(G(q)^T lambda)/dq (nq x nq) and d(G(q) v)/dq (6 x nq). */
f3r_product_fn f3r_constraint_times, f3r_constraint_transpose_times;
f3r_add_derivative_fn f3r_add_constraint_transpose_times_dq, f3r_add_constraint_times_dq;
/* gamma = (dG/dt) v (6), so that G a + gamma = 0 along a motion; scale * d(gamma)/dq and
 * scale * d(gamma)/dv (6 x nq) added into A. */
f3r_product_fn f3r_constraint_bias;
f3r_add_derivative_fn f3r_add_constraint_bias_dq, f3r_add_constraint_bias_dv;

/* --- energy ------------------------------------------------------------------------------------- */
double f3r_kinetic_energy(const f3r_model* m, const double* q, const double* v);
double f3r_potential_energy(const f3r_model* m, const double* q);

/* --- impacts at the end stops ---------------------------------------------------------------------- */
/* An impact at the end stops for the legs in contact (legs, count <= 3), each leg's rate after it
 * given (rates[count], m/s: -c rho_i' for Newton's law with restitution c, 0 for a leg that
 * stays): the jump dv solves [M -G^T -E; G 0 0; E^T 0 0] [dv; Lambda; p] = [0; 0; rates - E^T v],
 * E the unit columns of rho_legs, so the loops stay closed (G dv = 0). v_out = v + dv,
 * impulse[count] the impulses (N s, along rho_i). work holds f3r_impact_work_size doubles. */
f3r_status f3r_impact(const f3r_model* m, const double* q, const double* v, const int* legs,
                      int count, const double* rates, double* v_out, double* impulse, double* work);
size_t f3r_impact_work_size(const f3r_model* m);

/* --- end stops held as contact (equations.h) at (q, v) ----------------------------------------- */
/* The stops' forces f (3) under the generalized forces Q without them. work holds
 * f3r_stop_forces_work_size doubles. */
f3r_status f3r_stop_forces(const f3r_model* m, const f3r_stop_locks* locks, const double* q,
                           const double* v, const double* Q, double* f, double* work);
/* The same forces and the accelerations a (nq) under them. work as f3r_stop_forces'. */
f3r_status f3r_contact_accelerations(const f3r_model* m, const f3r_stop_locks* locks,
                                     const double* q, const double* v, const double* Q, double* f,
                                     double* a, double* work);

/* --- accelerations ------------------------------------------------------------------------------ */
/* Solves [M -G^T; G 0] [a; lambda] = [Q - h - k; -gamma] for the accelerations a (nq) and the
 * multipliers lambda (6) at (q, v). work holds f3r_solve_accelerations_work_size doubles.
 * Returns F3R_ERR_SINGULAR if the system is singular. */
f3r_status f3r_solve_accelerations(const f3r_model* m, const double* q, const double* v,
                                   const double* Q, double* a, double* lambda, double* work);

#ifdef __cplusplus
}
#endif
#endif
