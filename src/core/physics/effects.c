/* The scene's optional force effects, each a stage with its own derivatives. The model keeps a
 * list of the enabled ones only, so an effect that is off costs nothing in the residual.
 *
 * gravity (in-plane part of the gravity vector g; gravity along Z does no work). With e, n the
 * leg's axes, s = sum b_j eta_j, and the centres of mass A + L_c/2 e (cylinder),
 * A + (rho + l/2) e + s n (beam), P (platform and payload), Q = -dV_g/dq with V_g = -g . sum m r:
 *   Q_rho = m g.e,  Q_theta = (m_c L_c/2 + m (rho + l/2)) g.n - m s g.e,  Q_eta_j = m b_j g.n,
 *   Q_X, Q_Y = (m_p + m_payload) g_x, g_y.
 * joint friction (viscous): Q_rho_i = -c_p v_rho_i, Q_theta_i = -c_r v_theta_i.
 * modal damping: Q_eta_j = -2 zeta omega_j m eta_j', omega_j the clamped beam's frequency. */
#include <math.h>

#include "dense.h"
#include "effects.h"

/* --- gravity --------------------------------------------------------------------------------- */
static double cylinder_moment(const f3r_model* m) {
  return m->cylinder_mass * m->cylinder_length / 2.0;
}

static void gravity_add(const f3r_model* m, f3r_data* d, double* Q) {
  const double* q = d->q;
  const double gx = m->gravity[0], gy = m->gravity[1], mass = m->link_mass;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const double g_e = gx * k->c + gy * k->s, g_n = -gx * k->s + gy * k->c;
    Q[i] += mass * g_e;
    Q[F3R_Q_THETA + i] += (cylinder_moment(m) + mass * (q[i] + m->link_length / 2.0)) * g_n -
                          mass * k->mean_defl * g_e;
    const f3r_link_params* lp = &m->link[i];
    for (int j = 0; j < lp->modes; ++j) Q[lp->eta_index + j] += mass * lp->mean[j] * g_n;
  }
  Q[F3R_Q_X] += m->platform_mass * gx;
  Q[F3R_Q_Y] += m->platform_mass * gy;
}

static void gravity_add_dq(const f3r_model* m, const f3r_data* d, double scale, double* A, int ld) {
  const double* q = d->q;
  const double gx = m->gravity[0], gy = m->gravity[1], mass = m->link_mass;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const double g_e = gx * k->c + gy * k->s, g_n = -gx * k->s + gy * k->c;
    const int r = i, th = F3R_Q_THETA + i;
    /* de/dtheta = n, dn/dtheta = -e */
    F3R_AT(A, ld, r, th) += scale * mass * g_n;
    F3R_AT(A, ld, th, r) += scale * mass * g_n;
    F3R_AT(A, ld, th, th) +=
        scale * (-(cylinder_moment(m) + mass * (q[i] + m->link_length / 2.0)) * g_e -
                 mass * k->mean_defl * g_n);
    const f3r_link_params* lp = &m->link[i];
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      F3R_AT(A, ld, th, col) += scale * (-mass * lp->mean[j] * g_e);
      F3R_AT(A, ld, col, th) += scale * (-mass * lp->mean[j] * g_e);
    }
  }
}

const f3r_force_effect f3r_gravity_effect = {"gravity", gravity_add, gravity_add_dq, 0};

/* --- joint friction ---------------------------------------------------------------------------- */
static void friction_add(const f3r_model* m, f3r_data* d, double* Q) {
  const double* v = d->v;
  for (int n = 0; n < F3R_Q_LEG_JOINTS; ++n) Q[n] -= m->joint_friction[n] * v[n];
}

static void friction_add_dv(const f3r_model* m, const f3r_data* d, double scale, double* A,
                            int ld) {
  (void)d;
  for (int n = 0; n < F3R_Q_LEG_JOINTS; ++n) F3R_AT(A, ld, n, n) -= scale * m->joint_friction[n];
}

const f3r_force_effect f3r_friction_effect = {"joint_friction", friction_add, 0, friction_add_dv};

/* --- modal damping ------------------------------------------------------------------------------ */

static void damping_add(const f3r_model* m, f3r_data* d, double* Q) {
  const double* v = d->v;
  for (int n = F3R_Q_MODAL; n < m->nq; ++n) Q[n] -= m->modal_damping[n] * v[n];
}

