/* f3r_data: the inputs of one evaluation of the model and everything it computes, grouped by the
 * stage of the forward pass (forward.c) that fills it. The caller sets the inputs (as MuJoCo's
 * mjData holds qpos and qvel) and calls f3r_forward(m, d, what) with the stages it needs; a stage
 * reads the inputs and the fields of the stages before it and writes its own fields once. So each
 * leg's trigonometry is evaluated once per evaluation, and a new force term is one stage and one
 * field. Private: the public (q, v) functions of stages.h run the stages they need into a local
 * f3r_data and read it.
 *
 * Conventions (docs/model.md, dynamics.c, constraints.c): per link, e = (c, s) along the
 * leg, n = (-s, c) across it, L = rho + l, w the tip deflection; C_i sits at
 * P + r_PC (cc, sc) with (cc, sc) = (cos, sin)(phi_i + phi_p). */
#ifndef FLEX3RPR_DATA_H
#define FLEX3RPR_DATA_H

#include "model_layout.h"
#include "stages.h"

/* A small kernel called once per link or column in a hot loop, inlined whatever the compiler's
 * estimate: as calls, their arguments and results went through memory. */
#if defined(__GNUC__)
#define F3R_INLINE static inline __attribute__((always_inline))
#else
#define F3R_INLINE static inline
#endif

/* Legs whose beam root comes closer than this fraction of l to A_i are degenerate: there the
 * constraint Jacobian loses rank (det of the leg's 2x2 block is rho + l), and the loop closure
 * refuses them. A run stops long before, at the collapse guard (events.h,
 * F3R_COLLAPSE_LEG_FRACTION = 0.1); this bound only keeps the closure itself finite. */
#define F3R_CLOSURE_MIN_LEG_FRACTION 1e-3

/* The stages of the forward pass, a bit set for f3r_forward. */
enum {
  F3R_FWD_POSITION = 1 << 0,        /* q -> per link trigonometry, blocks; g */
  F3R_FWD_POSITION_CLOSED = 1 << 1, /* z -> q_closed by the loop closure (instead of POSITION) */
  F3R_FWD_VELOCITY = 1 << 2,        /* v -> per link rates; h; gamma */
  F3R_FWD_VELOCITY_CLOSED = 1 << 3, /* u -> v_closed by G v = 0 (instead of VELOCITY) */
  F3R_FWD_FORCES = 1 << 4,          /* t, held, lag -> k, Q, commanded, power */
  F3R_FWD_ENERGY = 1 << 5           /* kinetic and potential energy */
};

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
  double g_theta[2]; /* dg_i/dtheta_i = L n - w e; dg_i/drho_i = e, dg_i/deta_j = tip_j n
                               * (fixed-free only), dg_i/dP = -I */
  double g_phi[2];   /* dg_i/dphi_p = r_PC (sc, -cc) */
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
  double k[F3R_MAX_Q]; /* elastic forces dV/dq */
  double Q[F3R_MAX_Q]; /* applied generalized forces: held + effects (+ actuator lag) */
  double commanded[3]; /* leg forces commanded to the actuator lag (when n_lag = 3) */
  double power;        /* Q . v (W) */
  /* --- energy stage -------------------------------------------------------------------------- */
  double kinetic;   /* T = v^T M v / 2 (J) */
  double potential; /* V = eta^T K eta / 2 (J) */
  /* --- formulation stage --------------------------------------------------------------------- */
  double a[F3R_MAX_Q];     /* accelerations */
  double R[F3R_MAX_Q];     /* M a + h + k - Q */
  double lambda[F3R_NCON]; /* multipliers: the constraint force on each loop (N) */
  /* --- counters ------------------------------------------------------------------------------ */
  long sincos_pairs; /* sin/cos pairs evaluated into this data since it was cleared */
} f3r_data;

/* --- the forward pass (forward.c) ------------------------------------------------------------- */
/* Runs the stages in `what` (F3R_FWD_*) on the inputs in d, in order. Returns F3R_ERR_SINGULAR
 * when the closed position stage finds a leg that cannot reach its joint, else F3R_OK. */
f3r_status f3r_forward(const f3r_model* m, f3r_data* d, unsigned what);
/* A cleared d with inputs q and v (either may be NULL when no stage asked for reads it), through
 * the stages in `what`, for the public (q, v) functions of stages.h; returns d. */
const f3r_data* f3r_forward_at(const f3r_model* m, const double* q, const double* v, unsigned what,
                               f3r_data* d);
/* The leg strokes rho_i alone from the platform pose and modal coordinates in q, by the same
 * closure and arithmetic as the closed position stage (the same values to the last bit), without
 * its mass and constraint blocks: what the event roots, evaluated once a step, need. */
f3r_status f3r_fwd_leg_strokes(const f3r_model* m, const double* q, double rho[3]);
/* theta_i in q from the closed directions of the position stage, on the model's branch. */
void f3r_fwd_leg_angles(const f3r_model* m, const f3r_data* d, double* q);

