/* The accuracy knob's mode search (accuracy_parts.h): the fewest modes whose linearised
 * end-effector path stays within a target of a reference with more modes. Runs once before a
 * simulation, so it allocates freely. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accuracy_parts.h"
#include "flex3rpr/linear.h"

#define MAX_SAMPLES 20001
/* The linear path "leaves the initial pose far" beyond this share of the platform's side (or
 * this rotation): then the linearisation is checked by a nonlinear pilot. */
#define FAR_SHARE 0.1
#define FAR_ROTATION 0.05

static int lowest_modes(const f3r_scene* s, int i) { /* the initial state's highest mode */
  int low = 1;
  for (int j = 0; j < F3R_MAX_MODES; ++j)
    if (s->links[i].eta0[j] != 0.0 || s->links[i].eta_rate0[j] != 0.0) low = j + 1;
  return low;
}

/* The scene with fixed mode counts, no accuracy request: a model the caller must destroy. The
 * working scene is a view of base (its tables shared, scene.h), and the model copies them. */
f3r_status f3r_model_with_modes(const f3r_scene* base, const int modes[3], int exact_kinematics,
                                f3r_model** model, f3r_error* err) {
  f3r_scene s = *base;
  s.accuracy = 0.0;
  s.exact_kinematics = exact_kinematics;
  for (int i = 0; i < 3; ++i) s.links[i].modes = f3r_is_flexible(&s, i) ? modes[i] : 0;
  const unsigned fit = f3r_shape_mix_open(&s); /* the scene's own shape_mix: fit, at these counts */
  const f3r_status st = fit ? f3r_shape_mix_set_fitted(&s, fit, &s, NULL, err) : F3R_OK;
  return st == F3R_OK ? f3r_model_create(&s, model, err) : st;
}

/* The scene's inputs at the search's sampling, sampled with the first model that needs them: the
 * same for every model of the scene (the mode counts and kinematics do not change the inputs or
 * the actuator lag), and a tenth of the search's time when sampled per path. */
static const double* search_inputs(f3r_mode_search* ms, const f3r_model* model) {
  if (!ms->inputs) {
    ms->inputs = malloc((size_t)ms->count * F3R_RIGID_FORCES * sizeof(double));
    if (ms->inputs) f3r_linear_sample_inputs(model, ms->dt, ms->count, ms->inputs);
  }
  return ms->inputs; /* NULL without memory: the response samples them itself */
}

/* ms->inputs copied from a search of the same inputs and sampling (a copy costs a hundredth of
 * sampling them: 18 000 cosines on paper simulation 3); nothing without memory. */
static void share_inputs(const f3r_mode_search* same, f3r_mode_search* ms) {
  if (!same || !same->inputs || same->count != ms->count || same->dt != ms->dt) return;
  const size_t bytes = (size_t)ms->count * F3R_RIGID_FORCES * sizeof(double);
  ms->inputs = malloc(bytes);
  if (ms->inputs) memcpy(ms->inputs, same->inputs, bytes);
}

f3r_status f3r_linear_path(const f3r_scene* s, f3r_mode_search* ms, const int modes[3], int order,
                           double* pose, f3r_error* err) {
  f3r_model* model = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = f3r_model_with_modes(s, modes, 0, &model, err);
  if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
  if (st == F3R_OK)
    st = f3r_linear_response_sampled(lin, model, NULL, search_inputs(ms, model), ms->dt, ms->count,
                                     order, pose, NULL, err);
  f3r_linear_destroy(lin);
  f3r_model_destroy(model);
  return st;
}

f3r_status f3r_linear_kinematics(const f3r_scene* s, const f3r_mode_search* ms, const int modes[3],
                                 double* effect, f3r_error* err) {
  *effect = 0.0;
  f3r_model *model = NULL, *exact = NULL;
  f3r_linear_model* lin = NULL;
  double* pose = malloc((size_t)ms->count * 3 * sizeof(double));
  f3r_status st = pose ? F3R_OK : f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  if (st == F3R_OK) st = f3r_model_with_modes(s, modes, 0, &model, err);
  if (st == F3R_OK) st = f3r_model_with_modes(s, modes, 1, &exact, err);
  if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
  if (st == F3R_OK)
    st = f3r_linear_response_sampled(lin, model, exact, ms->inputs, ms->dt, ms->count, 1, pose,
                                     NULL, err);
  for (int k = 0; st == F3R_OK && k < ms->count; ++k)
    *effect = fmax(*effect, hypot(pose[3 * k], pose[3 * k + 1]));
  f3r_linear_destroy(lin);
  f3r_model_destroy(exact);
  f3r_model_destroy(model);
  free(pose);
  return st;
}

