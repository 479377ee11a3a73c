/* The model's accessors (flex3rpr/model.h): its sizes, geometry, links and beam shapes; the
 * model is built by model_create.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_layout.h"

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

int f3r_state_size(const f3r_model* m, f3r_formulation form) { return m->state_size[form]; }

const f3r_link_params* f3r_model_link(const f3r_model* m, int link) { return &m->link[link]; }

const f3r_scene* f3r_model_scene(const f3r_model* m) { return &m->scene; }

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