static void damping_add_dv(const f3r_model* m, const f3r_data* d, double scale, double* A, int ld) {
  (void)d;
  for (int n = F3R_Q_MODAL; n < m->nq; ++n) F3R_AT(A, ld, n, n) -= scale * m->modal_damping[n];
}

const f3r_force_effect f3r_damping_effect = {"damping", damping_add, 0, damping_add_dv};

/* --- scripted inputs ------------------------------------------------------------------------------ */
/* Each input's force also into d->input, where the actuator lag (forces.c) reads its command. */
static void inputs_add(const f3r_model* m, f3r_data* d, double* Q) {
  const double t = d->t;
  double wave[F3R_RIGID_FORCES]; /* cos(omega t + phase), once per distinct harmonic */
  for (int n = 0; n < F3R_RIGID_FORCES; ++n) { /* an input that is off adds nothing */
    const f3r_input* in = &m->scene.inputs[n];
    const int source = m->wave_source[n];
    if (source < 0) {
      d->input[n] = in->kind != F3R_INPUT_NONE ? f3r_input_value(in, t) : 0.0;
      if (in->kind != F3R_INPUT_NONE) Q[n] += d->input[n];
      continue;
    }
    wave[n] = source == n ? cos(in->omega * t + in->phase) : wave[source];
    d->input[n] = in->offset + in->amplitude * wave[n]; /* as f3r_input_value sums it */
    Q[n] += d->input[n];
  }
}

const f3r_force_effect f3r_inputs_effect = {"inputs", inputs_add, 0, 0};

/* --- the list: every caller's one loop over the enabled effects -------------------------------- */

void f3r_effects_add_forces(const f3r_model* m, f3r_data* d, double* Q) {
  for (int e = 0; e < m->n_effects; ++e) m->effects[e]->add(m, d, Q);
}

int f3r_effects_have_derivatives(const f3r_model* m) {
  for (int e = 0; e < m->n_effects; ++e)
    if (m->effects[e]->add_dq || m->effects[e]->add_dv) return 1;
  return 0;
}

void f3r_effects_add_derivatives(const f3r_model* m, const f3r_data* d, double scale, double* dQ_dq,
                                 double* dQ_dv, int ld) {
  for (int e = 0; e < m->n_effects; ++e) {
    const f3r_force_effect* effect = m->effects[e];
    if (dQ_dq && effect->add_dq) effect->add_dq(m, d, scale, dQ_dq, ld);
    if (dQ_dv && effect->add_dv) effect->add_dv(m, d, scale, dQ_dv, ld);
  }
}

void f3r_model_compile_effects(f3r_model* m) {
  const f3r_scene* s = &m->scene;
  for (int i = 0; i < 3; ++i) {
    m->joint_friction[i] = s->friction_prismatic[i];
    m->joint_friction[F3R_Q_THETA + i] = s->friction_revolute[i];
    for (int j = 0; j < m->link[i].modes; ++j)
      m->modal_damping[m->link[i].eta_index + j] =
          2.0 * s->links[i].damping_ratio * m->link[i].omega_clamped[j] * m->link_mass;
  }
  for (int n = 0; n < F3R_RIGID_FORCES; ++n) {
    const f3r_input* in = &s->inputs[n];
    m->wave_source[n] = in->kind == F3R_INPUT_HARMONIC ? n : -1;
    for (int k = 0; k < n && m->wave_source[n] == n; ++k)
      if (m->wave_source[k] == k && s->inputs[k].omega == in->omega &&
          s->inputs[k].phase == in->phase)
        m->wave_source[n] = k;
  }
  m->n_effects = 0;
  int any_input = 0;
  for (int n = 0; n < F3R_RIGID_FORCES; ++n) any_input |= s->inputs[n].kind != F3R_INPUT_NONE;
  if (any_input) m->effects[m->n_effects++] = &f3r_inputs_effect;
  if (m->gravity[0] != 0.0 || m->gravity[1] != 0.0)
    m->effects[m->n_effects++] = &f3r_gravity_effect;
  int friction = 0, damping = 0;
  for (int i = 0; i < 3; ++i) {
    friction |= s->friction_prismatic[i] != 0.0 || s->friction_revolute[i] != 0.0;
    damping |= m->link[i].modes > 0 && s->links[i].damping_ratio != 0.0;
  }
  if (friction) m->effects[m->n_effects++] = &f3r_friction_effect;
  if (damping) m->effects[m->n_effects++] = &f3r_damping_effect;
}