/* Largest end-effector distance between two pose paths (3 values a sample) over count samples. */
double f3r_max_distance(const double* a, const double* b, int count) {
  double worst = 0.0;
  for (int k = 0; k < count; ++k)
    worst = fmax(worst, hypot(a[3 * k] - b[3 * k], a[3 * k + 1] - b[3 * k + 1]));
  return worst;
}

/* A scene whose linear path never leaves its initial state: no scripted input, no initial rate
 * or deflection, no in-plane gravity. Its mode counts need no estimate. */
static int at_rest(const f3r_scene* s) {
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) {
    const f3r_input* in = &s->inputs[k];
    if (in->kind != F3R_INPUT_NONE && !(in->kind == F3R_INPUT_CONSTANT && in->offset == 0.0))
      return 0;
  }
  if (s->gravity[0] != 0.0 || s->gravity[1] != 0.0) return 0;
  for (int k = 0; k < 3; ++k)
    if (s->platform_velocity0[k] != 0.0) return 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < F3R_MAX_MODES; ++j)
      if (s->links[i].eta0[j] != 0.0 || s->links[i].eta_rate0[j] != 0.0) return 0;
  return 1;
}

static int any_flexible(const f3r_scene* s) {
  for (int i = 0; i < 3; ++i)
    if (f3r_is_flexible(s, i)) return 1;
  return 0;
}

/* The reference the mode count r is compared with: "larger r", three times r and three more, so
 * that a slowly converging fixed-free link is compared with modes well beyond it; 20 from r = 6.
 * Where every chosen link carries the static shapes, two times r and two more: that basis
 * converges at once (paper simulation 3 with fixed-free links and the pair, first-order paths:
 * r = 1, 2, 3 differ from 2 r + 2 modes by 2.88e-7, 3.11e-8 and 1.18e-8 m, from 12 modes by
 * 2.87e-7, 3.09e-8 and 1.18e-8), and the 6- and 9-mode references it spares were a third of
 * the knob's choosing there at 1e-5 m (9.5 -> 8.3 ms). */
static int reference_modes(const f3r_mode_search* ms, int r) {
  const int more = (ms->corrected & ms->chosen) == ms->chosen ? 2 * r + 2 : 3 * r + 3;
  return more < F3R_MAX_MODES ? more : F3R_MAX_MODES;
}

/* Forgets what was computed at the current sampling: the paths and the sampled inputs. */
static void memo_clear(f3r_mode_search* ms) {
  for (int k = 0; k < ms->memo_used; ++k) {
    free(ms->memo[k].pose);
    ms->memo[k].pose = NULL;
  }
  ms->memo_used = ms->memo_next = 0;
  free(ms->inputs);
  ms->inputs = NULL;
}

/* Safe to call twice (init frees on its own failure, and its caller frees again). */
void f3r_mode_search_free(f3r_mode_search* ms) {
  free(ms->ref);
  free(ms->path);
  ms->ref = ms->path = NULL;
  memo_clear(ms);
}

/* r on the chosen links (at least the initial state's, at most what leaves room for the static
 * shapes), the scene's counts on the others. */
static void uniform(const f3r_mode_search* ms, int r, int modes[3]) {
  for (int i = 0; i < 3; ++i) {
    const int at_least = r > ms->low[i] ? r : ms->low[i];
    modes[i] =
        (ms->chosen >> i & 1) ? (at_least < ms->most[i] ? at_least : ms->most[i]) : ms->fixed[i];
  }
}

/* The largest count any chosen link may take: the search's own reference. */
static int top_modes(const f3r_mode_search* ms) {
  int top = 1;
  for (int i = 0; i < 3; ++i)
    if ((ms->chosen >> i & 1) && ms->most[i] > top) top = ms->most[i];
  return top;
}

void f3r_mode_search_least(const f3r_mode_search* ms, int modes[3]) { uniform(ms, 1, modes); }

void f3r_mode_search_uniform(const f3r_mode_search* ms, int r, int modes[3]) {
  uniform(ms, r, modes);
}

