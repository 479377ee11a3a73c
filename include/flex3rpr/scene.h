/* f3r_scene: everything one run asks for, as a plain struct with documented defaults.
 * f3r_default_scene() gives Table I of the paper with the conventions of docs/model.md,
 * rigid links, no inputs, the minimal formulation on IDA at rtol 2e-7; a caller (or the YAML loader) changes only what it needs.
 * All quantities are SI: m, kg, s, N, rad. */
#ifndef FLEX3RPR_SCENE_H
#define FLEX3RPR_SCENE_H

#include <stddef.h>

#include "flex3rpr/coords.h"
#include "flex3rpr/kinds.h"
#include "flex3rpr/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  F3R_LINK_RIGID = 0,
  F3R_LINK_FIXED_PINNED = F3R_BEAM_FIXED_PINNED,
  F3R_LINK_FIXED_FREE = F3R_BEAM_FIXED_FREE
} f3r_link_model;

typedef enum {
  F3R_FORMULATION_DAE = 0,     /* redundant coordinates + multipliers, GGL index-2 */
  F3R_FORMULATION_MINIMAL = 1, /* platform pose + modal coordinates, implicit ODE */
  F3R_FORMULATION_INDEX3 = 2   /* redundant coordinates + multipliers, plain index 3: for external
                                * solvers (MEBDFI, RADAU5); a simulation rejects it */
} f3r_formulation;

typedef enum {
  F3R_INTEGRATOR_IDA = 0,  /* SUNDIALS IDA: variable-order BDF, implicit (both formulations) */
  F3R_INTEGRATOR_ERK = 1,  /* SUNDIALS ARKODE ERKStep, explicit Runge-Kutta (minimal only) */
  F3R_INTEGRATOR_DIRK = 2, /* SUNDIALS ARKODE ARKStep, diagonally implicit RK (minimal only) */
  /* registered integrators (kinds.h) take the values after the built-ins, up to this one: it
   * makes them values of the enum in C++ too, where a value outside the enum's range is
   * undefined */
  F3R_INTEGRATOR_LAST_KIND = F3R_INTEGRATOR_MAX_KINDS - 1
} f3r_integrator;

/* The enums' names as scene files, --set, the CLI and the node's parameters spell them ("rigid",
 * "dae", "ida"; names.c holds the one table). _name gives "unknown" for a value outside its
 * enum. _from_name sets *out and returns 0, or returns -1 for a name a scene cannot choose
 * (index3 has a name but is no choice). _names writes the choices for a message, "dae, minimal",
 * into list (terminated, cut short if size is too small) and returns list. */
const char* f3r_link_model_name(f3r_link_model model);
int f3r_link_model_from_name(const char* name, f3r_link_model* model);
const char* f3r_link_model_names(char* list, size_t size);
const char* f3r_formulation_name(f3r_formulation formulation);
int f3r_formulation_from_name(const char* name, f3r_formulation* formulation);
const char* f3r_formulation_names(char* list, size_t size);
const char* f3r_integrator_name(f3r_integrator integrator);
int f3r_integrator_from_name(const char* name, f3r_integrator* integrator);
const char* f3r_integrator_names(char* list, size_t size);

/* A scripted generalized force f(t). Breakpoints (step times, ramp and chirp ends, table
 * times) are integration stops: the integrator restarts there and never steps across a kink. */
typedef enum {
  F3R_INPUT_NONE = 0,
  F3R_INPUT_CONSTANT = 1, /* f = offset */
  F3R_INPUT_HARMONIC = 2, /* f = offset + amplitude cos(omega t + phase) */
  F3R_INPUT_STEP = 3,     /* f = before (t <= t0), after (t > t0) */
  F3R_INPUT_RAMP = 4,     /* from before t0 to after t1, linear in between */
  F3R_INPUT_CHIRP = 5,    /* offset + amplitude sin(2 pi (f0 tau + (f1 - f0) tau^2 / (2 T))),
                             tau = t - t0 in [0, T = t1 - t0]; offset outside */
  F3R_INPUT_TABLE = 6     /* piecewise linear through (time[k], value[k]); constant outside */
} f3r_input_kind;

