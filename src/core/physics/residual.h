/* The model as a residual F(t, y, y') = 0 in one of three formulations, with its Jacobian
 * dF/dy + cj dF/dy'. Private to the core, the tests, the benchmark and the peer library
 * (flex3rpr_core_private), so that any DAE or ODE solver there can integrate the same model.
 *
 * dae (stabilised index 2, Gear-Gupta-Leimkuhler), ny = 2 nq + 13:
 *   y = [q (nq) | v (nq) | lambda (6) | mu (6) | W (1)]
 *   F = [ q' - v + G^T mu
 *         M v' + h + k - Q - G^T lambda
 *         g(q)
 *         G v
 *         W' - Q . v ]
 *   lambda and mu are algebraic (mu = 0 along exact solutions); q, v and W are differential.
 * index3 (the paper's form, for external solvers such as MEBDFI), ny = 2 nq + 7:
 *   y = [q (nq) | v (nq) | lambda (6) | W (1)],
 *   F = [ q' - v
 *         M v' + h + k - Q - G^T lambda
 *         g(q)
 *         W' - Q . v ]
 *   q and W are index-1 variables, v index 2, lambda index 3 (f3r_index3_variable_indices).
 *   IDA cannot integrate it (f3r_sim_create refuses it): its error test needs the index-2 form.
 * minimal (independent coordinates z = q[6..nq) = (X_p, Y_p, phi_p, eta)), ny = 2 nz + 1:
 *   y = [z (nz) | u (nz) | W (1)],  rho and theta from the closed-form loop closure,
 *   F = [ z' - u
 *         B^T (M a + h + k - Q)      with v = B u, a = B u' + c
 *         W' - Q . v ]
 *   where B = dq/dz and c = dB/dt u. B^T eliminates the multipliers: lambda follows from the
 *   solved accelerations.
 * W is the work done by the generalized forces Q, so T + V - W is conserved. With actuator lag
 * the applied leg forces F_a (3) stand before W, with rows tau F_a' - (F_cmd - F_a). */
#ifndef FLEX3RPR_RESIDUAL_H
#define FLEX3RPR_RESIDUAL_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#include "workspace.h" /* its scratch memory, and the model's state layouts (model_layout.h) */

/* 1 for differential components of y, 0 for algebraic ones (lambda, mu of dae; lambda of index3). */
void f3r_state_kinds(const f3r_model* model, f3r_formulation form, double* id);
/* The index3 form's variables by differentiation index, as MEBDFI and RADAU5 want them:
 * index_of[n] in {1, 2, 3} for each component (ny values, or NULL) and counts[k - 1] of each
 * index (q, lag and W: 1; v: 2; lambda: 3). */
void f3r_index3_variable_indices(const f3r_model* model, int* index_of, int counts[3]);

/* The shapes of a residual F(t, y, y'), its Jacobian and an explicit right-hand side y' = f(t, y),
 * which the functions below and the peers (bench/c) share. */
typedef f3r_status f3r_residual_fn(const f3r_model* model, f3r_formulation form, double t,
                                   const double* y, const double* yp, const double* held,
                                   double* res, f3r_workspace* ws);
typedef f3r_status f3r_jacobian_fn(const f3r_model* model, f3r_formulation form, double t,
                                   double cj, const double* y, const double* yp, const double* held,
                                   double* J, int ld, f3r_workspace* ws);
typedef f3r_status f3r_rhs_fn(const f3r_model* model, double t, const double* y, const double* held,
                              double* ydot, f3r_workspace* ws);

/* End stops held as contact (f3r_workspace_set_locks): the stops' forces (3, N along rho_i, zero
 * on free legs) at state y of the formulation under held forces, from the formulation's own
 * forward pass. */
f3r_status f3r_stop_forces_at(const f3r_model* model, f3r_formulation form, double t,
                              const double* y, const double* held, double* f, f3r_workspace* ws);

/* held: the caller's generalized forces (nq), or NULL. Returns F3R_OK, F3R_ERR_SINGULAR for a
 * configuration the loop closure cannot reach, or F3R_ERR_NONFINITE. */
f3r_residual_fn f3r_residual;

/* J (ny x ny, column-major, leading dimension ld) = dF/dy + cj dF/dy', exact and analytic for
 * both formulations (form_minimal.c derives the minimal one through the loop closure). */
f3r_jacobian_fn f3r_residual_jacobian;

/* The minimal formulation as an explicit ODE y' = f(t, y), y = [z | u | W]: the forward pass,
 * the reduced equations at u' = 0, and one solve with the reduced mass K = B^T M B. K is never
 * formed: each link's modal block is m I plus a rank-2 term and couples to the pose through
 * rank 2 (form_minimal.c), so the solve costs O(r) a link. For explicit integrators and ODE
 * peers. */
f3r_rhs_fn f3r_explicit_rhs;
/* The same with the solve chosen: structured 1 (the low-rank solve above), 0 (K assembled and
 * factored by a dense Cholesky). For the benchmark's comparison and the tests of both. */
f3r_status f3r_explicit_rhs_solver(const f3r_model* model, int structured, double t,
                                   const double* y, const double* held, double* ydot,
                                   f3r_workspace* ws);

/* Full coordinates q, v (nq each) of a state y. */
f3r_status f3r_state_to_full(const f3r_model* model, f3r_formulation form, const double* y,
                             double* q, double* v);

/* Consistent y and y' at time t from full q, v that satisfy the constraints, with work W and
 * actuator lag states lag (3, or NULL for zero):
 * accelerations and multipliers from f3r_solve_accelerations. lambda may be NULL. */
f3r_status f3r_consistent_state(const f3r_model* model, f3r_formulation form, double t,
                                const double* q, const double* v, const double* held,
                                const double* lag, double work, double* y, double* yp,
                                double* lambda, f3r_workspace* ws);

#ifdef __cplusplus
}
#endif
#endif
