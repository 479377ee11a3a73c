/* An independent evaluation of Lagrange's equations of the 3-RPR, for tests only.
 * T is integrated by quadrature over the beam's velocity field (paper eq. 9, or, with exact
 * kinematics, the complex-step derivative of the beam point positions r(x; q)), V by quadrature
 * of EI w''^2; the equations come from finite differences of T and V. Only the model's constants
 * and f3r_beam_basis_eval (the mode shapes and the static shapes) are shared with the code under
 * test. */
#ifndef FLEX3RPR_TEST_INDEPENDENT_LAGRANGIAN_H
#define FLEX3RPR_TEST_INDEPENDENT_LAGRANGIAN_H

#include "flex3rpr/model.h"
#include "model_layout.h"

#ifdef __cplusplus
extern "C" {
#endif

double indep_kinetic_energy(const f3r_model* m, const double* q, const double* qd);
double indep_potential_energy(const f3r_model* m, const double* q);
/* out = d/dt dT/dqd - dT/dq + dV/dq along (q, qd, qdd); should equal M qdd + h + k. */
void indep_lagrange(const f3r_model* m, const double* q, const double* qd, const double* qdd,
                    double* out);
/* Gravitational potential -sum m g.r_com of the cylinders, the beams (by quadrature over the
 * deflected centre line) and the platform with its payload, from m->gravity. */
double indep_gravity_potential(const f3r_model* m, const double* q);

/* Loop-closure residual from positions alone: beam tip (x = l) minus platform joint C_i. */
void indep_constraints(const f3r_model* m, const double* q, double* g);

#ifdef __cplusplus
}
#endif
#endif