int f3r_mode_search_found(const f3r_mode_search* ms, const int modes[3]) {
  for (int i = 0; i < 3; ++i)
    if ((ms->chosen >> i & 1) && modes[i] < ms->most[i]) return 1;
  return !ms->chosen;
}

f3r_status f3r_basis_cost(const f3r_scene* s, const int modes[3], double* cost, f3r_error* err) {
  *cost = 0.0;
  f3r_model* model = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = f3r_model_with_modes(s, modes, 0, &model, err);
  if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
  if (st == F3R_OK && lin->n > 0)
    *cost = sqrt(sqrt(fmax(lin->omega2[lin->n - 1], 0.0))) * f3r_model_nq(model);
  f3r_linear_destroy(lin);
  f3r_model_destroy(model);
  return st;
}

f3r_status f3r_mode_search_path(const f3r_scene* s, f3r_mode_search* ms, const int modes[3],
                                int order, double* pose, f3r_error* err) {
  const size_t bytes = (size_t)ms->count * 3 * sizeof(double);
  for (int k = 0; k < ms->memo_used; ++k)
    if (ms->memo[k].order == order && ms->memo[k].corrected == ms->corrected &&
        ms->memo[k].mixed == ms->mixed &&
        !memcmp(ms->memo[k].modes, modes, sizeof ms->memo[k].modes)) {
      memcpy(pose, ms->memo[k].pose, bytes);
      return F3R_OK;
    }
  ++ms->evaluations;
  const f3r_status st = f3r_linear_path(s, ms, modes, order, pose, err);
  if (st != F3R_OK) return st;
  int k = ms->memo_used; /* a free entry, or the oldest one */
  if (ms->memo_used < F3R_PATH_MEMO) {
    ++ms->memo_used;
  } else {
    k = ms->memo_next;
    ms->memo_next = (ms->memo_next + 1) % F3R_PATH_MEMO;
  }
  if (!ms->memo[k].pose) ms->memo[k].pose = malloc(bytes);
  if (ms->memo[k].pose) { /* without memory the memo just forgets */
    memcpy(ms->memo[k].modes, modes, sizeof ms->memo[k].modes);
    ms->memo[k].order = order;
    ms->memo[k].corrected = ms->corrected;
    ms->memo[k].mixed = ms->mixed;
    memcpy(ms->memo[k].pose, pose, bytes);
  } else {
    ms->memo[k].order = -1;
  }
  return F3R_OK;
}

static f3r_status reference_for(const f3r_scene* s, f3r_mode_search* ms, int r, f3r_error* err) {
  const int top = top_modes(ms), more = reference_modes(ms, r), R = more < top ? more : top;
  if (ms->ref_r == R) return F3R_OK;
  int modes[3];
  uniform(ms, R, modes);
  ms->ref_r = 0;
  const f3r_status st = f3r_mode_search_path(s, ms, modes, ms->order, ms->ref, err);
  if (st == F3R_OK) ms->ref_r = R;
  return st;
}

/* The extent and rotation of the reference path from its start; far when either leaves the pose. */
static void measure_extent(const f3r_scene* s, f3r_mode_search* ms) {
  for (int k = 0; k < ms->count; ++k) {
    const double* p = ms->ref + 3 * k;
    ms->extent = fmax(ms->extent, hypot(p[0] - ms->ref[0], p[1] - ms->ref[1]));
    ms->rotation = fmax(ms->rotation, fabs(p[2] - ms->ref[2]));
  }
  ms->far = ms->extent > FAR_SHARE * s->platform_side || ms->rotation > FAR_ROTATION;
}

/* The first sampling: the output step, fine enough for the fastest input, and at most
 * MAX_SAMPLES samples. */
static void sample_for_inputs(const f3r_scene* s, f3r_mode_search* ms) {
  double fastest = 0.0;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k)
    fastest = fmax(fastest, f3r_input_max_frequency(&s->inputs[k]));
  double h = s->output_step;
  if (fastest > 0.0) h = fmin(h, 1.0 / (20.0 * fastest));
  if (s->duration / h > MAX_SAMPLES - 1) h = s->duration / (MAX_SAMPLES - 1);
  ms->count = (int)ceil(s->duration / h - 1e-9) + 1;
  ms->dt = s->duration / (ms->count - 1);
}

