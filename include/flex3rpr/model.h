/* f3r_model: built once from a scene, then read-only. Several simulations may share one model.
 *
 * Generalized coordinates q (paper eq. 19 order), nq = 9 + sum of the links' mode counts:
 *   q[0..2] rho_i   stroke |A_i B_i| (m)
 *   q[3..5] theta_i direction of leg i from +X at A_i (rad)
 *   q[6..8] X_p, Y_p, phi_p platform pose (m, m, rad)
 *   q[9..]  eta of link 1 (link[0].modes values: its r modes, then its static shapes), then
 *           link 2, then link 3 (m)
 * A rigid link contributes no modal coordinates. */
#ifndef FLEX3RPR_MODEL_H
#define FLEX3RPR_MODEL_H

#include "flex3rpr/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define F3R_MAX_Q (9 + 3 * F3R_MAX_MODES)
#define F3R_NCON 6 /* loop-closure constraints: (x, y) of the loop of each link */

/* A link's modal constants: arrays of `modes` values in the model's buffer, NULL for a rigid
 * link. */
typedef struct {
  f3r_link_model model;
  int modes;         /* modal coordinates: r_i paper modes (chosen above the model when the
                          * scene says auto), then static_shapes correction shapes */
  int static_shapes; /* links.static_correction's orthogonalised static shapes (0 without) */
  int eta_index;     /* index of this link's first modal coordinate in q */
  /* psi_j: function j of the link's basis, mass-orthonormal (int psi_i psi_j = delta_ij) with
   * a diagonal stiffness; the paper's modes first, then the static shapes (beam_basis.h) */
  double* alpha;         /* roots of the frequency equation; (int psi_j''^2)^(1/4) of a shape */
  double* mean;          /* int_0^1 psi_j dxi */
  double* first_moment;  /* int_0^1 xi psi_j dxi */
  double* tip;           /* psi_j(1): 0 for fixed-pinned */
  double* stiffness;     /* EI/l^3 int psi_j''^2 (N/m), diagonal modal stiffness */
  double* omega_clamped; /* alpha_j^2 sqrt(EI/(m l^3)) (rad/s) */
} f3r_link_params;

/* Opaque to the CLI and the node: they read it through the accessors below. The core's layers
 * see its layout in src/core/physics/model_layout.h. */
typedef struct f3r_model f3r_model;

/* The numbers the shells draw and check a robot with (docs/model.md). */
typedef struct {
  double base_joint[3][2];       /* A_i (m) */
  double platform_angle[3];      /* phi_i of C_i on the platform: -pi/6, pi/2, 7pi/6 */
  double platform_radius;        /* r_PC (m) */
  double link_length;            /* l (m) */
  double link_mass;              /* m (kg) */
  double cylinder_mass;          /* m_c (kg) */
  double cylinder_length;        /* L (m) */
  double platform_mass;          /* m_p plus the payload's mass (kg) */
  double platform_inertia;       /* I_p plus the payload's inertia (kg m^2) */
  int end_stops;                 /* 1: the stroke is hard */
  double stroke_min, stroke_max; /* limits of rho_i (m) */
} f3r_geometry;

f3r_geometry f3r_model_geometry(const f3r_model* model);

/* The number of generalized coordinates, and of actuator lag states (3 or 0). */
int f3r_model_nq(const f3r_model* model);
int f3r_model_lag_states(const f3r_model* model);

/* Link i's (0..2) model, mode count and modal constants. */
const f3r_link_params* f3r_model_link(const f3r_model* model, int link);

/* The scene the model was built from (validated), valid while the model lives. */
const f3r_scene* f3r_model_scene(const f3r_model* model);

/* Builds a model from a scene (validating it first). Every flexible link's mode count must be a
 * number: modes left open (modes: auto, or none under an accuracy request) are an error, resolved
 * above the model by f3r_accuracy_resolve (accuracy.h). The model is one allocation, its copy
 * of the scene included: f3r_model_destroy frees it. */
f3r_status f3r_model_create(const f3r_scene* scene, f3r_model** model, f3r_error* err);
void f3r_model_destroy(f3r_model* model);

/* Closed-form loop closure (docs/model.md): the full coordinates q (nq) from the platform
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

/* Function j (0 .. modes - 1) of link i's basis at xi in [0, 1]: psi_j and psi_j' (derivative
 * with respect to xi); either output may be NULL. The paper's mode shapes for j < modes -
 * static_shapes, the link's orthogonalised static shapes after them. */
void f3r_model_link_shape(const f3r_model* model, int link, int j, double xi, double* psi,
                          double* dpsi);

/* "fixed_free, 1 mode + 2 static shapes", "fixed_pinned, 3 modes" or "rigid" into text (size
 * bytes, terminated); returns text. */
const char* f3r_model_link_basis_name(const f3r_model* model, int link, char* text, size_t size);

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
