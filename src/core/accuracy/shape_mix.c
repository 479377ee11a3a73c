/* links[i].shape_mix: fit (scene.h): the ratio of a fixed-free link's two static loads that the
 * mechanism's slowest modes put on it, so that one shape of that ratio stands for the pair
 * (beam_basis.h, f3r_beam_basis_build_mixed).
 *
 * With the pair, the linearised mechanism's modes (linear.h) give each link's deflection beyond
 * its paper modes as a_tip t_tip + a_uniform t_uniform in the two shapes' residuals: a = V c for
 * the link's correction coordinates c and the basis's V. In its lowest group of modes (those
 * within 0.2 % of the lowest the link takes part in) the link's a points one way: mix is
 * a_uniform / a_tip of the principal direction of sum a a^T over the group, which a degenerate
 * pair of modes leaves unchanged. That mode's shape then lies in the span of the modes and the
 * one mixed shape, so the mixed basis keeps the pair's lowest frequency (the test checks it),
 * and its stiffer combination, whose own fast mode bounds IDA's step, is gone
 * (docs/benchmarks/fast_shapes.md). */
#include <math.h>
#include <string.h>

#include "accuracy_parts.h"
#include "flex3rpr/accuracy.h"
#include "flex3rpr/linear.h"
#include "model_layout.h"

/* Relative width of a group of modes, and the share of a mode's shape on a link's coordinates
 * that makes the link take part in it. */
#define GROUP_WIDTH 2e-3
#define LINK_SHARE 1e-2

/* The share of mode j's shape (column j of Phi) on link i's modal coordinates. */
static double link_share(const f3r_linear_model* lin, const f3r_model* m, int i, int j) {
  const f3r_link_params* lp = &m->link[i];
  const double* phi = lin->shapes + (size_t)j * lin->n;
  const int first = lp->eta_index - F3R_Q_INDEPENDENT;
  double on_link = 0.0, all = 0.0;
  for (int a = 0; a < lin->n; ++a) all += phi[a] * phi[a];
  for (int a = first; a < first + lp->modes; ++a) on_link += phi[a] * phi[a];
  return all > 0.0 ? on_link / all : 0.0;
}

/* Link i's load ratio over its lowest group of elastic modes into *mix; F3R_ERR_SCENE if the link
 * takes part in no elastic mode or its group loads no tip. */
static f3r_status link_mix(const f3r_linear_model* lin, const f3r_model* m, int i, double* mix,
                           f3r_error* err) {
  const f3r_beam_basis* b = &m->basis[i];
  const int r = b->modes, first = m->link[i].eta_index - F3R_Q_INDEPENDENT + r;
  const double top = lin->omega2[lin->n - 1];
  int start = -1;
  for (int j = 0; j < lin->n && start < 0; ++j)
    if (lin->omega2[j] > 1e-10 * top && link_share(lin, m, i, j) >= LINK_SHARE) start = j;
  if (start < 0)
    return f3r_error_set(err, F3R_ERR_SCENE,
                         "links[%d].shape_mix: fit: the link takes part in no elastic mode", i);
  double S[3] = {0.0, 0.0, 0.0}; /* sum a a^T: (tip, tip), (tip, uniform), (uniform, uniform) */
  const double edge = lin->omega2[start] * (1.0 + GROUP_WIDTH) * (1.0 + GROUP_WIDTH);
  for (int j = start; j < lin->n && lin->omega2[j] <= edge; ++j) {
    const double* phi = lin->shapes + (size_t)j * lin->n;
    double a[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k)
      for (int c = 0; c < b->corrections; ++c) a[k] += (double)b->V[k][c] * phi[first + c];
    S[0] += a[0] * a[0];
    S[1] += a[0] * a[1];
    S[2] += a[1] * a[1];
  }
  /* the larger eigenvalue's eigenvector of [[S0 S1] [S1 S2]]: (S1, lambda - S0) */
  const double half = 0.5 * (S[2] - S[0]);
  const double lambda = S[0] + half + hypot(half, S[1]);
  const double tip = fabs(S[1]) > 0.0 ? S[1] : (S[0] >= S[2] ? 1.0 : 0.0);
  const double uniform = fabs(S[1]) > 0.0 ? lambda - S[0] : (S[0] >= S[2] ? 0.0 : 1.0);
  if (!(fabs(tip) * F3R_SHAPE_MIX_LIMIT > fabs(uniform)))
    return f3r_error_set(err, F3R_ERR_SCENE,
                         "links[%d].shape_mix: fit: the slowest modes load the link with a "
                         "uniform load over %g times their tip force (allowed -%g..%g)",
                         i, F3R_SHAPE_MIX_LIMIT, F3R_SHAPE_MIX_LIMIT, F3R_SHAPE_MIX_LIMIT);
  *mix = uniform / tip;
  return F3R_OK;
}

f3r_status f3r_shape_mix_fit(const f3r_scene* scene, unsigned links, double mix[3],
                             f3r_error* err) {
  f3r_scene pair = *scene; /* a view: the tables are scene's */
  for (int i = 0; i < 3; ++i) {
    mix[i] = 0.0;
    if (!(links >> i & 1)) continue;
    const f3r_link_scene* L = &scene->links[i];
    if (L->model != F3R_LINK_FIXED_FREE || !L->static_correction)
      return f3r_error_set(err, F3R_ERR_ARGUMENT,
                           "links[%d].shape_mix: fit needs model fixed_free and "
                           "static_correction true",
                           i);
    pair.links[i].shape_mix_kind = F3R_SHAPE_PAIR;
  }
  for (int i = 0; i < 3; ++i) /* a fitted link the call leaves out is fitted with the pair */
    if (pair.links[i].shape_mix_kind == F3R_SHAPE_MIX_FIT)
      pair.links[i].shape_mix_kind = F3R_SHAPE_PAIR;
  f3r_model* m = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = f3r_model_create(&pair, &m, err);
  if (st == F3R_OK) st = f3r_linearise(m, &lin, err);
  for (int i = 0; i < 3 && st == F3R_OK; ++i)
    if ((links >> i & 1) && m->basis[i].shapes == 2) /* else one shape is left: nothing to mix */
      st = link_mix(lin, m, i, &mix[i], err);
  f3r_linear_destroy(lin);
  f3r_model_destroy(m);
  return st;
}

unsigned f3r_shape_mix_open(const f3r_scene* s) {
  unsigned open = 0;
  for (int i = 0; i < 3; ++i)
    if (s->links[i].static_correction && s->links[i].shape_mix_kind == F3R_SHAPE_MIX_FIT)
      open |= 1u << i;
  return open;
}

f3r_status f3r_shape_mix_set_fitted(const f3r_scene* at, unsigned links, f3r_scene* out,
                                    double* mix, f3r_error* err) {
  double fitted[3];
  const f3r_status st = f3r_shape_mix_fit(at, links, fitted, err);
  for (int i = 0; i < 3 && st == F3R_OK; ++i)
    if (links >> i & 1) {
      out->links[i].shape_mix_kind = F3R_SHAPE_MIXED;
      out->links[i].shape_mix = fitted[i];
    }
  if (mix) memcpy(mix, fitted, sizeof fitted);
  return st;
}
