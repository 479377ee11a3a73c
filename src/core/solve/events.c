/* The events of a run: end stops, the collapse guard, impacts and input breakpoints (events.h). */
#include "events.h"

#include <math.h>
#include <string.h>

#include "residual.h"
#include "queries.h"

int f3r_event_roots(const f3r_model* m, f3r_formulation form, const double* y, const int* locked,
                    const double* stop_force, double* g) {
  double rho[3]; /* the roots need the leg strokes alone */
  if (form == F3R_FORMULATION_MINIMAL) {
    double q[F3R_MAX_Q];
    memcpy(q + F3R_Q_INDEPENDENT, y, (size_t)m->n_independent * sizeof(double));
    if (f3r_fwd_leg_strokes(m, q, rho) != F3R_OK) return 1;
  } else {
    memcpy(rho, y, sizeof rho);
  }
  for (int i = 0; i < 3; ++i) {
    if (locked[i]) { /* its stop's force, which falls through zero where it would have to pull */
      const double push = -locked[i] * stop_force[i] + F3R_STOP_FORCE_ROOT_OFFSET;
      const double stop = locked[i] < 0 ? m->stroke_min : m->stroke_max;
      const double drift = F3R_LOCK_DRIFT - fabs(rho[i] - stop);
      g[2 * i] = locked[i] < 0 ? push : drift;
      g[2 * i + 1] = locked[i] > 0 ? push : drift;
    } else {
      g[2 * i] = m->end_stops ? rho[i] - m->stroke_min + F3R_STOP_ROOT_OFFSET : 1.0;
      g[2 * i + 1] = m->end_stops ? m->stroke_max - rho[i] + F3R_STOP_ROOT_OFFSET : 1.0;
    }
    g[F3R_COLLAPSE_ROOT + i] = rho[i] + (1.0 - F3R_COLLAPSE_LEG_FRACTION) * m->link_length;
  }
  return 0;
}

int f3r_event_next_breakpoint(const f3r_model* m, double t, double t_out, double* t_stop) {
  /* bisection for the first breakpoint after t (they are ascending) */
  int lo = 0, hi = m->n_breakpoints;
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (m->breakpoints[mid] > t)
      hi = mid;
    else
      lo = mid + 1;
  }
  if (lo == m->n_breakpoints || m->breakpoints[lo] > t_out) return 0;
  *t_stop = m->breakpoints[lo];
  return 1;
}

int f3r_event_collapsed_leg(const int* root_info) {
  for (int i = 0; i < 3; ++i)
    if (root_info[F3R_COLLAPSE_ROOT + i]) return i;
  return -1;
}

f3r_status f3r_event_collapse_error(const f3r_model* m, f3r_formulation form, const double* y,
                                    int leg, double t, f3r_error* err) {
  double q[F3R_MAX_Q], v[F3R_MAX_Q];
  if (f3r_state_to_full(m, form, y, q, v) != F3R_OK)
    return f3r_error_set(err, F3R_ERR_SINGULAR,
                         "leg %d collapsed at t = %.9g: the loop no longer closes; the last good "
                         "state is kept",
                         leg + 1, t);
  return f3r_error_set(
      err, F3R_ERR_SINGULAR,
      "leg %d collapsed at t = %.9g: rho_%d + l = %.4g m reached the guard %.2g l, "
      "where the beam's root nears A_%d and the loop closure degenerates; the "
      "last good state is kept",
      leg + 1, t, leg + 1, q[leg] + m->link_length, F3R_COLLAPSE_LEG_FRACTION, leg + 1);
}
