/* Scene to model: geometry, inertia, modal constants and the coordinate layout, computed once into
 * one allocation (model_layout.h); the accessors are model.c's. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "effects.h"
#include "flex3rpr/beam_modes.h"
#include "model_layout.h"
#include "position.h"

static const double kPlatformAngle[3] = {-M_PI / 6.0, M_PI / 2.0, 7.0 * M_PI / 6.0};

static int compare_doubles(const void* a, const void* b) {
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* Room for every input's breakpoints: a table's times, or at most two shape ends. */
static int breakpoint_room(const f3r_scene* scene) {
  return (int)f3r_scene_table_doubles(scene) / 2 + 2 * F3R_RIGID_FORCES;
}

static void collect_breakpoints(f3r_model* m) {
  int n = 0;
  const int max = breakpoint_room(&m->scene);
  for (int k = 0; k < F3R_RIGID_FORCES; ++k)
    n += f3r_input_breakpoints(&m->scene.inputs[k], m->breakpoints + n, max - n);
  qsort(m->breakpoints, (size_t)n, sizeof(double), compare_doubles);
  int unique = 0;
  for (int k = 0; k < n; ++k)
    if (m->breakpoints[k] > 0.0 && (unique == 0 || m->breakpoints[k] > m->breakpoints[unique - 1]))
      m->breakpoints[unique++] = m->breakpoints[k];
  m->n_breakpoints = unique;
}

/* The bodies: joint and platform geometry, the links' and cylinders' masses and inertias, the
 * platform's with its payload, and the effects' constants. */
static void fill_bodies(f3r_model* m) {
  const f3r_scene* scene = &m->scene;
  const double base_radius = scene->base_side / sqrt(3.0);
  m->platform_radius = scene->platform_side / sqrt(3.0);
  for (int i = 0; i < 3; ++i) {
    m->platform_angle[i] = kPlatformAngle[i];
    m->platform_direction[i][0] = cos(kPlatformAngle[i]);
    m->platform_direction[i][1] = sin(kPlatformAngle[i]);
    m->base_joint[i][0] = base_radius * cos(kPlatformAngle[i]);
    m->base_joint[i][1] = base_radius * sin(kPlatformAngle[i]);
  }
  const double l = scene->link_length, d = scene->link_diameter;
  m->link_length = l;
  m->link_mass = scene->link_density * M_PI * d * d / 4.0 * l;
  m->bending_stiffness = scene->link_youngs_modulus * M_PI * d * d * d * d / 64.0;
  const double ro = scene->cylinder_outer_diameter / 2.0, ri = scene->cylinder_inner_diameter / 2.0;
  const double Lc = scene->cylinder_length;
  const double cylinder_mass = scene->cylinder_density * M_PI * (ro * ro - ri * ri) * Lc;
  m->cylinder_inertia = cylinder_mass * (Lc * Lc / 3.0 + (ro * ro + ri * ri) / 4.0);
  m->cylinder_mass = cylinder_mass;
  m->cylinder_length = Lc;
  m->platform_inertia =
      scene->platform_inertia > 0.0
          ? scene->platform_inertia
          : scene->platform_mass * scene->platform_side * scene->platform_side / 12.0;
  /* A payload at P adds to the platform: a model constant, nothing in the residual. */
  m->platform_mass = scene->platform_mass + scene->payload_mass;
  m->platform_inertia += scene->payload_inertia;
  for (int k = 0; k < 3; ++k) m->gravity[k] = scene->gravity[k];
  m->n_lag = scene->actuator_lag > 0.0 ? 3 : 0;
  m->lag_time_constant = scene->actuator_lag;
  m->end_stops = scene->end_stops;
  m->stroke_min = scene->stroke_min;
  m->stroke_max = scene->stroke_max;
  m->restitution = scene->restitution;
  m->exact_kinematics = scene->exact_kinematics;
}

/* Mode counts are numbers here: `modes: auto`, or none under an accuracy request, is the
 * accuracy knob's to resolve (f3r_accuracy_resolve, above the model), so that building a model
 * never runs one. */
static f3r_status check_modes_resolved(const f3r_scene* scene, f3r_error* err) {
  for (int i = 0; i < 3; ++i) {
    const f3r_link_scene* L = &scene->links[i];
    if (L->model != F3R_LINK_RIGID && (L->modes == F3R_MODES_AUTO || L->modes == 0))
      return f3r_error_set(err, F3R_ERR_SCENE,
                           "links[%d].modes: left open (auto, or none under an accuracy request): "
                           "resolve it with f3r_accuracy_resolve before building the model",
                           i);
    if (L->static_correction && L->shape_mix_kind == F3R_SHAPE_MIX_FIT)
      return f3r_error_set(err, F3R_ERR_SCENE,
                           "links[%d].shape_mix: fit: resolve it with f3r_accuracy_resolve before "
                           "building the model",
                           i);
  }
  return F3R_OK;
}