/* The reference and scratch paths at the current sampling; 0 without memory. */
static int allocate_paths(f3r_mode_search* ms) {
  ms->ref = malloc((size_t)ms->count * 3 * sizeof(double));
  ms->path = malloc((size_t)ms->count * 3 * sizeof(double));
  return ms->ref && ms->path;
}

/* Hz: the lowest elastic frequency of the linear model at the least mode counts (0: none). */
static f3r_status first_elastic_frequency(const f3r_scene* s, const f3r_mode_search* ms,
                                          double* first, f3r_error* err) {
  *first = 0.0;
  int modes[3];
  uniform(ms, 1, modes);
  f3r_model* model = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = f3r_model_with_modes(s, modes, 0, &model, err);
  if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
  if (st == F3R_OK) {
    const double top = lin->omega2[lin->n - 1];
    for (int j = 0; j < lin->n && *first == 0.0; ++j)
      if (lin->omega2[j] > 1e-8 * top) *first = sqrt(lin->omega2[j]) / (2.0 * M_PI);
  }
  f3r_linear_destroy(lin);
  f3r_model_destroy(model);
  return st;
}

/* The second-order estimate, where the first-order path stays near the pose. Its remainder
 * oscillates with the vibration itself, so its sampling must resolve the first elastic mode too
 * (20 samples a period); a run too long for that is estimated as a far one. */
static f3r_status use_second_order(const f3r_scene* s, f3r_mode_search* ms, f3r_error* err) {
  double first;
  f3r_status st = first_elastic_frequency(s, ms, &first, err);
  if (st != F3R_OK) return st;
  double fine = ms->dt;
  if (first > 0.0) fine = fmin(fine, 1.0 / (20.0 * first));
  const double samples = ceil(s->duration / fine - 1e-9) + 1;
  if (samples > MAX_SAMPLES) {
    ms->far = 1;
    return F3R_OK;
  }
  if ((int)samples != ms->count) {
    memo_clear(ms); /* paths and inputs at the old sampling */
    ms->count = (int)samples;
    ms->dt = s->duration / (ms->count - 1);
    free(ms->ref);
    free(ms->path);
    if (!allocate_paths(ms)) return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  }
  ms->order = 2;
  ms->ref_r = 0; /* the first-order reference is no longer the one compared with */
  /* Vibration can drive an unactuated platform away at second order although the first-order
   * path stays put (free_vibration_long: 0.1 mm at first order, 4 cm at second order in 2 s);
   * then the path leaves the pose after all. */
  if ((st = reference_for(s, ms, 1, err)) != F3R_OK) return st;
  measure_extent(s, ms);
  if (ms->far) {
    ms->order = 1;
    ms->ref_r = 0;
  }
  return F3R_OK;
}

f3r_status f3r_mode_search_init(const f3r_scene* s, unsigned chosen, const f3r_mode_search* same,
                                f3r_mode_search* ms, f3r_error* err) {
  memset(ms, 0, sizeof *ms);
  sample_for_inputs(s, ms);
  share_inputs(same, ms);
  for (int i = 0; i < 3; ++i) {
    if (!f3r_is_flexible(s, i)) chosen &= ~(1u << i);
    ms->low[i] = lowest_modes(s, i);
    ms->fixed[i] = f3r_is_flexible(s, i) ? s->links[i].modes : 0;
    const int corrected = f3r_is_flexible(s, i) && s->links[i].static_correction;
    ms->corrected |= (unsigned)corrected << i;
    ms->mixed |= (unsigned)(corrected && s->links[i].shape_mix_kind == F3R_SHAPE_MIXED) << i;
    ms->most[i] = F3R_MAX_MODES - f3r_link_correction_functions(&s->links[i]);
  }
  ms->chosen = chosen;
  ms->order = 1;
  ms->at_rest = at_rest(s);
  if (ms->at_rest) return F3R_OK;
  if (!ms->chosen && !any_flexible(s)) {
    /* Nothing for a linear model to choose: the path is taken to leave the pose, so that a
     * solver whose relation nears its budget is checked by a pilot. */
    ms->far = 1;
    return F3R_OK;
  }
  if (!allocate_paths(ms)) {
    f3r_mode_search_free(ms);
    return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  }
  /* How far the first-order path goes decides the order of the estimate. */
  f3r_status st = reference_for(s, ms, 1, err);
  if (st != F3R_OK) return st;
  measure_extent(s, ms);
  if (ms->far) return F3R_OK;
  return use_second_order(s, ms, err);
}