/* --- per-link kernels of the stages, beside their derivatives (dynamics.c, constraints.c) ------ */
/* The mass blocks of link i at stroke rho; its part of h (the velocity stage of link i in d). */
void f3r_link_mass_blocks(const f3r_model* m, int i, f3r_link_data* k, double rho);
void f3r_link_velocity_forces(const f3r_model* m, int i, f3r_data* d);
/* k of link i's coordinates (rho_i, theta_i: zero; eta_i) into k (nq). */
void f3r_link_elastic_forces(const f3r_model* m, int i, const double* q, double* k);
/* G's direction-dependent blocks of link i and its g rows (zero when `closed`: the closure
 * satisfies them); its gamma rows (the velocity stage of link i in d). */
void f3r_link_constraints(const f3r_model* m, int i, f3r_data* d, int closed);
void f3r_link_constraint_bias(const f3r_model* m, int i, f3r_data* d);
/* The energy stage: T and V from the position and velocity stages. */
void f3r_data_energies(const f3r_model* m, f3r_data* d);
/* Q (nq) += the effects' forces at t, q, v and the position stage in d; scale dQ/dq into dQ_dq
 * and scale dQ/dv into dQ_dv (leading dimension ld; either NULL to skip) (effects.c). */
void f3r_effects_add_forces(const f3r_model* m, const f3r_data* d, double* Q);
/* 1 when an effect has derivatives: only then do the Jacobians form dQ/dq and dQ/dv. */
int f3r_effects_have_derivatives(const f3r_model* m);
void f3r_effects_add_derivatives(const f3r_model* m, const f3r_data* d, double scale, double* dQ_dq,
                                 double* dQ_dv, int ld);

/* --- kernels on the position stage (dynamics.c, constraints.c) -------------------------------- */
void f3r_data_mass_times(const f3r_model* m, const f3r_data* d, const double* x, double* out);
void f3r_data_add_mass_matrix(const f3r_model* m, const f3r_data* d, double scale, double* A,
                              int ld);
void f3r_data_add_velocity_forces_dv(const f3r_model* m, const f3r_data* d, const double* q,
                                     double scale, double* A, int ld);
void f3r_data_constraint_times(const f3r_model* m, const f3r_data* d, const double* x, double* out);
void f3r_data_constraint_transpose_times(const f3r_model* m, const f3r_data* d, const double* y,
                                         double* out);
void f3r_data_add_constraint_jacobian(const f3r_model* m, const f3r_data* d, double scale,
                                      double* A, int ld);
void f3r_data_add_constraint_jacobian_transpose(const f3r_model* m, const f3r_data* d, double scale,
                                                double* A, int ld);
void f3r_data_add_constraint_transpose_times_dq(const f3r_model* m, const f3r_data* d,
                                                const double* y, double scale, double* A, int ld);
void f3r_data_add_constraint_times_dq(const f3r_model* m, const f3r_data* d, const double* x,
                                      double scale, double* A, int ld);
void f3r_data_add_constraint_bias_dq(const f3r_model* m, const f3r_data* d, const double* v,
                                     double scale, double* A, int ld);
void f3r_data_add_constraint_bias_dv(const f3r_model* m, const f3r_data* d, const double* v,
                                     double scale, double* A, int ld);
/* Link k's dependent block G_d = [e, L n - w e] of the constraint Jacobian (det L):
 *   (rho, theta) = G_d^{-1} (vx, vy):  theta = (n . V) / L,  rho = e . V + w theta;
 *   (lx, ly) = G_d^{-T} (r_rho, r_theta) = r_rho e + ((r_theta + w r_rho) / L) n. */
static inline void f3r_link_solve_dependent(const f3r_link_data* k, double vx, double vy,
                                            double* rho, double* theta) {
  const double c = k->c, s = k->s, w = k->w, len = k->len; /* read before rho, theta are written */
  const double th = (-s * vx + c * vy) / len;
  *rho = (c * vx + s * vy) + w * th;
  *theta = th;
}
static inline void f3r_link_solve_dependent_transpose(const f3r_link_data* k, double r_rho,
                                                      double r_theta, double* lx, double* ly) {
  const double c = k->c, s = k->s, along = r_rho, across = (r_theta + k->w * r_rho) / k->len;
  *lx = along * c - across * s;
  *ly = along * s + across * c;
}
/* G's column of mode j of a fixed-free link k: psi_j(1) n = (-tip_j s, tip_j c) (a fixed-pinned
 * link's modes vanish at the tip: no entry). The one spelling of it for G, G^T and the minimal
 * formulation's solves. */
static inline void f3r_link_modal_constraint(const f3r_link_params* lp, const f3r_link_data* k,
                                             int j, double* gx, double* gy) {
  *gx = -lp->tip[j] * k->s;
  *gy = lp->tip[j] * k->c;
}
/* x = scale G_d^{-1} V per link for the ncols columns of V (6 x ncols, (x, y) per link): x's rho
 * and theta rows (6 x ncols; x may be V). */
void f3r_data_solve_dependent(const f3r_data* d, const double* V, int ncols, double scale,
                              double* x);
/* f3r_model_actuation_condition at q from the position stage's platform joints (model.c). */
double f3r_data_actuation_condition(const f3r_model* m, const f3r_data* d, const double* q);

#endif
