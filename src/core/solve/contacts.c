/* The end stops' contacts at an event or a restart (contacts.h). */
#include "contacts.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "queries.h"

/* Slack of the complementarity tests: an impulse (N s), a rate (m/s), a force (N) and an
 * acceleration (m/s^2) this close to its bound meets it. The force roots fire further out
 * (F3R_STOP_FORCE_ROOT_OFFSET), so a leg whose root fired is never kept by this slack. */
#define IMPULSE_SLACK 1e-12
#define RATE_SLACK 1e-12
#define FORCE_SLACK 1e-10
#define ACCELERATION_SLACK 1e-9

static double stop_of(const f3r_model* m, int side) {
  return side < 0 ? m->stroke_min : m->stroke_max;
}

static int count_bits(unsigned mask) {
  int n = 0;
  for (; mask; mask &= mask - 1) ++n;
  return n;
}

/* The subsets of `all` (a mask of legs), `first` first, then by size, largest first: the order in
 * which the complementarity problems try their active sets. Returns their count (<= 8). */
static int subsets_in_order(unsigned all, unsigned first, unsigned order[8]) {
  int n = 0;
  order[n++] = first;
  for (int size = count_bits(all); size >= 0; --size)
    for (unsigned s = 0; s < 8; ++s)
      if ((s & ~all) == 0 && count_bits(s) == size && s != first) order[n++] = s;
  return n;
}

/* d rho_leg / d pose_j at q (the loop closure's rates for a unit pose rate). */
static void stroke_pose_jacobian(const f3r_model* m, const double* q, double B[3][3]) {
  for (int j = 0; j < 3; ++j) {
    double unit[F3R_MAX_Q] = {0.0};
    unit[F3R_Q_X + j] = 1.0;
    f3r_model_close_loop_rates(m, q, unit);
    for (int i = 0; i < 3; ++i) B[i][j] = unit[F3R_Q_RHO + i];
  }
}

/* Puts each leg with side[i] != 0 exactly on its stop by the least change of the platform's pose
 * (Newton on the loop closure, dp = B^T (B B^T)^-1 r over those legs' rows B of d rho / d pose),
 * then the dependent coordinates and rates of q and v follow. */
static f3r_status project_onto_stops(const f3r_model* m, const int* side, double* q, double* v) {
  int legs[3], k = 0;
  for (int i = 0; i < 3; ++i)
    if (side[i]) legs[k++] = i;
  if (!k) return F3R_OK;
  for (int iteration = 0;; ++iteration) {
    if (f3r_model_close_loops(m, q) != F3R_OK) return F3R_ERR_SINGULAR;
    double r[3], worst = 0.0;
    for (int c = 0; c < k; ++c) {
      r[c] = stop_of(m, side[legs[c]]) - q[F3R_Q_RHO + legs[c]];
      worst = fmax(worst, fabs(r[c]));
    }
    if (worst <= 1e-15) break;
    if (iteration == 8) return F3R_ERR_SINGULAR;
    double B[3][3], A[9];
    int piv[3];
    stroke_pose_jacobian(m, q, B);
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) {
        double sum = 0.0;
        for (int j = 0; j < 3; ++j) sum += B[legs[a]][j] * B[legs[b]][j];
        F3R_AT(A, k, a, b) = sum;
      }
    if (f3r_lu_factor(A, k, piv)) return F3R_ERR_SINGULAR;
    f3r_lu_solve(A, k, piv, r);
    for (int j = 0; j < 3; ++j)
      for (int c = 0; c < k; ++c) q[F3R_Q_X + j] += B[legs[c]][j] * r[c];
  }
  f3r_model_close_loop_rates(m, q, v);
  return F3R_OK;
}

/* Every leg in contact leaves its stop at F3R_RESTING_SPEED or more, at its rate in `rates` (nq
 * velocities), or rests on it: v (whose jump it is) becomes that, impulse[i] the impulse on leg i
 * (N s, along rho_i). */
static f3r_status settle(const f3r_model* m, const double* q, const int* side, const double* rates,
                         double* v, double* impulse, double* work) {
  int legs[3], count = 0;
  double leg_rates[3], p[3], after[F3R_MAX_Q];
  for (int i = 0; i < 3; ++i) {
    if (!side[i]) continue;
    const double leaving = -side[i] * rates[F3R_Q_RHO + i];
    leg_rates[count] = leaving >= F3R_RESTING_SPEED ? rates[F3R_Q_RHO + i] : 0.0;
    legs[count++] = i;
  }
  if (!count) return F3R_OK;
  if (f3r_impact(m, q, v, legs, count, leg_rates, after, p, work) != F3R_OK)
    return F3R_ERR_SINGULAR;
  memcpy(v, after, (size_t)m->nq * sizeof(double));
  for (int c = 0; c < count; ++c) impulse[legs[c]] = p[c];
  return F3R_OK;
}