/* The fewest modes whose linear path stays within target of its reference: uniform r on the
 * chosen links first (the cost grows with every link's r alike), then each link down while the
 * path stays within it (a link the inputs excite less needs fewer). */
f3r_status f3r_mode_search_run(const f3r_scene* s, f3r_mode_search* ms, double target, int modes[3],
                               double* estimate, f3r_error* err) {
  const int top = top_modes(ms);
  uniform(ms, top, modes);
  *estimate = 0.0;
  if (!ms->chosen) return F3R_OK;
  if (ms->at_rest) {
    uniform(ms, 1, modes);
    return F3R_OK;
  }
  f3r_status st = F3R_OK;
  double est = 0.0;
  int found = top;
  /* r = 1, 2, 3 each against its own reference (reference_modes); beyond, a bisection of 4..19
   * against 20 modes (17 with the static shapes), assuming the difference falls with r (it does,
   * if slowly, for both beam models and both bases). */
  for (int r = 1; r <= 3 && found == top; ++r) {
    int trial[3];
    uniform(ms, r, trial);
    if ((st = reference_for(s, ms, r, err)) != F3R_OK ||
        (st = f3r_mode_search_path(s, ms, trial, ms->order, ms->path, err)) != F3R_OK)
      return st;
    const double e = f3r_max_distance(ms->path, ms->ref, ms->count);
    if (e <= target) {
      memcpy(modes, trial, sizeof trial);
      est = e;
      found = r;
    }
  }
  if (found == top) {
    int lo = 4, hi = top; /* e(hi) <= target; top is the reference itself */
    double e_hi = 0.0;
    if ((st = reference_for(s, ms, top, err)) != F3R_OK) return st;
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      int trial[3];
      uniform(ms, mid, trial);
      if ((st = f3r_mode_search_path(s, ms, trial, ms->order, ms->path, err)) != F3R_OK) return st;
      const double e = f3r_max_distance(ms->path, ms->ref, ms->count);
      if (e <= target) {
        hi = mid;
        e_hi = e;
      } else {
        lo = mid + 1;
      }
    }
    found = hi;
    est = e_hi;
    uniform(ms, found, modes);
  }
  if (found == top) {
    *estimate = 0.0;
    return F3R_OK;
  }
  /* Far from the initial pose the first-order path cannot see what unequal links do to the
   * nonlinear motion (free_vibration_long: 6/4/5 modes drift 1 cm from 20 in 2 s, uniform 4..12
   * within 0.1 mm), so the counts stay uniform there. */
  for (int i = 0; i < 3 && !ms->far; ++i) { /* against the same reference */
    if (!(ms->chosen >> i & 1)) continue;
    while (modes[i] > ms->low[i]) {
      --modes[i];
      if ((st = f3r_mode_search_path(s, ms, modes, ms->order, ms->path, err)) != F3R_OK) return st;
      const double e = f3r_max_distance(ms->path, ms->ref, ms->count);
      if (e > target) {
        ++modes[i];
        break;
      }
      est = e;
    }
  }
  *estimate = est;
  return F3R_OK;
}

f3r_status f3r_mode_search_fits(const f3r_scene* s, f3r_mode_search* ms, int r, double target,
                                int* fits, f3r_error* err) {
  *fits = 0;
  int trial[3];
  uniform(ms, r, trial);
  f3r_status st = reference_for(s, ms, r, err);
  if (st == F3R_OK) st = f3r_mode_search_path(s, ms, trial, ms->order, ms->path, err);
  if (st == F3R_OK) *fits = f3r_max_distance(ms->path, ms->ref, ms->count) <= target;
  return st;
}

f3r_status f3r_accuracy_modes(const f3r_scene* scene, unsigned chosen, double target, int modes[3],
                              double* estimate, double* extent, int* evaluations, f3r_error* err) {
  f3r_mode_search ms;
  double est = 0.0;
  f3r_status st = f3r_mode_search_init(scene, chosen, NULL, &ms, err);
  if (st == F3R_OK)
    st = f3r_mode_search_run(scene, &ms, target > 0.0 ? target : -target * ms.extent, modes, &est,
                             err);
  if (st == F3R_OK) {
    if (estimate) *estimate = est;
    if (extent) *extent = ms.extent;
    if (evaluations) *evaluations = ms.evaluations;
  }
  f3r_mode_search_free(&ms);
  return st;
}