/* The static shapes links[i].static_correction adds (beam_basis.h): fixed-free links carry the
 * platform joint's tip force and their own inertia as a uniform load; a pin takes no tip force,
 * so fixed-pinned links take the uniform and the linear load. The fixed-free linear load is
 * left out: it halves the basis error at one mode but doubles IDA's steps (its own frequency,
 * 6.7 kHz against 3.1 kHz), so the accuracy knob met every request faster without it
 * (docs/benchmarks/shape_choice.md). */
static unsigned correction_shapes(const f3r_link_scene* L) {
  if (!L->static_correction) return 0u;
  if (L->model == F3R_LINK_FIXED_FREE) return F3R_SHAPE_TIP_FORCE | F3R_SHAPE_UNIFORM_LOAD;
  return F3R_SHAPE_UNIFORM_LOAD | F3R_SHAPE_LINEAR_LOAD;
}

/* Whether link L's fixed-free correction is one mixed shape (beam_basis.h). */
static int mixed(const f3r_link_scene* L) {
  return L->static_correction && L->model == F3R_LINK_FIXED_FREE &&
         L->shape_mix_kind == F3R_SHAPE_MIXED;
}

/* An earlier link whose basis link i's would repeat (the same end, modes and shapes), or -1. A
 * basis with static shapes costs thousands of long double sin, cos and exp (beam_basis.c), and
 * the accuracy knob builds tens of models while it chooses. */
static int same_basis_as(const f3r_model* m, int i) {
  const f3r_link_scene* L = &m->scene.links[i];
  for (int j = 0; j < i; ++j) {
    const f3r_link_scene* K = &m->scene.links[j];
    if (K->model == L->model && K->modes == L->modes &&
        correction_shapes(K) == correction_shapes(L) && mixed(K) == mixed(L) &&
        (!mixed(L) || K->shape_mix == L->shape_mix))
      return j;
  }
  return -1;
}

/* Link i's basis (its r modes, then its static shapes) and each function's constants: the modes'
 * exactly as f3r_beam_mode_constants gives them, the shapes' from the Ritz step. */
static f3r_status fill_link_constants(f3r_model* m, int i, double* room, f3r_error* err) {
  const f3r_link_scene* L = &m->scene.links[i];
  f3r_link_params* lp = &m->link[i];
  f3r_beam_basis* b = &m->basis[i];
  const int same = same_basis_as(m, i);
  int built = 0;
  if (same >= 0)
    *b = m->basis[same]; /* the build is a function of these alone: the same numbers, once */
  else
    built = mixed(L)
                ? f3r_beam_basis_build_mixed(L->modes, L->shape_mix, b)
                : f3r_beam_basis_build((f3r_beam_end)lp->model, L->modes, correction_shapes(L), b);
  if (built == F3R_BASIS_NO_MEMORY)
    return f3r_error_set(err, F3R_ERR_MEMORY, "links[%d]: out of memory building its basis", i);
  if (built)
    return f3r_error_set(err, F3R_ERR_SCENE, "links[%d].modes: %d is out of range 1..%d", i,
                         L->modes, F3R_MAX_MODES - (f3r_link_scene_functions(L) - L->modes));
  lp->modes = b->count;
  lp->static_shapes = b->corrections;
  for (int j = b->count; j < f3r_link_scene_functions(L); ++j)
    if (L->eta0[j] != 0.0 || L->eta_rate0[j] != 0.0)
      return f3r_error_set(err, F3R_ERR_SCENE,
                           "links[%d].initial_deflection[%d]: the link keeps %d functions (%d "
                           "modes + %d static shapes): at %d modes the residual of a shape falls "
                           "under %g of it and the shape is dropped",
                           i, j, b->count, b->modes, b->shapes, b->modes, F3R_SHAPE_DROP_RATIO);
  double** arrays[] = {&lp->alpha, &lp->mean,      &lp->first_moment,
                       &lp->tip,   &lp->stiffness, &lp->omega_clamped};
  for (int a = 0; a < 6; ++a, room += lp->modes) *arrays[a] = room;
  const double l = m->link_length, EI_l3 = m->bending_stiffness / (l * l * l);
  for (int j = 0; j < lp->modes; ++j) {
    lp->alpha[j] = b->alpha[j];
    lp->mean[j] = b->mean[j];
    lp->first_moment[j] = b->first_moment[j];
    lp->tip[j] = b->tip[j];
    const double a2 = lp->alpha[j] * lp->alpha[j];
    if (j < b->modes) { /* int psi_j''^2 = alpha_j^4 (beam_modes.h) */
      lp->stiffness[j] = EI_l3 * a2 * a2;
      lp->omega_clamped[j] = a2 * sqrt(EI_l3 / m->link_mass);
    } else { /* the shape's Rayleigh quotient: its frequency alone in the clamped link */
      lp->stiffness[j] = EI_l3 * b->stiffness[j];
      lp->omega_clamped[j] = sqrt(b->stiffness[j]) * sqrt(EI_l3 / m->link_mass);
    }
  }
  return F3R_OK;
}

/* The coordinate layout (each link's modal coordinates after the 9 rigid ones: m->nq) and each
 * flexible link's basis, modal constants, stiffnesses and clamped frequencies. */