/* The impact over the legs in contact (side[i] != 0; normal n_i = -side_i, into the stroke):
 * target[i] the least rate into the stroke after it, the complementarity problem's. Then it
 * settles: a leg that the impulses of its neighbours lift off slower than F3R_RESTING_SPEED falls
 * back at once, and each return would be another impact (a Zeno sequence, which the rest ends;
 * the forces then decide which legs stay, hold()). */
static f3r_status impact(const f3r_model* m, const double* q, const int* side, const double* target,
                         double* v, double* impulse, double* work) {
  unsigned contact = 0, pressing = 0;
  for (int i = 0; i < 3; ++i) {
    if (!side[i]) continue;
    contact |= 1u << i;
    if (-side[i] * v[F3R_Q_RHO + i] < target[i]) pressing |= 1u << i;
  }
  unsigned order[8];
  const int tries = subsets_in_order(contact, pressing, order);
  double after[F3R_MAX_Q];
  int k = 0;
  for (; k < tries; ++k) {
    int legs[3], count = 0;
    double rates[3], p[3];
    for (int i = 0; i < 3; ++i)
      if (order[k] >> i & 1u) rates[count] = -side[i] * target[i], legs[count++] = i;
    if (!count) {
      memcpy(after, v, (size_t)m->nq * sizeof(double));
    } else if (f3r_impact(m, q, v, legs, count, rates, after, p, work) != F3R_OK) {
      return F3R_ERR_SINGULAR;
    }
    int valid = 1;
    for (int c = 0; c < count; ++c) valid &= -side[legs[c]] * p[c] >= -IMPULSE_SLACK;
    for (int i = 0; i < 3; ++i)
      if ((contact & ~order[k]) >> i & 1u)
        valid &= -side[i] * after[F3R_Q_RHO + i] >= target[i] - RATE_SLACK;
    if (valid) break;
  }
  if (k == tries) return F3R_ERR_SINGULAR; /* no active set: the contacts are inconsistent */
  return settle(m, q, side, after, v, impulse, work);
}

/* Which of the legs at rest on a stop (mask resting) stay locked: their stop forces push, and
 * every one released accelerates into the stroke. Legs in `releasing` go first where both hold. */
static f3r_status hold(const f3r_model* m, double t, const double* held, const double* lag,
                       const double* q, const double* v, const int* side, unsigned resting,
                       unsigned releasing, int* locked, double* work) {
  for (int i = 0; i < 3; ++i) locked[i] = 0;
  if (!resting) return F3R_OK;
  double Q[F3R_MAX_Q];
  f3r_applied_forces(m, nextafter(t, INFINITY), held, q, v, lag, Q, NULL);
  unsigned order[8];
  const int tries = subsets_in_order(resting, resting & ~releasing, order);
  for (int k = 0; k < tries; ++k) {
    f3r_stop_locks locks = {{0, 0, 0}};
    for (int i = 0; i < 3; ++i)
      if (order[k] >> i & 1u) locks.side[i] = side[i];
    double f[3], a[F3R_MAX_Q];
    if (f3r_contact_accelerations(m, &locks, q, v, Q, f, a, work) != F3R_OK)
      return F3R_ERR_SINGULAR;
    int valid = 1;
    for (int i = 0; i < 3; ++i) {
      if (locks.side[i])
        valid &= -side[i] * f[i] >= -FORCE_SLACK;
      else if (resting >> i & 1u)
        valid &= -side[i] * a[F3R_Q_RHO + i] >= -ACCELERATION_SLACK;
    }
    if (!valid) continue;
    memcpy(locked, locks.side, sizeof locks.side);
    return F3R_OK;
  }
  return F3R_ERR_SINGULAR;
}

/* Step 1 of f3r_contacts_resolve: each leg's side in contact (0: none), the legs whose force root
 * fired (releasing) and those whose stop root fired (hit). */
static f3r_status contact_sides(const f3r_model* m, double t, const int* root_info, const double* q,
                                const int* locked, int* side, unsigned* releasing, f3r_error* err) {
  *releasing = 0;
  for (int i = 0; i < 3; ++i) {
    const double rho = q[F3R_Q_RHO + i];
    const int min_root = root_info && root_info[2 * i],
              max_root = root_info && root_info[2 * i + 1];
    side[i] = 0;
    if (locked[i]) {
      side[i] = locked[i];
      if (locked[i] < 0 ? min_root : max_root) *releasing |= 1u << i;
    } else if (min_root || rho <= m->stroke_min + F3R_CONTACT_GAP) {
      side[i] = -1;
    } else if (max_root || rho >= m->stroke_max - F3R_CONTACT_GAP) {
      side[i] = 1;
    }
    const double past = side[i] < 0 ? m->stroke_min - rho : side[i] > 0 ? rho - m->stroke_max : 0;
    if (past > F3R_STROKE_TOLERANCE)
      return f3r_error_set(err, F3R_ERR_SOLVER,
                           "end stop at t = %.9g: leg %d is %.3g m past its stop (rho_%d = %.12g "
                           "m, stroke [%g, %g] m); the last good state is kept",
                           t, i + 1, past, i + 1, rho, m->stroke_min, m->stroke_max);
  }
  return F3R_OK;
}

