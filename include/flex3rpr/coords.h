/* The layout of the generalized coordinates q (and of v, a and the generalized forces Q), named
 * once: every index into them in the core, the CLI and the node is one of these names.
 *   q[F3R_Q_RHO + i]    rho_i, stroke |A_i B_i| (m), i = 0..2
 *   q[F3R_Q_THETA + i]  theta_i, direction of leg i from +X at A_i (rad)
 *   q[F3R_Q_X], q[F3R_Q_Y], q[F3R_Q_PHI]  the platform pose X_p, Y_p (m), phi_p (rad)
 *   q[F3R_Q_MODAL ...]  eta of link 1 (r_1 values), then link 2, then link 3 (m)
 * The minimal formulation's independent coordinates z are q[F3R_Q_INDEPENDENT ...]: the platform
 * pose and the modal coordinates. */
#ifndef FLEX3RPR_COORDS_H
#define FLEX3RPR_COORDS_H

enum {
  F3R_Q_RHO = 0,
  F3R_Q_THETA = 3,
  F3R_Q_X = 6,
  F3R_Q_Y = 7,
  F3R_Q_PHI = 8,
  F3R_Q_MODAL = 9,
  F3R_Q_INDEPENDENT = F3R_Q_X, /* first coordinate of z */
  F3R_Q_LEG_JOINTS = F3R_Q_X   /* rho and theta of the three legs come before it */
};

/* Sizes and kinds every layer shares, from the scene up: the most modes a link may have, and
 * the two beam ends of beam_modes.h. */
#define F3R_MAX_MODES 20

typedef enum { F3R_BEAM_FIXED_PINNED = 1, F3R_BEAM_FIXED_FREE = 2 } f3r_beam_end;

#endif
