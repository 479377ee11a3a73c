/* f3r_model: built once from a scene, then read-only. Several simulations may share one model.
 *
 * Generalized coordinates q (paper eq. 19 order), nq = 9 + sum of the links' mode counts:
 *   q[0..2] rho_i   stroke |A_i B_i| (m)
 *   q[3..5] theta_i direction of leg i from +X at A_i (rad)
 *   q[6..8] X_p, Y_p, phi_p platform pose (m, m, rad)
 *   q[9..]  eta of link 1 (link_modes[0] values), then link 2, then link 3 (m)
 * A rigid link contributes no modal coordinates. */
#ifndef FLEX3RPR_MODEL_H
#define FLEX3RPR_MODEL_H

#include "flex3rpr/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define F3R_MAX_Q (9 + 3 * F3R_MAX_MODES)
#define F3R_NCON 6 /* loop-closure constraints: (x, y) of the loop of each link */

typedef struct {
  f3r_link_model model;
  int modes;                           /* r_i (chosen by the model when the scene says auto) */
  int eta_index;                       /* index of this link's first modal coordinate in q */
  double alpha[F3R_MAX_MODES];         /* roots of the frequency equation */
  double mean[F3R_MAX_MODES];          /* int_0^1 psi_j dxi */
  double first_moment[F3R_MAX_MODES];  /* int_0^1 xi psi_j dxi */
  double tip[F3R_MAX_MODES];           /* psi_j(1): 0 for fixed-pinned */
  double stiffness[F3R_MAX_MODES];     /* EI/l^3 int psi_j''^2 (N/m), diagonal modal stiffness */
  double omega_clamped[F3R_MAX_MODES]; /* alpha_j^2 sqrt(EI/(m l^3)) (rad/s) */
} f3r_link_params;

struct f3r_model;
struct f3r_data; /* the core's evaluation data (src/core/physics/data.h): private */

/* An optional force stage: adds its generalized forces to Q and, where they depend on q or v,
 * scale times their derivatives into a column-major A. A NULL derivative is zero. d holds the
 * forward pass's position stage at q (the legs' directions), so an effect computes no
 * trigonometry of its own. */
typedef struct {
  const char* name;
  void (*add)(const struct f3r_model* m, double t, const double* q, const double* v,
              const struct f3r_data* d, double* Q);
  void (*add_dq)(const struct f3r_model* m, const double* q, const double* v,
                 const struct f3r_data* d, double scale, double* A, int ld);
  void (*add_dv)(const struct f3r_model* m, const double* q, const double* v, double scale,
                 double* A, int ld);
} f3r_force_effect;

#define F3R_MAX_EFFECTS 8

typedef struct f3r_model {
  f3r_scene scene; /* the scene the model was built from (validated) */

  /* geometry (../shared/MODEL.md) */
  double base_joint[3][2];         /* A_i (m) */
  double platform_angle[3];        /* phi_i of C_i on the platform: -pi/6, pi/2, 7pi/6 */
  double platform_radius;          /* r_PC (m) */
  double platform_direction[3][2]; /* (cos, sin) phi_i: C_i's direction at phi_p = 0 */

  /* inertia and stiffness */
  double link_length;       /* l (m) */
  double link_mass;         /* m (kg) */
  double bending_stiffness; /* EI (N m^2) */
  double cylinder_inertia;  /* I_c about A_i (kg m^2) */
  double cylinder_mass;     /* m_c (kg) */
  double cylinder_length;   /* L (m) */
  double platform_mass;     /* m_p plus the payload's mass (kg) */
  double platform_inertia;  /* I_p plus the payload's inertia (kg m^2) */
  double gravity[3];        /* m/s^2, world frame; only X and Y do work */

  /* the enabled force effects, in order (effects.c); disabled ones are absent */
  int n_effects;
  const f3r_force_effect* effects[F3R_MAX_EFFECTS];

  f3r_link_params link[3];
  int exact_kinematics;

  /* breakpoints of the scripted inputs (s), ascending: integration stops */
  int n_breakpoints;
  double breakpoints[F3R_RIGID_FORCES * F3R_MAX_TABLE];

  int n_lag;                /* 3 with actuator lag (applied leg forces are states), else 0 */
  double lag_time_constant; /* s */

  /* coefficients of the effects (effects.c), copied from the scene so that the loop never reads it */
  double joint_friction[6];        /* viscous, per coordinate: rho_i (N s/m), theta_i (N m s) */
  double modal_damping[F3R_MAX_Q]; /* per modal coordinate n >= 9: 2 zeta omega_j m (N s/m) */

  /* end stops of the pistons (events.c): active only when end_stops is 1 */
  int end_stops;
  double stroke_min, stroke_max; /* limits of rho_i (m) */
  double restitution;            /* Newton's coefficient c: rho_i' -> -c rho_i' at a stop */

  int nq;                 /* number of generalized coordinates */
  int n_independent;      /* 3 + sum r_i: platform pose and modal coordinates */
  double theta_branch[3]; /* leg directions at the scene's initial pose: branch of atan2 */
} f3r_model;

/* Builds a model from a scene (validating it first). Every flexible link's mode count must be a
 * number: modes left open (modes: auto, or none under an accuracy request) are an error, resolved
 * above the model by f3r_accuracy_resolve (accuracy.h). The result owns no pointers, so a model
 * is freed with f3r_model_destroy or simply copied. */
f3r_status f3r_model_create(const f3r_scene* scene, f3r_model** model, f3r_error* err);
void f3r_model_destroy(f3r_model* model);

/* Closed-form loop closure (../shared/MODEL.md): the full coordinates q (nq) from the platform
 * pose and the modal coordinates in q (which are read), filling rho and theta of each link.
 * Returns F3R_ERR_SINGULAR if a link would need rho_i + l <= 0. */
f3r_status f3r_model_close_loops(const f3r_model* model, double* q);

/* The scene's initial full coordinates q and rates v (F3R_MAX_Q each, zero beyond nq), closed. */
f3r_status f3r_model_initial_state(const f3r_model* model, double* q, double* v);

/* Rates of rho and theta in qdot (nq) from the platform and modal rates in qdot and the pose q. */
void f3r_model_close_loop_rates(const f3r_model* model, const double* q, double* qdot);

/* Beam station k of link i (k = 0..count-1, evenly spaced from B_i to C_i): position (x, y) in
 * the world and tangent angle of the deflected centre line, and the deflection w there. */
void f3r_model_beam_point(const f3r_model* model, const double* q, int link, double xi,
                          double position[2], double* tangent_angle, double* deflection);

/* Condition number (2-norm) of the actuation map of leg forces: column i is the unit vector
 * u_i from A_i to C_i and its moment about P, (C_i - P) x u_i / r_PC. Capped at 1e16. */
double f3r_model_actuation_condition(const f3r_model* model, const double* q);

/* Length of the state vector y of a formulation (the layouts: src/core/physics/residual.h). */
int f3r_state_size(const f3r_model* model, f3r_formulation form);

/* Tip deflection w_i(l) of link i (m), and its rate for given qdot. */
double f3r_model_tip_deflection(const f3r_model* model, const double* q, int link);

#ifdef __cplusplus
}
#endif
#endif