f3r_status f3r_contacts_resolve(const f3r_model* m, double t, const double* held, const double* lag,
                                const int* root_info, double* q, double* v, int* locked,
                                f3r_impact_window* window, f3r_impact_record* record, int* legs_hit,
                                double* energy_lost, double* work, f3r_error* err) {
  *legs_hit = 0;
  *energy_lost = 0.0;
  if (!m->end_stops) return F3R_OK;
  int side[3];
  unsigned releasing;
  f3r_status st = contact_sides(m, t, root_info, q, locked, side, &releasing, err);
  if (st != F3R_OK) return st;
  if (!side[0] && !side[1] && !side[2]) {
    locked[0] = locked[1] = locked[2] = 0;
    return F3R_OK;
  }
  if (project_onto_stops(m, side, q, v) != F3R_OK)
    return f3r_error_set(err, F3R_ERR_SINGULAR,
                         "end stop at t = %.9g: the legs cannot reach "
                         "their stops (the loop closure has no solution)",
                         t);
  /* the impact: each approaching free leg's least rate after it (a locked leg moves by the
   * integrator's error alone, 1e-10 m/s, which the settling removes) */
  int approaching = 0, first = -1;
  for (int i = 0; i < 3; ++i)
    if (side[i] && !locked[i] && -side[i] * v[F3R_Q_RHO + i] < -RATE_SLACK)
      approaching += 1, first = first < 0 ? i : first;
  double target[3] = {0.0, 0.0, 0.0}, impulse[3] = {0.0, 0.0, 0.0}, v_before[F3R_MAX_Q];
  memcpy(v_before, v, (size_t)m->nq * sizeof(double));
  if (approaching) {
    if (t - window->window_start > 1e-3) window->window_start = t, window->count = 0;
    const int chatter = ++window->count > F3R_MAX_IMPACTS_PER_MS;
    for (int i = 0; i < 3; ++i) {
      const double rebound = side[i] ? m->restitution * fmax(0.0, side[i] * v[F3R_Q_RHO + i]) : 0;
      target[i] = chatter || rebound < F3R_RESTING_SPEED ? 0.0 : rebound;
    }
    if (impact(m, q, side, target, v, impulse, work) != F3R_OK)
      return f3r_error_set(err, F3R_ERR_SINGULAR, "end stop at t = %.9g: singular impact", t);
    record->t = t;
    record->leg = first;
    record->at_max = side[first] > 0;
    record->rho = q[F3R_Q_RHO + first];
    record->rate_before = v_before[F3R_Q_RHO + first];
    record->rate_after = v[F3R_Q_RHO + first];
    record->impulse = impulse[first];
    record->kinetic_before = f3r_kinetic_energy(m, q, v_before);
    record->kinetic_after = f3r_kinetic_energy(m, q, v);
    memcpy(record->q, q, sizeof record->q);
    *legs_hit = approaching;
  } else {
    double rates[F3R_MAX_Q];
    memcpy(rates, v, (size_t)m->nq * sizeof(double));
    if (settle(m, q, side, rates, v, impulse, work) != F3R_OK)
      return f3r_error_set(err, F3R_ERR_SINGULAR, "end stop at t = %.9g: singular contact", t);
  }
  *energy_lost = f3r_kinetic_energy(m, q, v_before) - f3r_kinetic_energy(m, q, v);
  unsigned resting = 0;
  for (int i = 0; i < 3; ++i)
    if (side[i] && -side[i] * v[F3R_Q_RHO + i] <= RATE_SLACK) resting |= 1u << i;
  if (hold(m, t, held, lag, q, v, side, resting, releasing, locked, work) != F3R_OK)
    return f3r_error_set(err, F3R_ERR_SINGULAR, "end stop at t = %.9g: singular contact", t);
  return F3R_OK;
}

f3r_status f3r_contacts_check_strokes(const f3r_model* m, const double* q, double t,
                                      f3r_error* err) {
  if (!m->end_stops) return F3R_OK;
  for (int i = 0; i < 3; ++i) {
    const double rho = q[F3R_Q_RHO + i];
    const double past = fmax(rho - m->stroke_max, m->stroke_min - rho);
    if (past > F3R_STROKE_TOLERANCE)
      return f3r_error_set(err, F3R_ERR_SOLVER,
                           "leg %d left its stroke at t = %.9g: rho_%d = %.12g m is %.3g m past "
                           "its stop [%g, %g] m; the run stops rather than pass it",
                           i + 1, t, i + 1, rho, past, m->stroke_min, m->stroke_max);
  }
  return F3R_OK;
}
