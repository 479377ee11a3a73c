/* Assumed modes of a clamped Euler-Bernoulli beam (paper eqs. 3-7, docs/model.md).
 *
 * A link is clamped at B (xi = 0) and either pinned or free at C (xi = 1). Mode j (1-based) is
 *   psi_j(xi) = (cos a xi - cosh a xi) - sigma_j (sin a xi - sinh a xi),   a = alpha_j,
 *   fixed-pinned: sigma = (cos a - cosh a)/(sin a - sinh a),  tan a = tanh a        (eq. 3, 4)
 *   fixed-free:   sigma = (cos a + cosh a)/(sin a + sinh a),  cos a cosh a + 1 = 0  (eq. 5, 6)
 * with the paper's sign (fixed-free psi_j(1) = 2(-1)^j). The modes are mass-orthonormal:
 * integral_0^1 psi_i psi_j dxi = delta_ij, and integral psi_i'' psi_j'' = alpha_i^4 delta_ij.
 * Evaluation uses decaying exponentials only, so it is accurate to machine precision for every
 * mode up to F3R_MAX_MODES (the printed cosh - sigma sinh form cancels catastrophically). */
#ifndef FLEX3RPR_BEAM_MODES_H
#define FLEX3RPR_BEAM_MODES_H

#include "flex3rpr/coords.h" /* F3R_MAX_MODES, f3r_beam_end */

#ifdef __cplusplus
extern "C" {
#endif

/* alpha_j, j = 1..count, roots of the frequency equation of `end`, to ~1e-15 relative.
 * Returns 0, or -1 if count is outside 1..F3R_MAX_MODES. */
int f3r_beam_roots(f3r_beam_end end, int count, double* alpha);

/* psi, psi' and psi'' (derivatives with respect to xi) of the mode with root alpha, at xi in
 * [0, 1]. Any output pointer may be NULL. */
void f3r_beam_mode_eval(f3r_beam_end end, double alpha, double xi, double* psi, double* dpsi,
                        double* ddpsi);

/* Integrals of the first `count` modes over [0, 1], by composite Gauss-Legendre quadrature.
 * Every output may be NULL. mean[j] = int psi_j, first_moment[j] = int xi psi_j,
 * gram[i*count+j] = int psi_i psi_j, bending[i*count+j] = int psi_i'' psi_j'',
 * tip[j] = psi_j(1) (exactly 0 for fixed-pinned). Returns 0, or -1 for a bad count. */
int f3r_beam_modal_integrals(f3r_beam_end end, int count, double* mean, double* first_moment,
                             double* gram, double* bending, double* tip);

/* The constants a link's model needs of its first `count` modes, in closed form (no quadrature):
 * alpha[j], mean[j] = int psi_j, first_moment[j] = int xi psi_j, tip[j] = psi_j(1), all from the
 * cancellation-free form of f3r_beam_mode_eval; int psi_j''^2 = alpha_j^4 needs no output. Equal to
 * f3r_beam_modal_integrals' to rounding, and ~100x cheaper at 20 modes. Every output but alpha
 * may be NULL. Returns 0, or -1 for a bad count. */
int f3r_beam_mode_constants(f3r_beam_end end, int count, double* alpha, double* mean,
                            double* first_moment, double* tip);

/* Nodes and weights of the n-point Gauss-Legendre rule on [0, 1] (n <= 64). Returns 0 or -1. */
int f3r_gauss_legendre(int n, double* nodes, double* weights);

#ifdef __cplusplus
}
#endif
#endif
