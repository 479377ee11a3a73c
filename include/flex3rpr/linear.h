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
  int n;                  /* number of minimal coordinates */
  double* mass;           /* n x n, column-major */
  double* damping;        /* n x n: joint friction and modal damping through the loop closure */
  double* stiffness;      /* n x n: beam stiffness and the geometric stiffness of static loads */
  double* input;          /* n x F3R_RIGID_FORCES */
  double* static_force;   /* n */
  double* shapes;         /* n x n: mode shapes Phi, Phi^T M Phi = I, by ascending omega^2 */
  double* omega2;         /* n: eigenvalues of K Phi = M Phi diag(omega^2), rad^2/s^2 */
  double* modal_damping;  /* n: diagonal of Phi^T D Phi (its coupling terms are neglected) */
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
                                          const f3r_model* other, double dt, int count, double* pose,
                                          int* unreachable, f3r_error* err);

#ifdef __cplusplus
}
#endif
#endif
