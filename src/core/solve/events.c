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
      g[2 * i] = locked[i] < 0 ? stop_force[i] : 1.0;
      g[2 * i + 1] = locked[i] > 0 ? -stop_force[i] : 1.0;
    } else {
      g[2 * i] = m->end_stops ? rho[i] - m->stroke_min : 1.0;
      g[2 * i + 1] = m->end_stops ? m->stroke_max - rho[i] : 1.0;
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

f3r_status f3r_event_impact(const f3r_model* m, double t, const int* root_info, const double* q,
                            const double* v, f3r_impact_window* window, double* v_after,
                            f3r_impact_record* record, int* legs_hit, int* lock, double* work,
                            f3r_error* err) {
  int legs[3], at_max[3], count = 0;
  double impulse[3];
  *legs_hit = 0;
  for (int i = 0; i < 3; ++i) {
    lock[i] = 0;
    if (root_info[2 * i] || root_info[2 * i + 1]) {
      at_max[count] = root_info[2 * i + 1] != 0;
      legs[count++] = i;
    }
  }
  if (!count) return F3R_OK;
  if (t - window->window_start > 1e-3) {
    window->window_start = t;
    window->count = 0;
  }
  /* chatter, or a rebound too slow to leave the stop: the legs stop dead and lock (contact) */
  int resting = ++window->count > F3R_MAX_IMPACTS_PER_MS;
  f3r_status st =
      f3r_impact(m, q, v, legs, count, resting ? 0.0 : m->restitution, v_after, impulse, work);
  for (int c = 0; c < count && st == F3R_OK && !resting; ++c)
    if (fabs(v_after[legs[c]]) < F3R_RESTING_SPEED) {
      resting = 1;
      st = f3r_impact(m, q, v, legs, count, 0.0, v_after, impulse, work);
    }
  if (st != F3R_OK) return f3r_error_set(err, st, "end stop at t = %.9g: singular impact", t);
  for (int c = 0; c < count && resting; ++c) lock[legs[c]] = at_max[c] ? 1 : -1;
  record->t = t;
  record->leg = legs[0];
  record->at_max = at_max[0];
  record->rho = q[legs[0]];
  record->rate_before = v[legs[0]];
  record->rate_after = v_after[legs[0]];
  record->impulse = impulse[0];
  record->kinetic_before = f3r_kinetic_energy(m, q, v);
  record->kinetic_after = f3r_kinetic_energy(m, q, v_after);
  memcpy(record->q, q, sizeof record->q);
  *legs_hit = count;
  return F3R_OK;
}
