/* The model linearised about the scene's initial platform pose with zero deflection and zero
 * velocity, in the minimal coordinates z = (X_p, Y_p, phi_p, eta) (n = 3 + sum r_i):
 *   M z'' + D z' + K (z - z0) = f0 + U u(t)
 * M, D, K are the derivatives of the public minimal residual (f3r_residual_jacobian) with respect
 * to z'', z' and z; U (n x 9) is the generalized force in z of a unit rigid force (F3R_FORCE_*),
 * from two residual evaluations; f0 is the residual's static force at rest (in-plane gravity).
 * Its modes, mass-normalised, and the platform pose's response to the scene's own
 * inputs and initial state follow by modal superposition, exact for piecewise-linear inputs.
 * The accuracy knob (accuracy.h) compares this response across mode counts. */
#ifndef FLEX3RPR_LINEAR_H
#define FLEX3RPR_LINEAR_H

#include "flex3rpr/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  int n;                 /* number of minimal coordinates */
  double* mass;          /* n x n, column-major */
  double* damping;       /* n x n: joint friction and modal damping through the loop closure */
  double* stiffness;     /* n x n: beam stiffness and the geometric stiffness of static loads */
  double* input;         /* n x F3R_RIGID_FORCES */
  double* static_force;  /* n */
  double* shapes;        /* n x n: mode shapes Phi, Phi^T M Phi = I, by ascending omega^2 */
  double* omega2;        /* n: eigenvalues of K Phi = M Phi diag(omega^2), rad^2/s^2 */
  double* modal_damping; /* n: diagonal of Phi^T D Phi (its coupling terms are neglected) */
} f3r_linear_model;

/* Linearises the model (with its actuator lag left out and its scripted inputs at zero) and
 * computes its modes. */
f3r_status f3r_linearise(const f3r_model* model, f3r_linear_model** out, f3r_error* err);
void f3r_linear_destroy(f3r_linear_model* linear);

/* Platform pose (X_p, Y_p, phi_p) at t_k = k dt, k = 0..count-1, into pose[3 k .. 3 k + 2]:
 * the response of the linear model to the scene's scripted inputs (through its actuator lag, if
 * any) and to its initial platform velocity and modal deflections and rates. The inputs are
 * sampled at t_k and taken as linear in between.
 * order 2 adds the second-order correction: the nonlinear residual's remainder along the linear
 * path (what the linearisation leaves out: quadratic velocity terms, the drift that vibration
 * drives in the unactuated mechanism, geometry) fed back through the same modes. Samples where the
 * linear path leaves the reachable poses contribute no correction; *unreachable (may be NULL)
 * counts them. */
f3r_status f3r_linear_response(const f3r_linear_model* linear, const f3r_model* model, double dt,
                               int count, int order, double* pose, int* unreachable,
                               f3r_error* err);

/* What `other` (a model of the same coordinates, e.g. with exact kinematics) adds to the path, to
 * first order in the difference: its residual less the model's along the model's first-order
 * linear path, fed through the model's modes. pose gets the deviation (x, y, phi a sample, zero at
 * t = 0). The difference is second order in the motion where the two models share their tangent
 * (exact kinematics' axial velocity -w theta_dot is), so the linear model cannot see it itself. */
f3r_status f3r_linear_difference_response(const f3r_linear_model* linear, const f3r_model* model,
                                          const f3r_model* other, double dt, int count,
                                          double* pose, int* unreachable, f3r_error* err);

/* The linear model as a first-order state-space system, for control design and for export
 * (flex3rpr_sim --linearise FILE.mat):
 *   x' = A x + B u,   y - y0 = C x + D u
 * about the operating point of f3r_linearise (the scene's initial platform pose, zero deflection,
 * zero velocity), with
 *   x = (z - z0, z')  (nx = 2 n, n = 3 + sum r_i; z = (X_p, Y_p, phi_p, eta of link 1..3))
 *   u = (leg forces on rho_1..3 (N), cylinder torques on theta_1..3 (N m))  (nu = 6)
 *   y = (rho_1..3 (m), theta_1..3 (rad), X_p, Y_p (m), phi_p (rad), tip deflections w_i(l) (m))
 *       (ny = 12)
 *   A = [0 I; -M^-1 K  -M^-1 D],  B = [0; M^-1 U_sel]  (M, D, K, U of f3r_linear_model; U_sel
 *       its columns F3R_FORCE_RHO + i and F3R_FORCE_THETA + i),
 *   C = [dy/dz  0] at z0: rho and theta from the loop closure's derivative (the velocity closure
 *       f3r_model_close_loop_rates, exact), the pose rows the identity, the tip deflections
 *       psi_j(1); D = 0.
 * u is the force the actuators deliver: a model's actuator lag is left out, as in f3r_linearise.
 * With in-plane gravity the operating point is not an equilibrium: its static force
 * (f3r_linear_model.static_force) is not part of A and B. All matrices are column-major. */
#define F3R_SS_INPUTS 6
#define F3R_SS_OUTPUTS 12
#define F3R_SS_NAME 24 /* room for any name below, NUL included */

typedef struct {
  int nx, nu, ny; /* 2 n, F3R_SS_INPUTS, F3R_SS_OUTPUTS */
  double* A;      /* nx x nx (1/s, 1/s^2) */
  double* B;      /* nx x nu (rates per N or N m) */
  double* C;      /* ny x nx */
  double* D;      /* ny x nu: zero */
  double* x0;     /* nx: the operating point (z0, 0) in absolute coordinates, so z = z0 + x[0..n) */
  double y0[F3R_SS_OUTPUTS];        /* the outputs at the operating point */
  char (*state_names)[F3R_SS_NAME]; /* nx: "x_p", "y_p", "phi_p", "eta_1_1" .. "eta_3_<r_3>", then
                                     * the same with "_rate" */
  char input_names[F3R_SS_INPUTS][F3R_SS_NAME];   /* "leg_force_1".., "cylinder_torque_1".. */
  char output_names[F3R_SS_OUTPUTS][F3R_SS_NAME]; /* "rho_1".., "theta_1".., "x_p", "y_p",
                                                   * "phi_p", "tip_deflection_1".. */
} f3r_state_space;

/* Builds the state-space form of the model's linearisation (f3r_linearise). Errors: those of
 * f3r_linearise (an unreachable pose, a singular mass matrix), F3R_ERR_MEMORY. */
f3r_status f3r_state_space_create(const f3r_model* model, f3r_state_space** out, f3r_error* err);
void f3r_state_space_destroy(f3r_state_space* ss);

#ifdef __cplusplus
}
#endif
#endif