#define F3R_MAX_TABLE 1024 /* the most entries a table may have */

typedef struct {
  f3r_input_kind kind;
  double offset;        /* N or N m: constant, harmonic and chirp offset */
  double amplitude;     /* N or N m: harmonic and chirp amplitude */
  double omega;         /* rad/s: harmonic */
  double phase;         /* rad: harmonic */
  double t0, t1;        /* s: step time (t0); ramp and chirp start and end */
  double before, after; /* step and ramp values before t0 and after (t1) */
  double f0, f1;        /* Hz: chirp start and end frequency */
  int table_size;       /* 2..F3R_MAX_TABLE entries in table_time and table_value */
  int table_hold;       /* 1: piecewise constant, value[k] on (time[k], time[k+1]] (a controller's
                     * held command); 0: piecewise linear */
  /* table_size entries each, one block owned by the scene (f3r_input_set_table, the loader,
   * f3r_scene_copy): NULL for an input without a table */
  double* table_time;
  double* table_value;
} f3r_input;

/* Index of a rigid generalized force in f3r_scene.inputs and in force vectors. */
enum {
  F3R_FORCE_RHO = F3R_Q_RHO,     /* 0..2: force along leg i on its piston (N) */
  F3R_FORCE_THETA = F3R_Q_THETA, /* 3..5: torque on cylinder i about A_i (N m) */
  F3R_FORCE_PLATFORM = F3R_Q_X,  /* 6, 7, 8: platform F_x (N), F_y (N), torque (N m) */
  F3R_RIGID_FORCES = F3R_Q_MODAL
};

#define F3R_MODES_AUTO (-1)
#define F3R_ACCURACY_MAX_ESCALATIONS 6 /* accuracy.escalations allowed */

/* Bits of f3r_scene.explicit_settings: what the scene file (or the caller) fixed itself, which
 * the accuracy knob (accuracy.h) keeps. */
enum {
  F3R_EXPLICIT_MODES = 1, /* << i: links[i].modes was given as a number */
  F3R_EXPLICIT_FORMULATION = 1 << 3,
  F3R_EXPLICIT_INTEGRATOR = 1 << 4,
  F3R_EXPLICIT_RTOL = 1 << 5,
  F3R_EXPLICIT_TABLE = 1 << 6,
  F3R_EXPLICIT_EXACT_KINEMATICS = 1 << 7,
  F3R_EXPLICIT_ATOL = 1 << 8,
  F3R_EXPLICIT_STATIC_CORRECTION = 1 << 9 /* << i: links[i].static_correction was given */
};

/* A fixed-free link's static correction: its tip-force and uniform-load shapes, or one shape of
 * both loads in a ratio, given or fitted to the mechanism's slowest modes (f3r_accuracy_resolve
 * fits it before the model is built). */
typedef enum { F3R_SHAPE_PAIR = 0, F3R_SHAPE_MIXED = 1, F3R_SHAPE_MIX_FIT = 2 } f3r_shape_mix;
#define F3R_SHAPE_MIX_LIMIT 100.0 /* |shape_mix| allowed; the fitted values are about -2 */

typedef struct {
  f3r_link_model model;
  int modes;                       /* 1..F3R_MAX_MODES for a flexible link, 0 for rigid,
                                        F3R_MODES_AUTO to let the model choose */
  double auto_tolerance;           /* modes: auto: static truncation target, default 1e-3 */
  double damping_ratio;            /* modal damping ratio of every mode, default 0 */
  double eta0[F3R_MAX_MODES];      /* initial modal coordinates (m): of the link's basis
                                      functions, its modes first, then its static shapes */
  double eta_rate0[F3R_MAX_MODES]; /* initial modal rates (m/s), the same functions */
  int static_correction; /* 1: the link's basis adds orthogonalised static shapes of the loads
                          * it carries to its modes (f3r_link_static_shapes of them), so
                          * modes + shapes <= F3R_MAX_MODES. Default 0; where the scene leaves it
                          * open, the accuracy knob may turn it on */
  f3r_shape_mix shape_mix_kind; /* fixed-free with static_correction: the two shapes (default),
                                 * or one, the tip force with shape_mix times a uniform load */
  double shape_mix;             /* q l / F of that one shape's loads (F3R_SHAPE_MIXED) */
} f3r_link_scene;