static f3r_status fill_links(f3r_model* m, double* room, f3r_error* err) {
  int next = 9;
  for (int i = 0; i < 3; ++i) {
    f3r_link_params* lp = &m->link[i];
    lp->model = m->scene.links[i].model;
    lp->modes = lp->static_shapes = 0;
    lp->eta_index = next;
    if (lp->model != F3R_LINK_RIGID) {
      const f3r_status st = fill_link_constants(m, i, room, err);
      if (st != F3R_OK) return st;
    }
    next += lp->modes;
    room += 6 * lp->modes;
  }
  m->nq = next;
  return F3R_OK;
}

/* Each formulation's state vector (residual.h): [q | v | multipliers | lag | W] or, minimal,
 * [z | u | lag | W]; the multipliers are lambda and mu (dae), lambda (index3). */
static void fill_state_layouts(f3r_model* m) {
  const f3r_formulation forms[3] = {F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL,
                                    F3R_FORMULATION_INDEX3};
  for (int k = 0; k < 3; ++k) {
    const f3r_formulation form = forms[k];
    const int multipliers = form == F3R_FORMULATION_DAE      ? 2 * F3R_NCON
                            : form == F3R_FORMULATION_INDEX3 ? F3R_NCON
                                                             : 0;
    const int motion =
        form == F3R_FORMULATION_MINIMAL ? 2 * m->n_independent : 2 * m->nq + multipliers;
    m->lag_index[form] = motion;
    m->state_size[form] = motion + m->n_lag + 1;
  }
}

/* The branch of each leg's direction is fixed by the scene's initial pose; the loop closure then
 * checks that the legs reach it. */
static f3r_status close_initial_pose(f3r_model* m, f3r_error* err) {
  const f3r_scene* scene = &m->scene;
  double q[F3R_MAX_Q] = {0};
  for (int k = 0; k < 3; ++k) q[F3R_Q_X + k] = scene->platform_pose0[k];
  for (int i = 0; i < 3; ++i) {
    const double* P = scene->platform_pose0;
    const double cx = P[0] + m->platform_radius * cos(m->platform_angle[i] + P[2]);
    const double cy = P[1] + m->platform_radius * sin(m->platform_angle[i] + P[2]);
    m->theta_branch[i] = atan2(cy - m->base_joint[i][1], cx - m->base_joint[i][0]);
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < m->link[i].modes; ++j)
      q[m->link[i].eta_index + j] = scene->links[i].eta0[j];
  double rho[3];
  if (f3r_fwd_leg_strokes(m, q, rho) != F3R_OK)
    return f3r_error_set(
        err, F3R_ERR_SCENE, "initial.platform_pose: (%g, %g, %g) cannot be reached by the legs",
        scene->platform_pose0[0], scene->platform_pose0[1], scene->platform_pose0[2]);
  return F3R_OK;
}

/* The doubles after the struct: the scene's tables, the breakpoints, six modal constants per
 * mode and the modal damping (nq). */
static size_t buffer_doubles(const f3r_scene* scene) {
  int modes = 0; /* at most: a nearly dependent static shape is dropped */
  for (int i = 0; i < 3; ++i) modes += f3r_link_scene_functions(&scene->links[i]);
  return f3r_scene_table_doubles(scene) + (size_t)breakpoint_room(scene) + 6 * (size_t)modes +
         (size_t)(F3R_Q_MODAL + modes);
}

/* Everything a model holds in one calloc'd block: the struct, then its arrays in the order of
 * buffer_doubles. */
static f3r_status build(const f3r_scene* source, f3r_model** out, f3r_error* err) {
  f3r_model* m = calloc(1, sizeof *m + buffer_doubles(source) * sizeof(double));
  if (!m) return f3r_error_set(err, F3R_ERR_MEMORY, "f3r_model_create: out of memory");
  double* room = (double*)(m + 1);
  f3r_scene_copy_into(&m->scene, source, room);
  room += f3r_scene_table_doubles(source);
  m->breakpoints = room;
  room += breakpoint_room(source);
  fill_bodies(m);
  f3r_status st = fill_links(m, room, err);
  m->modal_damping = room + 6 * (m->nq - F3R_Q_MODAL);
  if (st == F3R_OK) {
    collect_breakpoints(m);
    f3r_model_compile_effects(m);
    m->n_independent = m->nq - 6;
    fill_state_layouts(m);
    st = close_initial_pose(m, err);
  }
  if (st != F3R_OK) {
    free(m);
    return st;
  }
  *out = m;
  return F3R_OK;
}

f3r_status f3r_model_create(const f3r_scene* source, f3r_model** out, f3r_error* err) {
  if (!source || !out)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_model_create: NULL argument");
  *out = NULL;
  /* the source is checked first: the buffer's size follows from its tables and mode counts */
  f3r_status st = f3r_scene_validate(source, err);
  if (st == F3R_OK) st = check_modes_resolved(source, err);
  if (st != F3R_OK) return st;
  return build(source, out, err);
}
