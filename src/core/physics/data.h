/* f3r_data: the inputs of one evaluation of the model and everything it computes, grouped by the
 * stage of the forward pass (forward.c) that fills it. The caller sets the inputs (as MuJoCo's
 * mjData holds qpos and qvel) and calls f3r_forward(m, d, what) with the stages it needs; a stage
 * reads the inputs and the fields of the stages before it and writes its own fields once. So each
 * leg's trigonometry is evaluated once per evaluation. A new force term is its code in the stage
 * that sums Q (forces.c, or effects.c for one the scene switches on) and a field here only if a
 * later stage reads it; a switchable one also needs its scene field (scene.h, scene_yaml.c), its
 * compiled parameters and its derivatives for the Jacobian (effects.c): about five files.
 * Private: the query functions of queries.h run the stages they need into a local f3r_data and
 * read it.
 *
 * Conventions (docs/model.md, position.c, mass.c, velocity.c): per link, e = (c, s) along the
 * leg, n = (-s, c) across it, L = rho + l, w the tip deflection; C_i sits at
 * P + r_PC (cc, sc) with (cc, sc) = (cos, sin)(phi_i + phi_p). */
#ifndef FLEX3RPR_DATA_H
#define FLEX3RPR_DATA_H

#include "model_layout.h"

/* A small kernel called once per link or column in a hot loop, inlined whatever the compiler's
 * estimate: as calls, their arguments and results went through memory. */
#if defined(__GNUC__)
#define F3R_INLINE static inline __attribute__((always_inline))
#else
#define F3R_INLINE static inline
#endif

/* A function whose loops run over one link's modes (r = 1..6 on the shipped scenes), where GCC's
 * vectorized loops' runtime alias checks and epilogues cost more than they save, in a file whose
 * other loops gain from it (the CMake file names the files compiled without it whole). */
#if defined(__GNUC__) && !defined(__clang__)
#define F3R_NO_VECTORIZE __attribute__((optimize("no-tree-vectorize")))
#else
#define F3R_NO_VECTORIZE
#endif

/* The stages of the forward pass, a bit set for f3r_forward. */
enum {
  F3R_FWD_POSITION = 1 << 0,        /* q -> per link trigonometry, blocks; g */
  F3R_FWD_POSITION_CLOSED = 1 << 1, /* z -> q_closed by the loop closure (instead of POSITION) */
  F3R_FWD_VELOCITY = 1 << 2,        /* v -> per link rates; h; gamma */
  F3R_FWD_VELOCITY_CLOSED = 1 << 3, /* u -> v_closed by G v = 0 (instead of VELOCITY) */
  F3R_FWD_FORCES = 1 << 4,          /* t, held, lag -> k, Q, commanded, power */
  F3R_FWD_STOPS = 1 << 5,           /* locks, stop_work -> the end stops' forces, into Q too */
  F3R_FWD_ACCELERATION = 1 << 6,    /* vdot, multipliers, mu -> R, G^T mu, G v */
  F3R_FWD_ACCELERATION_CLOSED = 1 << 7, /* udot -> a by the loop closure, R, lambda; reduced */
  F3R_FWD_ENERGY = 1 << 8               /* kinetic and potential energy */
};

struct f3r_stop_locks; /* the legs held at their end stops (equations.h) */

typedef struct {
  /* --- position stage: from q ------------------------------------------------------------- */
  double c, s;          /* cos theta_i, sin theta_i */
  double len;           /* L = rho_i + l (m) */
  double w;             /* tip deflection w_i(l) = sum tip_j eta_j (m) */
  double mean_defl;     /* sum b_j eta_j = int_0^1 w dxi (m) */
  double eta_sq;        /* sum eta_j^2 (m^2) */
  double cc, sc;        /* direction of C_i from P */
  double m_rho_theta;   /* M(rho, theta) = -e m mean_defl (kg m; e = 1 for exact kinematics) */
  double m_theta_theta; /* M(theta, theta) = I_c + m (l^2/3 + l rho + rho^2) + e m eta_sq */
  double m_theta_eta[F3R_MAX_MODES]; /* M(theta, eta_j) = m (l a_j + rho b_j); M(eta, eta) = m I */
  double g_theta[2];                 /* dg_i/dtheta_i = L n - w e; dg_i/drho_i = e, dg_i/dP = -I */
  double g_phi[2];                   /* dg_i/dphi_p = r_PC (sc, -cc) */
  /* dg_i/deta_j = psi_j(1) n = (-tip_j s, tip_j c) of a fixed-free link (a fixed-pinned link's
   * modes vanish at the tip: G has no entry, and these are not filled) */
  double g_eta_x[F3R_MAX_MODES], g_eta_y[F3R_MAX_MODES];
  /* --- velocity stage: from v and the position stage ---------------------------------------- */
  double rho_dot, theta_dot; /* m/s, rad/s */
  double w_dot;              /* sum tip_j eta_j' */
  double mean_defl_dot;      /* sum b_j eta_j' */
  double eta_eta_dot;        /* sum eta_j eta_j' */
} f3r_link_data;

