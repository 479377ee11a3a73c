/* Scene to model: geometry, inertia, modal constants and the coordinate layout, computed once. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/beam_modes.h"
#include "flex3rpr/model.h"
#include "model_layout.h"
#include "effects.h"
#include "data.h"

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
  if (f3r_model_close_loops(m, q) != F3R_OK)
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

void f3r_model_destroy(f3r_model* model) { free(model); }

f3r_geometry f3r_model_geometry(const f3r_model* m) {
  f3r_geometry g = {.platform_radius = m->platform_radius,
                    .link_length = m->link_length,
                    .link_mass = m->link_mass,
                    .cylinder_mass = m->cylinder_mass,
                    .cylinder_length = m->cylinder_length,
                    .platform_mass = m->platform_mass,
                    .platform_inertia = m->platform_inertia,
                    .end_stops = m->end_stops,
                    .stroke_min = m->stroke_min,
                    .stroke_max = m->stroke_max};
  memcpy(g.base_joint, m->base_joint, sizeof g.base_joint);
  memcpy(g.platform_angle, m->platform_angle, sizeof g.platform_angle);
  return g;
}

int f3r_model_nq(const f3r_model* m) { return m->nq; }

int f3r_model_lag_states(const f3r_model* m) { return m->n_lag; }

const f3r_link_params* f3r_model_link(const f3r_model* m, int link) { return &m->link[link]; }

const f3r_scene* f3r_model_scene(const f3r_model* m) { return &m->scene; }

double f3r_model_tip_deflection(const f3r_model* m, const double* q, int link) {
  const f3r_link_params* lp = &m->link[link];
  double w = 0.0;
  for (int j = 0; j < lp->modes; ++j) w += lp->tip[j] * q[lp->eta_index + j];
  return w;
}

/* The closed-form loop closure and its rates are the minimal formulation's position and
 * velocity stages (forward.c). */
f3r_status f3r_model_close_loops(const f3r_model* m, double* q) {
  f3r_data d = {.z = q + F3R_Q_INDEPENDENT};
  const f3r_status st = f3r_forward(m, &d, F3R_FWD_POSITION_CLOSED);
  if (st != F3R_OK) return st;
  for (int i = 0; i < 3; ++i) q[F3R_Q_RHO + i] = d.q_closed[F3R_Q_RHO + i];
  f3r_fwd_leg_angles(m, &d, q);
  return F3R_OK;
}

void f3r_model_close_loop_rates(const f3r_model* m, const double* q, double* qdot) {
  f3r_data d = {.q = q, .u = qdot + F3R_Q_INDEPENDENT};
  f3r_forward(m, &d, F3R_FWD_POSITION | F3R_FWD_VELOCITY_CLOSED);
  for (int n = 0; n < F3R_Q_LEG_JOINTS; ++n) qdot[n] = d.v_closed[n];
}

void f3r_model_beam_point(const f3r_model* m, const double* q, int link, double xi,
                          double position[2], double* tangent_angle, double* deflection) {
  const f3r_link_params* lp = &m->link[link];
  const double theta = q[3 + link], c = cos(theta), s = sin(theta), l = m->link_length;
  double w = 0.0, slope = 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    double psi, dpsi;
    f3r_beam_basis_eval(&m->basis[link], j, xi, &psi, &dpsi, NULL);
    w += psi * q[lp->eta_index + j];
    slope += dpsi * q[lp->eta_index + j] / l;
  }
  const double along = q[link] + xi * l;
  position[0] = m->base_joint[link][0] + along * c - w * s;
  position[1] = m->base_joint[link][1] + along * s + w * c;
  if (tangent_angle) *tangent_angle = theta + atan(slope);
  if (deflection) *deflection = w;
}

void f3r_model_link_shape(const f3r_model* m, int link, int j, double xi, double* psi,
                          double* dpsi) {
  f3r_beam_basis_eval(&m->basis[link], j, xi, psi, dpsi, NULL);
}

