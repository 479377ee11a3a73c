/* The layout of f3r_model, private to the core's layers, the tests, the benchmark and the peer
 * (flex3rpr_core_private); the CLI and the node see an opaque type (flex3rpr/model.h).
 *
 * A model is one allocation, laid out by f3r_model_create as MuJoCo lays out mjModel: this
 * struct, then the sized arrays its pointers point into (the scene's input tables, the
 * breakpoints, the links' modal constants, the modal damping). */
#ifndef FLEX3RPR_MODEL_LAYOUT_H
#define FLEX3RPR_MODEL_LAYOUT_H

#include "flex3rpr/model.h"
#include "beam_basis.h"

#ifdef __cplusplus
extern "C" {
#endif

struct f3r_data; /* the core's evaluation data (data.h) */

/* An optional force stage: adds its generalized forces at d's t, q and v to Q and, where they
 * depend on q or v, scale times their derivatives into a column-major A. A NULL derivative is
 * zero. d holds the forward pass's position stage at q (the legs' directions), so an effect
 * computes no trigonometry of its own. */
typedef struct {
  const char* name;
  void (*add)(const struct f3r_model* m, struct f3r_data* d, double* Q);
  void (*add_dq)(const struct f3r_model* m, const struct f3r_data* d, double scale, double* A,
                 int ld);
  void (*add_dv)(const struct f3r_model* m, const struct f3r_data* d, double scale, double* A,
                 int ld);
} f3r_force_effect;

#define F3R_MAX_EFFECTS 8

struct f3r_model {
  f3r_scene scene; /* the scene the model was built from (validated); its tables are in the
                    * model's buffer */

  /* geometry (docs/model.md) */
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

  f3r_link_params link[3]; /* modal constants: link[i].modes values each, in the buffer */
  f3r_beam_basis basis[3]; /* each flexible link's basis: its functions' coefficients */
  int exact_kinematics;

  /* breakpoints of the scripted inputs (s), ascending: integration stops (n_breakpoints values
   * in the buffer, room for every table time and shape end) */
  int n_breakpoints;
  double* breakpoints;

  int n_lag;                /* 3 with actuator lag (applied leg forces are states), else 0 */
  double lag_time_constant; /* s */

  /* coefficients of the effects (effects.c), copied from the scene so that the loop never reads it */
  double joint_friction[6]; /* viscous, per coordinate: rho_i (N s/m), theta_i (N m s) */
  double* modal_damping;    /* nq values; for modal coordinate n >= 9: 2 zeta omega_j m (N s/m) */
  /* per input: the first harmonic input with the same omega and phase (itself if none), whose
   * cosine it shares in an evaluation; -1 for an input that is not harmonic */
  int wave_source[F3R_RIGID_FORCES];

  /* end stops of the pistons (events.c): active only when end_stops is 1 */
  int end_stops;
  double stroke_min, stroke_max; /* limits of rho_i (m) */
  double restitution;            /* Newton's coefficient c: rho_i' -> -c rho_i' at a stop */

  /* each formulation's state vector y (residual.h), indexed by f3r_formulation: its size and
   * where its actuator lag states start (W follows them, last) */
  int state_size[3], lag_index[3];

  int nq;                 /* number of generalized coordinates */
  int n_independent;      /* 3 + sum r_i: platform pose and modal coordinates */
  double theta_branch[3]; /* leg directions at the scene's initial pose: branch of atan2 */
};

/* Index of the actuator lag states in y (valid when model->n_lag == 3). */
static inline int f3r_lag_index(const f3r_model* model, f3r_formulation form) {
  return model->lag_index[form];
}

#ifdef __cplusplus
}
#endif
#endif