typedef struct f3r_data {
  /* --- inputs: the caller's, before f3r_forward --------------------------------------------- */
  double t;           /* s */
  const double* q;    /* full coordinates (nq); the closed position stage points it at q_closed */
  const double* v;    /* their rates (nq); the closed velocity stage points it at v_closed */
  const double* z;    /* the minimal formulation's independent coordinates (nz), closed stages */
  const double* u;    /* and their rates (nz) */
  const double* held; /* the caller's generalized forces (nq), or NULL */
  const double* lag;  /* the actuator lag states (3), or NULL */
  /* the stops stage's: the locked legs (or NULL for none) and its scratch
   * (f3r_stop_forces_work_size doubles) */
  const struct f3r_stop_locks* locks;
  double* stop_work;
  /* the acceleration stages': the accelerations v' (nq), the multipliers lambda (6) and the
   * stabilised form's mu (6, or NULL) of the redundant formulations; the independent
   * accelerations u' (nz, or NULL for zero) of the minimal one */
  const double *vdot, *multipliers, *mu, *udot;
  /* where the closed acceleration stage writes the reduced equations B^T R = R_z - G_z^T lambda
   * (nz; the minimal residual's rows), or NULL for none */
  double* reduced;
  /* --- the closed stages' full coordinates and rates: z, u and the legs' from the closure; theta_i
   * are not filled (f3r_fwd_leg_angles gives them) ------------------------------------------ */
  double q_closed[F3R_MAX_Q], v_closed[F3R_MAX_Q];
  f3r_link_data link[3];
  /* --- position stage ------------------------------------------------------------------------ */
  double g[F3R_NCON]; /* loop-closure constraints g(q) (m); the position stage */
  /* --- velocity stage ------------------------------------------------------------------------ */
  double h[F3R_MAX_Q];    /* velocity-dependent forces h(q, v) = dM/dt v - dT/dq */
  double gamma[F3R_NCON]; /* (dG/dt) v, so that G a + gamma = 0 */
  /* --- force stage --------------------------------------------------------------------------- */
  double k[F3R_MAX_Q];            /* elastic forces dV/dq */
  double Q[F3R_MAX_Q];            /* applied generalized forces: held + effects (+ actuator lag) */
  double input[F3R_RIGID_FORCES]; /* the scripted inputs' forces at t (the inputs effect; zero
                                   * without it), read again by the actuator lag */
  double commanded[3];            /* leg forces commanded to the actuator lag (when n_lag = 3) */
  double power;                   /* Q . v (W) */
  /* --- stops stage ------------------------------------------------------------------------- */
  double stop_force[3]; /* the locked legs' stop forces (N, along rho_i; zero on free legs) */
  /* --- acceleration stages --------------------------------------------------------------------- */
  double a[F3R_MAX_Q];     /* accelerations: vdot, or from udot by the loop closure (closed) */
  double R[F3R_MAX_Q];     /* M a + h + k - Q, and - G^T lambda where lambda is given (open) */
  double lambda[F3R_NCON]; /* multipliers: the constraint force on each loop (N) */
  double gt_mu[F3R_MAX_Q]; /* open, with mu: G^T mu */
  double gv[F3R_NCON];     /* open, with mu: G v */
  /* --- energy stage -------------------------------------------------------------------------- */
  double kinetic;   /* T = v^T M v / 2 (J) */
  double potential; /* V = eta^T K eta / 2 (J) */
  /* --- counters ------------------------------------------------------------------------------ */
  long sincos_pairs; /* sin/cos pairs evaluated into this data since it was cleared */
} f3r_data;

#endif