/* A simulated sensor (docs/scenes.md, sensors): off unless enabled. Sample k is taken at the first
 * update at or after t = k / rate; the reading reports sample k - delay. noise is the standard
 * deviation of additive Gaussian noise, resolution the quantum the reading is rounded to (0:
 * none); [0] and [1] are a sensor's two kinds of channel (encoders: stroke m, angle rad;
 * accelerometer: specific force m/s^2, angular rate rad/s; strain gauges: [0] only). */
#define F3R_SENSOR_MAX_DELAY 64 /* periods */
#define F3R_SENSOR_MAX_RATE 1e6 /* Hz */
typedef struct {
  int enabled;
  double rate;          /* Hz, default 1000 */
  int delay;            /* periods, 0..F3R_SENSOR_MAX_DELAY, default 0 */
  double noise[2];      /* standard deviations, default 0 */
  double resolution[2]; /* quanta, default 0 */
  int seed;             /* 0..2147483647, default 1 */
} f3r_sensor_scene;

/* Each sensor kind's settings, indexed as the kinds' table (kinds.h; sensors.h names the
 * built-ins: F3R_SENSOR_ENCODERS, _STRAIN, _ACCELEROMETER). */
typedef struct {
  f3r_sensor_scene kind[F3R_SENSOR_MAX_KINDS];
} f3r_sensors_scene;

/* A sensor's defaults (rate 1000 Hz, seed 1, no delay, noise or quantisation), enabled. */
void f3r_sensor_scene_defaults(f3r_sensor_scene* sensor);
/* Range checks of the enabled sensors; messages name "sensors.encoders.rate" and the range. */
f3r_status f3r_sensors_scene_validate(const f3r_sensors_scene* sensors, f3r_error* err);

