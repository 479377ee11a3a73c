/* f3r_data: everything one evaluation of the model computes, grouped by the stage of the
 * forward pass (forward.c) that fills it. A stage reads t, q, v and the fields of the stages
 * before it and writes its own fields once; everything after it reads them. So each leg's
 * trigonometry is evaluated once per evaluation, and a new force term is one stage and one
 * field. Private: the public (q, v) functions of stages.h run the stages they need into a local
 * f3r_data and read it.
 *
 * Conventions (../shared/MODEL.md, dynamics.c, constraints.c): per link, e = (c, s) along the
 * leg, n = (-s, c) across it, L = rho + l, w the tip deflection; C_i sits at
 * P + r_PC (cc, sc) with (cc, sc) = (cos, sin)(phi_i + phi_p). */
#ifndef FLEX3RPR_DATA_H
#define FLEX3RPR_DATA_H

#include "stages.h"

/* Legs whose beam root comes closer than this fraction of l to A_i are degenerate: there the
 * constraint Jacobian loses rank (det of the leg's 2x2 block is rho + l), and the loop closure
 * refuses them. A run stops long before, at the collapse guard (events.h,
 * F3R_COLLAPSE_LEG_FRACTION = 0.1); this bound only keeps the closure itself finite. */
#define F3R_CLOSURE_MIN_LEG_FRACTION 1e-3

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
  f3r_link_data link[3];
  /* --- position stage ------------------------------------------------------------------------ */
  double g[F3R_NCON]; /* loop-closure constraints g(q) (m); filled by f3r_fwd_position */
  /* --- velocity stage ------------------------------------------------------------------------ */
  double h[F3R_MAX_Q];    /* velocity-dependent forces h(q, v) = dM/dt v - dT/dq */
  double gamma[F3R_NCON]; /* (dG/dt) v, so that G a + gamma = 0 */
  /* --- force stage --------------------------------------------------------------------------- */
  double k[F3R_MAX_Q]; /* elastic forces dV/dq */
  double Q[F3R_MAX_Q]; /* applied generalized forces: held + effects (+ actuator lag) */
  double commanded[3]; /* leg forces commanded to the actuator lag (when n_lag = 3) */
  double power;        /* Q . v (W) */
  /* --- formulation stage --------------------------------------------------------------------- */
  double a[F3R_MAX_Q];     /* accelerations */
  double R[F3R_MAX_Q];     /* M a + h + k - Q */
  double lambda[F3R_NCON]; /* multipliers: the constraint force on each loop (N) */
  /* --- counters ------------------------------------------------------------------------------ */
  long sincos_pairs; /* sin/cos pairs evaluated into this data since it was cleared */
} f3r_data;

/* --- the stages (forward.c) -------------------------------------------------------------------- */
/* Position stage from the full coordinates q: trigonometry, mass and constraint blocks, g. */
void f3r_fwd_position(const f3r_model* m, const double* q, f3r_data* d);
/* Position stage of the minimal formulation: the platform pose and modal coordinates in q are
 * given; the loop closure fills rho_i in q and the legs' directions in d algebraically (no
 * atan2). theta_i in q are left as they are: f3r_fwd_leg_angles fills them when asked. Returns
 * F3R_ERR_SINGULAR when a leg cannot reach its joint. g is not filled (zero by construction). */
f3r_status f3r_fwd_position_closed(const f3r_model* m, double* q, f3r_data* d);
/* The leg strokes rho_i alone from the platform pose and modal coordinates in q, by the same
 * closure and arithmetic as f3r_fwd_position_closed (the same values to the last bit), without
 * its mass and constraint blocks: what the event roots, evaluated once a step, need. */
f3r_status f3r_fwd_leg_strokes(const f3r_model* m, const double* q, double rho[3]);
/* theta_i in q from the closed directions of the position stage, on the model's branch. */
void f3r_fwd_leg_angles(const f3r_model* m, const f3r_data* d, double* q);
/* Velocity stage from v (and q's modal coordinates): rates per link, h and gamma. */
void f3r_fwd_velocity(const f3r_model* m, const double* q, const double* v, f3r_data* d);
/* Velocity stage of the minimal formulation: the platform and modal rates in v are given; the
 * loop closure fills rho_i' and theta_i' in v (G v = 0), then as f3r_fwd_velocity. */
void f3r_fwd_velocity_closed(const f3r_model* m, const double* q, double* v, f3r_data* d);
/* Force stage: k, Q (the caller's held forces, the effects, the actuator lag states lag or
 * NULL), the commanded leg forces and the power Q . v. */
void f3r_fwd_forces(const f3r_model* m, double t, const double* held, const double* q,
                    const double* v, const double* lag, f3r_data* d);

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
/* Per link, the dependent block G_d = [e, L n - w e] of the constraint Jacobian (det L):
 *   x = G_d^{-1} V  (x's rho and theta entries from V's (x, y) per link),
 *   x = G_d^{-T} R  (the loop force (x, y) per link from R's rho and theta entries). */
void f3r_data_solve_dependent(const f3r_data* d, const double* V, double* x);
/* f3r_model_actuation_condition at q from the position stage's platform joints (model.c). */
double f3r_data_actuation_condition(const f3r_model* m, const f3r_data* d, const double* q);
void f3r_data_solve_dependent_transpose(const f3r_data* d, const double* R, double* lambda);

#endif
