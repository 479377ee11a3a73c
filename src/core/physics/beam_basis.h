/* A link's beam basis: the paper's r modes, optionally enlarged by static correction shapes
 * (issue 28). Private to the core.
 *
 * A static shape s_k is the clamped beam's static deflection under one load it carries
 * (EI w per unit load, xi = x/l, in l-units; s'''' is the load):
 *   fixed-free:   tip force      xi^2 (3 - xi) / 6
 *                 uniform load   xi^2 (6 - 4 xi + xi^2) / 24
 *                 linear load    xi^2 (20 - 10 xi + xi^3) / 120        (load q = xi)
 *   fixed-pinned: uniform load   xi^2 (1 - xi) (3 - 2 xi) / 48
 *                 linear load    xi^2 (1 - xi) (7 - 2 xi - 2 xi^2) / 240
 * (a tip force does no work at a pin: there is no fixed-pinned tip shape).
 *
 * A Ritz step makes the enlarged basis mass-orthonormal with a diagonal stiffness:
 *   t_k = s_k - sum_{j<=r} C_jk psi_j,  C_jk = int psi_j s_k   (the residual, orthogonal to the
 *         modes in mass and, since K(psi_j, u) = alpha_j^4 M(psi_j, u), in stiffness too);
 *   K_t v = lambda M_t v on the residuals' Grams, v^T M_t v = 1, lambda ascending;
 *   phi_{r+m} = sum_k V[k][m] t_k = sum_k V[k][m] s_k - sum_j CV[j][m] psi_j.
 * The first r functions are the paper's modes with f3r_beam_mode_constants' constants, bit for
 * bit. Derivation and a 50-digit reference: test/reference/static_correction_reference.py. */
#ifndef FLEX3RPR_BEAM_BASIS_H
#define FLEX3RPR_BEAM_BASIS_H

#include "flex3rpr/beam_modes.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The static shapes, as bits of a shape set. */
enum { F3R_SHAPE_TIP_FORCE = 1, F3R_SHAPE_UNIFORM_LOAD = 2, F3R_SHAPE_LINEAR_LOAD = 4 };

/* A shape is dropped when its residual is this small against the shape, in mass norm:
 * ||t_k|| / ||s_k|| < 1e-6 (the research note's tolerance). The functions lose about
 * eps / (that ratio) to the cancellation in t_k = s_k - sum C psi. */
#define F3R_SHAPE_DROP_RATIO 1e-6

typedef struct {
  f3r_beam_end end;
  int modes;                       /* r: the paper's modes, functions 0..r-1 */
  int shapes;                      /* p: static shapes kept after the drop test (the rows of V) */
  int corrections;                 /* functions r..count-1 made of them: p, or 1 when mixed */
  int count;                       /* r + corrections <= F3R_MAX_MODES */
  int mixed;                       /* 1: the correction is tip + mix uniform (build_mixed) */
  double mix;                      /* then q l / F of its loads */
  unsigned shape_kind[3];          /* the F3R_SHAPE_* bit of kept shape k (the rows of V) */
  double alpha[F3R_MAX_MODES];     /* roots of the modes; alpha_equiv = stiffness^(1/4) beyond r */
  double stiffness[F3R_MAX_MODES]; /* int phi_j''^2: alpha_j^4 for a mode, lambda beyond */
  double mean[F3R_MAX_MODES];      /* int phi_j */
  double first_moment[F3R_MAX_MODES]; /* int xi phi_j */
  double tip[F3R_MAX_MODES];          /* phi_j(1): exactly 0 for fixed-pinned */
  double residual_ratio[3];           /* ||t_k|| / ||s_k|| (mass norm) of each kept shape */
  /* phi_{r+m} = sum_k V[k][m] s_k - sum_j CV[j][m] psi_j. Long double: |CV| reaches |s|/|t|
   * (1e5 at r = 3), and its double rounding alone left int phi psi_1 at 1e-10 (r = 3, three
   * shapes) against 2e-13 in long double (x86-64's 64-bit mantissa; aarch64 Linux's is quad).
   * Where long double is double (MSVC, Apple arm64) the basis is good to ~1e-10 only. */
  long double V[3][3];
  long double CV[F3R_MAX_MODES][3];
} f3r_beam_basis;

/* Builds the basis of `modes` paper modes plus the orthogonalised static shapes in shape_set
 * (0: the paper's basis, identical to f3r_beam_mode_constants). Shapes whose residual is below
 * F3R_SHAPE_DROP_RATIO, or nearly dependent on the others, are left out (out->shapes says how
 * many stay). Corrections are sorted by stiffness ascending, with the sign fixed-free
 * phi(1) > 0, fixed-pinned int phi > 0. Returns 0, or -1 for a bad end, modes outside
 * 1..F3R_MAX_MODES, unknown bits, a tip-force shape on a fixed-pinned link, or modes plus the
 * requested shapes above F3R_MAX_MODES, or F3R_BASIS_NO_MEMORY when its table of the modes at
 * the quadrature nodes (freed before it returns) cannot be allocated. */
#define F3R_BASIS_NO_MEMORY (-2)
int f3r_beam_basis_build(f3r_beam_end end, int modes, unsigned shape_set, f3r_beam_basis* out);

/* A fixed-free basis of `modes` paper modes and one correction: the static deflection under a tip
 * force F together with a uniform load q along the link, mix = q l / F, orthogonalised as above
 * (its residual t = t_tip + mix t_uniform, normalised in mass; its stiffness the Rayleigh
 * quotient). One function where the pair has two: the mechanism's slow modes load a link in one
 * ratio, which f3r_shape_mix_fit (accuracy layer) finds, and the pair's stiffer combination only
 * adds a fast mode (docs/benchmarks/fast_shapes.md). When the drop test leaves one shape, that
 * shape is the correction, unmixed. Returns what f3r_beam_basis_build would, and -1 for a
 * non-finite mix. */
int f3r_beam_basis_build_mixed(int modes, double mix, f3r_beam_basis* out);

/* phi_j, phi_j' and phi_j'' (derivatives with respect to xi) of function j (0-based, < count)
 * at xi in [0, 1]. Any output may be NULL. */
void f3r_beam_basis_eval(const f3r_beam_basis* b, int j, double xi, double* phi, double* dphi,
                         double* ddphi);

#ifdef __cplusplus
}
#endif
#endif