typedef struct {
  /* geometry and materials (Table I) */
  double base_side;               /* |A_i A_j| (m), 0.66 */
  double platform_side;           /* b = |C_i C_j| (m), 0.1 */
  double platform_mass;           /* m_p (kg), 0.2 */
  double platform_inertia;        /* I_p about P (kg m^2); default m_p b^2 / 12 */
  double link_length;             /* l (m), 0.2 */
  double link_diameter;           /* solid round section (m), 0.010 */
  double link_density;            /* kg/m^3, 2270 */
  double link_youngs_modulus;     /* E (Pa), 73e9 */
  double cylinder_length;         /* L (m), 0.2 */
  double cylinder_inner_diameter; /* m, 0.014 */
  double cylinder_outer_diameter; /* m, 0.016 */
  double cylinder_density;        /* kg/m^3, 2270 */

  f3r_link_scene links[3];
  int exact_kinematics;   /* 1: keep the axial velocity -w theta_dot of a beam point (default 0) */
  double gravity[3];      /* m/s^2, world frame, default (0, 0, -9.81): no work in the plane */
  double payload_mass;    /* kg at P, default 0 */
  double payload_inertia; /* kg m^2 about P, default 0 */
  double friction_prismatic[3];  /* viscous, N s/m on rho_i, default 0 */
  double friction_revolute[3];   /* viscous, N m s on theta_i, default 0 */
  double actuator_lag;           /* s: first-order lag of the applied leg forces; 0 is off */
  int end_stops;                 /* 1: the stroke is hard: impacts at stroke_min and stroke_max */
  double stroke_min, stroke_max; /* m, default 0 and 0.2: the range of rho_i (geometry.stroke_min,
                                 * _max or effects.end_stops.min, max), the URDF's limits */
  double restitution;            /* coefficient of restitution of the stops, default 0.5 */

  /* initial state: platform pose (X_p, Y_p, phi_p) and its rate; deflections are in links[]
   * (within the F3R_STATE_* ranges below) */
  double platform_pose0[3];
  double platform_velocity0[3];

  /* scripted generalized forces, indexed by F3R_FORCE_* (modal forces come from the caller) */
  f3r_input inputs[F3R_RIGID_FORCES];

  /* solver */
  f3r_formulation formulation; /* default minimal */
  f3r_integrator integrator;   /* default ida */
  double rtol;                 /* default 2e-7: the cheapest 6 correct digits (scene.c) */
  double atol;                 /* default 2e-9 (m, m/s) */
  double max_step;             /* s; 0 means no limit */
  int max_order;               /* IDA's highest BDF order, 1..5 (2: A-stable, steps over undamped
                                * modes that nothing excites) */
  char table[48];              /* erk, dirk: the Butcher table by name; "" for the integrator's
                                * default (f3r_rk_tables) */

  /* accuracy knob (accuracy.h): requested end-effector accuracy (m), 0 for none */
  double accuracy;
  int accuracy_verify;        /* 1 (default): a run for a request is checked against a richer one
                             * (f3r_accuracy_check_scene); 0: the error is only estimated */
  int accuracy_escalations;   /* richer configurations tried after a check that misses, 0..6,
                             * default 3 */
  double accuracy_excitation; /* N: where commands come from outside (the node, Python's step),
                             * the knob sizes the model for steps of this size on the leg forces;
                             * 0 (default): limits.force */
  unsigned explicit_settings; /* F3R_EXPLICIT_* */

  /* limits of a command from outside (a controller through the node, flex3rpr.Sim.step): a
   * larger magnitude is refused (flex3rpr/session.h). Scripted inputs are the scene's own. */
  double limit_force;       /* N, a leg force or a platform force component, default 1000 */
  double limit_torque;      /* N m, a cylinder torque or the platform torque, default 100 */
  double limit_modal_force; /* N, a modal force, default 1000 */

  /* run */
  double duration;    /* s, default 0.5 */
  double output_step; /* s, default 1e-4 */
  int beam_points;    /* stations per link for beam outputs, default 11 */

  f3r_sensors_scene sensors; /* all off by default */
} f3r_scene;

/* The ranges of a scene's initial state, which a state set later keeps too (session.h). */
#define F3R_STATE_POSITION_LIMIT 1.0     /* m, |X_p| and |Y_p| */
#define F3R_STATE_ANGLE_LIMIT 1e3        /* rad, |phi_p| */
#define F3R_STATE_RATE_LIMIT 1e3         /* m/s and rad/s, each component of the platform's twist */
#define F3R_STATE_MODAL_LIMIT 0.1        /* m, a modal coordinate */
#define F3R_STATE_MODAL_RATE_LIMIT 100.0 /* m/s, a modal coordinate's rate */

/* Table I, rigid links, home pose (P = O, phi_p = 0), no inputs, minimal on IDA at rtol 2e-7. */
f3r_scene f3r_default_scene(void);

/* A scene owns its input tables; everything else is plain values. Ownership:
 * - f3r_default_scene gives a scene without tables; f3r_scene_load (on success: a failed load
 *   leaves *scene as it was), f3r_scene_copy and f3r_input_set_table give tables it owns.
 * - f3r_scene_free releases them (and turns table inputs into none); it is safe on any scene
 *   that came from these functions, and twice.
 * - A struct assignment `b = a` shares a's tables: b is a view, valid while a lives, and only a
 *   is freed. f3r_scene_copy is the deep copy, of the tables' real sizes only (a few kB). */
void f3r_scene_free(f3r_scene* scene);

/* Deep copy: dst is overwritten whole (free what it held first), with tables of its own. On
 * F3R_ERR_MEMORY dst holds no tables. */
f3r_status f3r_scene_copy(f3r_scene* dst, const f3r_scene* src, f3r_error* err);

/* The doubles src's tables take (2 * table_size of each table input), and the same deep copy
 * with the tables in storage (that many doubles), which the caller owns: a model keeps its
 * scene in its one buffer this way. Never f3r_scene_free such a copy. */