const char* f3r_model_link_basis_name(const f3r_model* m, int link, char* text, size_t size) {
  const f3r_link_params* lp = &m->link[link];
  const int r = lp->modes - lp->static_shapes;
  if (lp->model == F3R_LINK_RIGID)
    snprintf(text, size, "rigid");
  else if (m->basis[link].mixed)
    snprintf(text, size, "%s, %d mode%s + 1 static shape (tip force + %.4g uniform load)",
             f3r_link_model_name(lp->model), r, r == 1 ? "" : "s", m->basis[link].mix);
  else if (lp->static_shapes)
    snprintf(text, size, "%s, %d mode%s + %d static shape%s", f3r_link_model_name(lp->model), r,
             r == 1 ? "" : "s", lp->static_shapes, lp->static_shapes == 1 ? "" : "s");
  else
    snprintf(text, size, "%s, %d mode%s", f3r_link_model_name(lp->model), r, r == 1 ? "" : "s");
  return text;
}

f3r_status f3r_model_initial_state(const f3r_model* m, double* q, double* v) {
  const f3r_scene* sc = &m->scene;
  memset(q, 0, F3R_MAX_Q * sizeof(double));
  memset(v, 0, F3R_MAX_Q * sizeof(double));
  for (int k = 0; k < 3; ++k) {
    q[F3R_Q_X + k] = sc->platform_pose0[k];
    v[F3R_Q_X + k] = sc->platform_velocity0[k];
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < m->link[i].modes; ++j) {
      q[m->link[i].eta_index + j] = sc->links[i].eta0[j];
      v[m->link[i].eta_index + j] = sc->links[i].eta_rate0[j];
    }
  const f3r_status st = f3r_model_close_loops(m, q);
  if (st != F3R_OK) return st;
  f3r_model_close_loop_rates(m, q, v);
  return F3R_OK;
}

/* Eigenvalues of a symmetric 3 x 3 matrix, by the trigonometric solution of its characteristic
 * cubic (Smith 1961); ascending in ev. */
static void symmetric_eigenvalues3(const double a[3][3], double ev[3]) {
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double tr = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
  const double p2 = (a[0][0] - tr) * (a[0][0] - tr) + (a[1][1] - tr) * (a[1][1] - tr) +
                    (a[2][2] - tr) * (a[2][2] - tr) + 2.0 * p1;
  const double p = sqrt(p2 / 6.0);
  if (p == 0.0) {
    ev[0] = ev[1] = ev[2] = tr;
    return;
  }
  double b[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) b[i][j] = (a[i][j] - (i == j ? tr : 0.0)) / p;
  const double det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                     b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                     b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
  const double r = fmax(-1.0, fmin(1.0, det / 2.0));
  const double phi = acos(r) / 3.0;
  ev[2] = tr + 2.0 * p * cos(phi);
  ev[0] = tr + 2.0 * p * cos(phi + 2.0 * M_PI / 3.0);
  ev[1] = 3.0 * tr - ev[0] - ev[2];
}

double f3r_model_actuation_condition(const f3r_model* m, const double* q) {
  f3r_data d;
  return f3r_data_actuation_condition(m, f3r_forward_at(m, q, NULL, F3R_FWD_POSITION, &d), q);
}

double f3r_data_actuation_condition(const f3r_model* m, const f3r_data* d, const double* q) {
  double J[3][3]; /* rows: force x, force y, moment / r_PC; column i: leg i */
  for (int i = 0; i < 3; ++i) {
    const double cx = m->platform_radius * d->link[i].cc, cy = m->platform_radius * d->link[i].sc;
    double ux = q[F3R_Q_X] + cx - m->base_joint[i][0], uy = q[F3R_Q_Y] + cy - m->base_joint[i][1];
    const double len = hypot(ux, uy);
    ux /= len;
    uy /= len;
    J[0][i] = ux;
    J[1][i] = uy;
    J[2][i] = (cx * uy - cy * ux) / m->platform_radius;
  }
  double JtJ[3][3], ev[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      JtJ[i][j] = J[0][i] * J[0][j] + J[1][i] * J[1][j] + J[2][i] * J[2][j];
  symmetric_eigenvalues3((const double(*)[3])JtJ, ev); /* ISO C before C2X: no implicit const */
  /* sigma_min from the determinant, which stays accurate where the smallest eigenvalue of J^T J
   * drowns in rounding: sigma_1 sigma_2 sigma_3 = |det J|. */
  const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                     J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                     J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
  const double sigma_max = sqrt(fmax(ev[2], 0.0)), sigma_mid = sqrt(fmax(ev[1], 0.0));
  const double cond = sigma_max * sigma_max * sigma_mid / fabs(det);
  return isfinite(cond) ? fmin(1e16, cond) : 1e16;
}