size_t f3r_scene_table_doubles(const f3r_scene* src);
void f3r_scene_copy_into(f3r_scene* dst, const f3r_scene* src, double* storage);

/* Gives input a table of its own (a copy of size entries of time and value), kind table, freeing
 * the one it held. size must be 2..F3R_MAX_TABLE (F3R_ERR_ARGUMENT); F3R_ERR_MEMORY leaves the
 * input as it was. */
f3r_status f3r_input_set_table(f3r_input* input, const double* time, const double* value, int size,
                               int hold, f3r_error* err);

/* Checks every field against its allowed range. The message names the field, the value and the
 * range, e.g. "links[1].modes: 25 is out of range 1..20". */
f3r_status f3r_scene_validate(const f3r_scene* scene, f3r_error* err);

/* The static shapes links.static_correction adds to a link of this model (3 fixed-free, 2
 * fixed-pinned, 0 rigid), and the number of modal coordinates of a link scene with a numeric
 * mode count: modes, plus those shapes when static_correction is on. */
int f3r_link_static_shapes(f3r_link_model model);
/* The functions a link's static correction adds to its modes: 0 without it, 1 for one mixed
 * shape (shape_mix), else f3r_link_static_shapes. */
int f3r_link_correction_functions(const f3r_link_scene* link);
int f3r_link_scene_functions(const f3r_link_scene* link);

/* The Butcher tables an integrator offers by name (those the benchmark measures), NULL-ended:
 * erk: ARKODE's FEHLBERG_13_7_8 (default), DORMAND_PRINCE_7_4_5, VERNER_8_5_6 and the pairs of
 * src/core/solve/erk_tables.c; dirk: ARKODE's KVAERNO_7_4_5 (default), ARK548L2SA_DIRK_8_4_5,
 * SDIRK_5_3_4. NULL for ida. */
const char* const* f3r_rk_tables(f3r_integrator integrator);

/* Reads a scene YAML file over the defaults, then validates it. Errors start with "path:line: ".
 * On success *scene is overwritten (free what it held first) and owns its tables; on error it is
 * left as it was. */
f3r_status f3r_scene_load(const char* path, f3r_scene* scene, f3r_error* err);

/* The same with an accuracy request from outside the file (a CLI flag, a node parameter): it
 * replaces accuracy.end_effector when > 0, before validation, so flexible links may leave their
 * modes to the knob. */
f3r_status f3r_scene_load_accuracy(const char* path, double accuracy, f3r_scene* scene,
                                   f3r_error* err);

/* What comes from outside the file: an accuracy request (> 0: replaces accuracy.end_effector) and
 * overrides "FIELD=VALUE", applied in order to the parsed document before it is read, so they pass
 * the same checks as the file; FIELD is the path a message names ("links[0].modes",
 * "effects.payload.mass"; "links.modes" sets every link), VALUE is YAML ("4", "fixed_free",
 * "[0, 0, -9.81]"). A missing section or field is added; "links[i]" on one mapping for all three
 * links turns it into three. An error about an override starts with "--set FIELD=VALUE: ". */
typedef struct {
  double accuracy;
  const char* const* overrides;
  int override_count;
} f3r_scene_options;

f3r_status f3r_scene_load_with(const char* path, const f3r_scene_options* options, f3r_scene* scene,
                               f3r_error* err);

/* Scene name of rigid generalized force `index` (F3R_FORCE_*), e.g. "rho_1", "platform_torque". */
const char* f3r_input_name(int index);

/* Value of a scripted input at time t. */
double f3r_input_value(const f3r_input* input, double t);

/* Highest frequency (Hz) the input carries: a harmonic's, a chirp's end frequency; 0 for the
 * others. */
double f3r_input_max_frequency(const f3r_input* input);

/* Times in (t_from, infinity) where the input has a kink or a jump, ascending; returns their
 * number (at most max). */
int f3r_input_breakpoints(const f3r_input* input, double* times, int max);

#ifdef __cplusplus
}
#endif
#endif
