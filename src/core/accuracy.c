/* The accuracy knob (include/flex3rpr/accuracy.h): linear mode-count estimate, nonlinear pilot
 * check, exact kinematics and the measured solver relation. Runs once before a simulation, so
 * it allocates freely; nothing here touches the step loop. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/linear.h"
#include "flex3rpr/sim.h"

#define MAX_SAMPLES 20001
/* The linear path "leaves the initial pose far" beyond this share of the platform's side (or
 * this rotation): then the linearisation is checked by a nonlinear pilot. */
#define FAR_SHARE 0.1
#define FAR_ROTATION 0.05
#define PILOT_SHARE 0.1 /* of the duration */
/* s: the longest of the work-precision benchmark's scenes (paper simulation 3), over which the
 * solver relations of solver_table.c were measured */
#define BENCHMARK_DURATION 0.5

static int is_flexible(const f3r_scene* s, int i) { return s->links[i].model != F3R_LINK_RIGID; }

static int lowest_modes(const f3r_scene* s, int i) { /* the initial state's highest mode */
  int low = 1;
  for (int j = 0; j < F3R_MAX_MODES; ++j)
    if (s->links[i].eta0[j] != 0.0 || s->links[i].eta_rate0[j] != 0.0) low = j + 1;
  return low;
}

/* The scene with fixed mode counts, no accuracy request: a model the caller must destroy. */
static f3r_status model_with(const f3r_scene* base, const int modes[3], int exact_kinematics,
                             f3r_model** model, f3r_error* err) {
  f3r_scene s = *base;
  s.accuracy = 0.0;
  s.exact_kinematics = exact_kinematics;
  for (int i = 0; i < 3; ++i) s.links[i].modes = is_flexible(&s, i) ? modes[i] : 0;
  return f3r_model_create(&s, model, err);
}

static f3r_status linear_path(const f3r_scene* s, const int modes[3], double dt, int count,
                              double* pose, f3r_error* err) {
  f3r_model* model = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = model_with(s, modes, 0, &model, err);
  if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
  if (st == F3R_OK) st = f3r_linear_response(lin, model, dt, count, 1, pose, NULL, err);
  f3r_linear_destroy(lin);
  f3r_model_destroy(model);
  return st;
}

/* Largest end-effector distance between two pose paths (3 values a sample) over count samples. */
static double max_distance(const double* a, const double* b, int count) {
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
    if (in->kind != F3R_INPUT_NONE && !(in->kind == F3R_INPUT_CONSTANT && in->offset == 0.0)) return 0;
  }
  if (s->gravity[0] != 0.0 || s->gravity[1] != 0.0) return 0;
  for (int k = 0; k < 3; ++k)
    if (s->platform_velocity0[k] != 0.0) return 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < F3R_MAX_MODES; ++j)
      if (s->links[i].eta0[j] != 0.0 || s->links[i].eta_rate0[j] != 0.0) return 0;
  return 1;
}

/* The nonlinear end-effector path at t_k = k dt, k < count, with the given solver: a pilot. */
static f3r_status pilot_path(const f3r_scene* base, const int modes[3], int exact_kinematics,
                             const f3r_solver_settings* solver, double dt, int count, double* pose,
                             f3r_error* err) {
  f3r_model* model = NULL;
  f3r_sim* sim = NULL;
  f3r_status st = model_with(base, modes, exact_kinematics, &model, err);
  if (st == F3R_OK) st = f3r_sim_create(model, solver, &sim, err);
  for (int k = 0; st == F3R_OK && k < count; ++k) {
    if (k) st = f3r_sim_advance(sim, k * dt, err);
    const f3r_outputs* out = f3r_sim_outputs(sim);
    for (int c = 0; c < 3; ++c) pose[3 * k + c] = out->q[F3R_Q_X + c];
  }
  f3r_sim_destroy(sim);
  f3r_model_destroy(model);
  if (st != F3R_OK) {
    char why[sizeof err->message] = "failed"; /* a copy: the message is rewritten from itself */
    if (err) snprintf(why, sizeof why, "%s", err->message);
    return f3r_error_set(err, st, "accuracy: pilot run at %d, %d, %d modes: %s", modes[0], modes[1],
                         modes[2], why);
  }
  return F3R_OK;
}

/* The reference the mode count r is compared with: "larger r", three times r and three more, so
 * that a slowly converging fixed-free link is compared with modes well beyond it; 20 from r = 6. */
static int reference_modes(int r) { return 3 * r + 3 < F3R_MAX_MODES ? 3 * r + 3 : F3R_MAX_MODES; }

/* What the mode search shares: the sampling, the links chosen, their least counts (the initial
 * state's highest mode), the order of the linear path (2 near the initial pose, where the
 * second-order correction holds; 1 where the path leaves it and the pilot checks instead) and the
 * current reference path. */
typedef struct {
  double dt;
  int count;
  unsigned chosen;
  int low[3];
  int fixed[3];     /* the modes of the links not chosen */
  int order;
  int ref_r;        /* the uniform count the reference in ref has on the chosen links, 0: none */
  double* ref;      /* 3 count */
  double* path;     /* 3 count, scratch */
  double extent;    /* m: largest distance of the linearised end effector from its start */
  double rotation;  /* rad: largest linearised platform rotation from its start */
  int far;          /* the first- or second-order path leaves the initial pose far */
  int at_rest;
  int evaluations;
} mode_search;

static void search_free(mode_search* ms) {
  free(ms->ref);
  free(ms->path);
}

static void uniform(const mode_search* ms, int r, int modes[3]) {
  for (int i = 0; i < 3; ++i) modes[i] = (ms->chosen >> i & 1) ? (r > ms->low[i] ? r : ms->low[i]) : ms->fixed[i];
}

static f3r_status path_at(const f3r_scene* s, mode_search* ms, const int modes[3], int order,
                          double* pose, f3r_error* err) {
  f3r_model* model = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = model_with(s, modes, 0, &model, err);
  if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
  if (st == F3R_OK) st = f3r_linear_response(lin, model, ms->dt, ms->count, order, pose, NULL, err);
  f3r_linear_destroy(lin);
  f3r_model_destroy(model);
  ++ms->evaluations;
  return st;
}

static f3r_status reference_for(const f3r_scene* s, mode_search* ms, int r, f3r_error* err) {
  const int R = reference_modes(r);
  if (ms->ref_r == R) return F3R_OK;
  int modes[3];
  uniform(ms, R, modes);
  ms->ref_r = 0;
  const f3r_status st = path_at(s, ms, modes, ms->order, ms->ref, err);
  if (st == F3R_OK) ms->ref_r = R;
  return st;
}

/* The extent and rotation of the reference path from its start; far when either leaves the pose. */
static void measure_extent(const f3r_scene* s, mode_search* ms) {
  for (int k = 0; k < ms->count; ++k) {
    const double* p = ms->ref + 3 * k;
    ms->extent = fmax(ms->extent, hypot(p[0] - ms->ref[0], p[1] - ms->ref[1]));
    ms->rotation = fmax(ms->rotation, fabs(p[2] - ms->ref[2]));
  }
  ms->far = ms->extent > FAR_SHARE * s->platform_side || ms->rotation > FAR_ROTATION;
}

static f3r_status search_init(const f3r_scene* s, unsigned chosen, mode_search* ms, f3r_error* err) {
  memset(ms, 0, sizeof *ms);
  double fastest = 0.0; /* sampling: the output step, fine enough for the fastest input */
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) fastest = fmax(fastest, f3r_input_max_frequency(&s->inputs[k]));
  double h = s->output_step;
  if (fastest > 0.0) h = fmin(h, 1.0 / (20.0 * fastest));
  if (s->duration / h > MAX_SAMPLES - 1) h = s->duration / (MAX_SAMPLES - 1);
  ms->count = (int)ceil(s->duration / h - 1e-9) + 1;
  ms->dt = s->duration / (ms->count - 1);
  for (int i = 0; i < 3; ++i) {
    if (!is_flexible(s, i)) chosen &= ~(1u << i);
    ms->low[i] = lowest_modes(s, i);
    ms->fixed[i] = is_flexible(s, i) ? s->links[i].modes : 0;
  }
  ms->chosen = chosen;
  ms->order = 1;
  ms->at_rest = at_rest(s);
  if (ms->at_rest) return F3R_OK;
  ms->ref = malloc((size_t)ms->count * 3 * sizeof(double));
  ms->path = malloc((size_t)ms->count * 3 * sizeof(double));
  if (!ms->ref || !ms->path) {
    search_free(ms);
    return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  }
  /* How far the first-order path goes decides the order of the estimate. */
  f3r_status st = reference_for(s, ms, 1, err);
  if (st != F3R_OK) return st;
  measure_extent(s, ms);
  if (ms->far) return F3R_OK;
  /* The second-order remainder oscillates with the vibration itself, so its sampling must
   * resolve the first elastic mode too (20 samples a period); a run too long for that is
   * estimated as a far one. */
  double first = 0.0;
  {
    int modes[3];
    uniform(ms, 1, modes);
    f3r_model* model = NULL;
    f3r_linear_model* lin = NULL;
    st = model_with(s, modes, 0, &model, err);
    if (st == F3R_OK) st = f3r_linearise(model, &lin, err);
    if (st == F3R_OK) {
      const double top = lin->omega2[lin->n - 1];
      for (int j = 0; j < lin->n && first == 0.0; ++j)
        if (lin->omega2[j] > 1e-8 * top) first = sqrt(lin->omega2[j]) / (2.0 * M_PI);
    }
    f3r_linear_destroy(lin);
    f3r_model_destroy(model);
    if (st != F3R_OK) return st;
  }
  double fine = ms->dt;
  if (first > 0.0) fine = fmin(fine, 1.0 / (20.0 * first));
  const double samples = ceil(s->duration / fine - 1e-9) + 1;
  if (samples > MAX_SAMPLES) {
    ms->far = 1;
    return F3R_OK;
  }
  if ((int)samples != ms->count) {
    ms->count = (int)samples;
    ms->dt = s->duration / (ms->count - 1);
    free(ms->ref);
    free(ms->path);
    ms->ref = malloc((size_t)ms->count * 3 * sizeof(double));
    ms->path = malloc((size_t)ms->count * 3 * sizeof(double));
    if (!ms->ref || !ms->path) return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
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

/* The fewest modes whose linear path stays within target of its reference: uniform r on the
 * chosen links first (the cost grows with every link's r alike), then each link down while the
 * path stays within it (a link the inputs excite less needs fewer). */
static f3r_status search_modes(const f3r_scene* s, mode_search* ms, double target, int modes[3],
                               double* estimate, f3r_error* err) {
  uniform(ms, F3R_MAX_MODES, modes);
  *estimate = 0.0;
  if (!ms->chosen) return F3R_OK;
  if (ms->at_rest) {
    uniform(ms, 1, modes);
    return F3R_OK;
  }
  f3r_status st = F3R_OK;
  double est = 0.0;
  int found = F3R_MAX_MODES;
  /* r = 1, 2, 3 each against its own reference (3 r + 3); beyond, a bisection of 4..19 against
   * 20 modes, assuming the difference falls with r (it does, if slowly, for both beam models). */
  for (int r = 1; r <= 3 && found == F3R_MAX_MODES; ++r) {
    int trial[3];
    uniform(ms, r, trial);
    if ((st = reference_for(s, ms, r, err)) != F3R_OK ||
        (st = path_at(s, ms, trial, ms->order, ms->path, err)) != F3R_OK)
      return st;
    const double e = max_distance(ms->path, ms->ref, ms->count);
    if (e <= target) {
      memcpy(modes, trial, sizeof trial);
      est = e;
      found = r;
    }
  }
  if (found == F3R_MAX_MODES) {
    int lo = 4, hi = F3R_MAX_MODES; /* e(hi) <= target; 20 is the reference itself */
    double e_hi = 0.0;
    if ((st = reference_for(s, ms, F3R_MAX_MODES, err)) != F3R_OK) return st;
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      int trial[3];
      uniform(ms, mid, trial);
      if ((st = path_at(s, ms, trial, ms->order, ms->path, err)) != F3R_OK) return st;
      const double e = max_distance(ms->path, ms->ref, ms->count);
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
  if (found == F3R_MAX_MODES) {
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
      if ((st = path_at(s, ms, modes, ms->order, ms->path, err)) != F3R_OK) return st;
      const double e = max_distance(ms->path, ms->ref, ms->count);
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

f3r_status f3r_accuracy_modes(const f3r_scene* scene, unsigned chosen, double target, int modes[3],
                              double* estimate, double* extent, int* evaluations, f3r_error* err) {
  mode_search ms;
  double est = 0.0;
  f3r_status st = search_init(scene, chosen, &ms, err);
  if (st == F3R_OK) st = search_modes(scene, &ms, target > 0.0 ? target : -target * ms.extent, modes, &est, err);
  if (st == F3R_OK) {
    if (estimate) *estimate = est;
    if (extent) *extent = ms.extent;
    if (evaluations) *evaluations = ms.evaluations;
  }
  search_free(&ms);
  return st;
}

/* The cheapest measured solver whose error fits `budget`, among those the scene leaves open. */
static const f3r_solver_relation* pick_solver(const f3r_scene* s, const char* kind, double budget) {
  const f3r_solver_relation* best = NULL;
  const unsigned fixed = s->explicit_settings;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (strcmp(r->kind, kind) || r->error > budget) continue;
    if ((fixed & F3R_EXPLICIT_FORMULATION) && r->formulation != s->formulation) continue;
    if ((fixed & F3R_EXPLICIT_INTEGRATOR) && r->integrator != s->integrator) continue;
    if ((fixed & F3R_EXPLICIT_RTOL) && r->rtol != s->rtol) continue;
    if ((fixed & F3R_EXPLICIT_TABLE) && strcmp(r->table, s->table)) continue;
    if (!best || r->cost < best->cost || (r->cost == best->cost && r->rtol > best->rtol)) best = r;
  }
  return best;
}

/* The measured error of the scene's own fixed solver (the nearest tolerance at or below). */
static double solver_error_of(const f3r_scene* s, const char* kind) {
  double error = NAN, at = 0.0;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (strcmp(r->kind, kind) || r->formulation != s->formulation || r->integrator != s->integrator ||
        strcmp(r->table, s->explicit_settings & F3R_EXPLICIT_TABLE ? s->table : "") ||
        r->rtol > s->rtol * (1.0 + 1e-9))
      continue;
    if (r->rtol > at) {
      at = r->rtol;
      error = r->error;
    }
  }
  return error;
}

static const char* integrator_name(f3r_integrator i) {
  return i == F3R_INTEGRATOR_ERK ? "erk" : i == F3R_INTEGRATOR_DIRK ? "dirk" : "ida";
}

static void append(char* text, size_t size, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
static void append(char* text, size_t size, const char* fmt, ...) {
  const size_t used = strlen(text);
  if (used + 1 >= size) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(text + used, size - used, fmt, ap);
  va_end(ap);
}

/* The loosest tolerance of minimal IDA, at most 1e-6, whose measured error stays below `error`
 * (1e-6 if none), and that error: the pilot's noise. Never looser than the baseline 1e-6, as the
 * pilot checks solvers too, and the benchmark's relations can be short on a scene unlike its own
 * (a long run). */
static double pilot_rtol(const char* kind, double error, double* noise) {
  double best = 0.0;
  *noise = error;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (!strcmp(r->kind, kind) && r->formulation == F3R_FORMULATION_MINIMAL &&
        r->integrator == F3R_INTEGRATOR_IDA && r->error <= error && r->rtol > best &&
        r->rtol <= 1e-6 * (1.0 + 1e-9)) {
      best = r->rtol;
      *noise = r->error;
    }
  }
  return best > 0.0 ? best : 1e-6;
}

/* The nonlinear pilot: runs over the first PILOT_SHARE of the duration at the linear estimate's
 * modes r, with a tolerance whose measured error is a tenth of the model's share. */
typedef struct {
  int count;         /* samples in the window */
  double grow;       /* duration / window */
  double noise;      /* m: the pilot's own solver error */
  f3r_solver_settings tight;
  int modes[3];
  double* a;         /* the path at r, tight */
  double* b;         /* scratch */
} pilot_run;

static void pilot_free(pilot_run* p) {
  free(p->a);
  free(p->b);
}

/* A difference over the window carried to the whole run: d(W) T / W. A difference that starts at
 * t = 0 grows as t^2 at first, whatever it does later, so the window cannot tell its later growth;
 * linear growth is what a phase error gives, and what paper simulation 3's nonlinear differences
 * show over the whole run (their ratio to the linear ones, 2.7 at 0.05 s, 5 at 0.1 s, 23 at 0.5 s). */
static double extrapolate(const pilot_run* p, const double* x, const double* y) {
  return max_distance(x, y, p->count) * fmax(p->grow, 1.0);
}

static f3r_status pilot_start(const f3r_scene* s, const mode_search* ms, const int modes[3],
                              const char* kind, double resolution, pilot_run* p, f3r_error* err) {
  memset(p, 0, sizeof *p);
  const double window = fmax(PILOT_SHARE * s->duration, ms->dt);
  p->count = ms->count < (int)ceil(window / ms->dt) + 1 ? ms->count : (int)ceil(window / ms->dt) + 1;
  p->grow = s->duration / ((p->count - 1) * ms->dt);
  p->tight = f3r_solver_settings_from_scene(s);
  p->tight.formulation = F3R_FORMULATION_MINIMAL;
  p->tight.integrator = F3R_INTEGRATOR_IDA;
  p->tight.rtol = pilot_rtol(kind, resolution, &p->noise);
  p->tight.atol = fmin(1e-2 * p->tight.rtol, s->atol); /* positions resolved from the start */
  p->tight.rk_table[0] = '\0';
  memcpy(p->modes, modes, sizeof p->modes);
  p->a = malloc((size_t)p->count * 3 * sizeof(double));
  p->b = malloc((size_t)p->count * 3 * sizeof(double));
  if (!p->a || !p->b) return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  return pilot_path(s, modes, 0, &p->tight, ms->dt, p->count, p->a, err);
}

/* The nonlinear difference of r and r + 1 modes, carried to the whole run (0 within the pilot's
 * noise), and the linear difference of the same pair over the whole run. */
static f3r_status pilot_pair(const f3r_scene* s, mode_search* ms, pilot_run* p, double* nonlinear,
                             double* linear, f3r_error* err) {
  *nonlinear = *linear = 0.0;
  int more[3];
  for (int i = 0; i < 3; ++i)
    more[i] = (ms->chosen >> i & 1) && p->modes[i] < F3R_MAX_MODES ? p->modes[i] + 1 : p->modes[i];
  double* la = malloc((size_t)ms->count * 3 * sizeof(double));
  double* lb = malloc((size_t)ms->count * 3 * sizeof(double));
  f3r_status st = la && lb ? F3R_OK : f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  if (st == F3R_OK && (st = pilot_path(s, more, 0, &p->tight, ms->dt, p->count, p->b, err)) == F3R_OK &&
      (st = linear_path(s, p->modes, ms->dt, ms->count, la, err)) == F3R_OK &&
      (st = linear_path(s, more, ms->dt, ms->count, lb, err)) == F3R_OK) {
    ms->evaluations += 2;
    *linear = max_distance(la, lb, ms->count);
    /* Below three times the pilot's own solver error the difference says nothing. */
    if (max_distance(p->a, p->b, p->count) > 3.0 * p->noise) *nonlinear = extrapolate(p, p->a, p->b);
  }
  free(la), free(lb);
  return st;
}

/* The effect of exact kinematics at r, carried to the whole run. */
static f3r_status pilot_kinematics(const f3r_scene* s, const mode_search* ms, pilot_run* p,
                                   double* effect, f3r_error* err) {
  *effect = 0.0;
  const f3r_status st = pilot_path(s, p->modes, 1, &p->tight, ms->dt, p->count, p->b, err);
  if (st == F3R_OK && max_distance(p->a, p->b, p->count) > 3.0 * p->noise) *effect = extrapolate(p, p->a, p->b);
  return st;
}

/* The error of a solver at r against the tight pilot, carried to the whole run (0 when within the
 * pilot's own noise). */
static f3r_status pilot_solver(const f3r_scene* s, const mode_search* ms, pilot_run* p,
                               const f3r_solver_settings* solver, double* error, f3r_error* err) {
  *error = 0.0;
  const f3r_status st = pilot_path(s, p->modes, 0, solver, ms->dt, p->count, p->b, err);
  if (st == F3R_OK && max_distance(p->a, p->b, p->count) > 3.0 * p->noise) *error = extrapolate(p, p->a, p->b);
  return st;
}

f3r_status f3r_accuracy_choose(const f3r_scene* scene, double request, int commanded,
                               f3r_accuracy_choice* c, f3r_error* err) {
  memset(c, 0, sizeof *c);
  if (!(request > 0.0) || !isfinite(request))
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "accuracy: the request must be a positive length (m)");
  c->request = request;
  unsigned chosen = 0;
  int any_flexible = 0;
  f3r_scene s = *scene;
  for (int i = 0; i < 3; ++i) {
    if (!is_flexible(scene, i)) continue;
    any_flexible = 1;
    if (!(scene->explicit_settings & (F3R_EXPLICIT_MODES << i))) {
      chosen |= 1u << i;
      s.links[i].modes = 1; /* a placeholder until chosen */
    }
  }
  const char* kind = commanded && any_flexible ? "commanded" : any_flexible ? "flexible" : "rigid";
  const double model_target = F3R_ACCURACY_MODEL_SHARE * request;
  const int kinematics_open = any_flexible && !(scene->explicit_settings & F3R_EXPLICIT_EXACT_KINEMATICS);
  mode_search ms;
  f3r_status st = search_init(&s, chosen, &ms, err);
  double linear_error = 0.0;
  if (st == F3R_OK) st = search_modes(&s, &ms, model_target, c->modes, &linear_error, err);
  c->extent = ms.extent;
  c->model_error = linear_error;
  c->pilot_ratio = 1.0;
  c->exact_kinematics = scene->exact_kinematics;
  pilot_run pilot = {0};
  const unsigned solver_fixed = F3R_EXPLICIT_FORMULATION | F3R_EXPLICIT_INTEGRATOR | F3R_EXPLICIT_RTOL;
  const int solver_open = (scene->explicit_settings & solver_fixed) != solver_fixed;
  if (st == F3R_OK && ms.far && (chosen || kinematics_open || solver_open)) {
    st = pilot_start(&s, &ms, c->modes, kind, 0.1 * model_target, &pilot, err);
    c->pilot = st == F3R_OK;
    /* The nonlinear difference of r and r + 1, times the linear model's tail beyond r + 1 (its
     * r-against-reference over r-against-r + 1, within 1..10), bounds the model error from
     * below; where it exceeds the linear estimate, the estimate is short by their ratio for
     * every r, and the search runs again with the target shrunk by it. */
    double nonlinear = 0.0, linear = 0.0;
    if (st == F3R_OK && chosen) st = pilot_pair(&s, &ms, &pilot, &nonlinear, &linear, err);
    const double tail = linear > 0.0 ? fmin(fmax(linear_error / linear, 1.0), 10.0) : 1.0;
    if (getenv("F3R_ACCURACY_DEBUG"))
      fprintf(stderr, "pilot: nonlinear %g linear %g linear_error %g tail %g noise %g rtol %g\n", nonlinear,
              linear, linear_error, tail, pilot.noise, pilot.tight.rtol);
    const double estimate = fmax(linear_error, nonlinear * tail);
    if (st == F3R_OK && estimate > linear_error) {
      c->pilot_ratio = linear_error > 0.0 ? estimate / linear_error : INFINITY;
      c->model_error = estimate;
      if (estimate > model_target && isfinite(c->pilot_ratio)) {
        st = search_modes(&s, &ms, model_target / c->pilot_ratio, c->modes, &linear_error, err);
        c->model_error = c->pilot_ratio * linear_error;
      }
    }
    if (st == F3R_OK && kinematics_open) {
      st = pilot_kinematics(&s, &ms, &pilot, &c->kinematics_effect, err);
      c->exact_kinematics = c->kinematics_effect > F3R_ACCURACY_KINEMATICS_SHARE * request;
      c->kinematics_error = c->exact_kinematics ? 0.0 : c->kinematics_effect;
    }
  }
  /* A run longer than the benchmark's scenes drifts further than their relations say (a phase
   * error grows with time): a pilot then measures the chosen solver on this scene as well. */
  int solver_pilot = 0;
  if (st == F3R_OK && !c->pilot && solver_open && !ms.at_rest && s.duration > BENCHMARK_DURATION) {
    st = pilot_start(&s, &ms, c->modes, kind, 0.1 * model_target, &pilot, err);
    solver_pilot = st == F3R_OK;
  }
  const int measured_solver = c->pilot || solver_pilot;
  c->linear_evaluations = ms.evaluations;
  const int rest = ms.at_rest, order = ms.order, reference = ms.ref_r;
  if (st != F3R_OK) {
    pilot_free(&pilot);
    search_free(&ms);
    return st;
  }

  char* text = c->summary;
  const size_t size = sizeof c->summary;
  append(text, size, "accuracy %g m on the end-effector path (shares: model %g, kinematics %g, solver %g)\n",
         request, F3R_ACCURACY_MODEL_SHARE, F3R_ACCURACY_KINEMATICS_SHARE, F3R_ACCURACY_SOLVER_SHARE);
  for (int i = 0; i < 3; ++i) {
    if (!is_flexible(scene, i)) append(text, size, "links[%d]: rigid\n", i);
    else if (!(chosen >> i & 1)) append(text, size, "links[%d]: %d modes, as the scene sets\n", i, c->modes[i]);
    else append(text, size, "links[%d]: %d modes\n", i, c->modes[i]);
  }
  if (chosen && rest)
    append(text, size, "modes: nothing excites the scene (no inputs, initial rates or deflections)\n");
  else if (chosen)
    append(text, size,
           "modes: the %s-order linearised path is within %.3g m of the same with %d modes (path "
           "extent %.3g m, %d linear models)\n",
           order == 2 ? "second" : "first", linear_error, reference, c->extent, c->linear_evaluations);
  if (c->pilot)
    append(text, size,
           "pilot: the path leaves the initial pose (%.3g m); nonlinear runs over the first %.0f%% of it, "
           "carried to the whole, scale the linear estimate by %.3g\n",
           c->extent, 100.0 * PILOT_SHARE, c->pilot_ratio);
  if (!any_flexible) append(text, size, "exact kinematics: no flexible link\n");
  else if (!kinematics_open)
    append(text, size, "exact kinematics: %s, as the scene sets\n", c->exact_kinematics ? "on" : "off");
  else if (!c->pilot)
    append(text, size, "exact kinematics: off (second order in the deflections; the path stays near the initial pose)\n");
  else
    append(text, size, "exact kinematics: %s (its effect is estimated at %.3g m; the limit is %.3g m)\n",
           c->exact_kinematics ? "on" : "off", c->kinematics_effect,
           F3R_ACCURACY_KINEMATICS_SHARE * request);

  double budget = request - c->model_error - c->kinematics_error;
  budget = fmax(budget, F3R_ACCURACY_SOLVER_SHARE * request);
  c->formulation = scene->formulation;
  c->integrator = scene->integrator;
  c->rtol = scene->rtol;
  c->atol = scene->atol;
  snprintf(c->table, sizeof c->table, "%s", scene->table);
  if (!solver_open) {
    c->solver_error = solver_error_of(scene, kind);
    append(text, size, "solver: %s, %s, rtol %g, as the scene sets (measured error %.3g m)\n",
           scene->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
           integrator_name(scene->integrator), scene->rtol, c->solver_error);
  } else {
    /* The cheapest measured relation within the budget; where a pilot ran, its own error there
     * checks the relation, and a relation it exceeds is replaced by one the excess allows. */
    double limit = budget, measured = 0.0;
    const f3r_solver_relation* r = NULL;
    for (int attempt = 0; attempt < 3; ++attempt) {
      const f3r_solver_relation* next = pick_solver(scene, kind, limit);
      if (!next || next == r) break;
      r = next;
      if (!measured_solver) break;
      f3r_scene trial = s;
      trial.formulation = r->formulation;
      trial.integrator = r->integrator;
      trial.rtol = r->rtol;
      trial.atol = scene->explicit_settings & F3R_EXPLICIT_ATOL ? scene->atol : r->atol;
      snprintf(trial.table, sizeof trial.table, "%s", r->table);
      const f3r_solver_settings settings = f3r_solver_settings_from_scene(&trial);
      if ((st = pilot_solver(&s, &ms, &pilot, &settings, &measured, err)) != F3R_OK) break;
      if (measured <= budget) break;
      limit = r->error * budget / measured; /* the relation is short by measured / error here */
    }
    if (st != F3R_OK) {
      pilot_free(&pilot);
      search_free(&ms);
      return st;
    }
    if (!r) {
      c->solver_error = solver_error_of(scene, kind);
      append(text, size, "solver: no measured solver fits %.3g m; keeping %s, rtol %g\n", budget,
             integrator_name(scene->integrator), scene->rtol);
    } else {
      c->formulation = r->formulation;
      c->integrator = r->integrator;
      c->rtol = r->rtol;
      if (!(scene->explicit_settings & F3R_EXPLICIT_ATOL)) c->atol = r->atol;
      snprintf(c->table, sizeof c->table, "%s", r->table);
      c->solver_error = fmax(r->error, measured);
      append(text, size,
             "solver: %s, %s%s%s, rtol %g, atol %g: the cheapest measured within %.3g m (at most %.3g m on "
             "the %d %s benchmark scenes; cost %.2g of minimal IDA at 1e-6; measured on %s)\n",
             r->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
             integrator_name(r->integrator), r->table[0] ? " " : "", r->table, r->rtol, c->atol, budget,
             r->error, r->scenes, r->kind, r->cost, f3r_solver_relations_source);
      if (solver_pilot)
        append(text, size,
               "solver: the run is longer than the benchmark's scenes (%g s); a pilot over its first "
               "%.0f%% measures %.3g m for it over the run\n",
               BENCHMARK_DURATION, 100.0 * PILOT_SHARE, measured);
      else if (c->pilot)
        append(text, size, "solver: the pilot measures %.3g m for it over the run\n", measured);
    }
  }
  pilot_free(&pilot);
  search_free(&ms);
  const double total = c->model_error + c->kinematics_error + (isfinite(c->solver_error) ? c->solver_error : 0.0);
  /* Neither the linear model nor a pilot window sees an impact's jump, and a path with impacts
   * need not converge in the mode count at all: end_stop_impact at 12 and 20 modes (exact
   * kinematics, rtol 1e-9 and 1e-11) part by 5 cm within 0.3 s. Say so rather than promise. */
  const int impacts = s.end_stops && !rest;
  if (impacts)
    append(text, size, "end stops: impacts are outside this estimate (with them the path need not converge in "
                       "the mode count); check the result against a run with more modes\n");
  append(text, size, "estimated error %.3g m (model %.3g, kinematics %.3g, solver %.3g)", total,
         c->model_error, c->kinematics_error, c->solver_error);
  char how[64] = "linear estimate";
  if (c->pilot) snprintf(how, sizeof how, "linear estimate x %.3g from the pilot", c->pilot_ratio);
  snprintf(c->brief, sizeof c->brief,
           "accuracy %g m: modes %d/%d/%d (%s), exact kinematics %s, %s %s%s%s rtol %g; "
           "estimated %.3g m%s",
           request, c->modes[0], c->modes[1], c->modes[2], how, c->exact_kinematics ? "on" : "off",
           c->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal", integrator_name(c->integrator),
           c->table[0] ? " " : "", c->table, c->rtol, total, impacts ? " without the impacts" : "");
  return F3R_OK;
}

void f3r_accuracy_apply(const f3r_accuracy_choice* c, f3r_scene* s) {
  for (int i = 0; i < 3; ++i)
    if (is_flexible(s, i)) s->links[i].modes = c->modes[i];
  s->exact_kinematics = c->exact_kinematics;
  s->formulation = c->formulation;
  s->integrator = c->integrator;
  s->rtol = c->rtol;
  s->atol = c->atol;
  snprintf(s->table, sizeof s->table, "%s", c->table);
}

f3r_status f3r_accuracy_resolve(f3r_scene* scene, int commanded, f3r_accuracy_choice* choice,
                                f3r_error* err) {
  f3r_accuracy_choice local;
  f3r_accuracy_choice* c = choice ? choice : &local;
  memset(c, 0, sizeof *c);
  if (scene->accuracy > 0.0) {
    const f3r_status st = f3r_accuracy_choose(scene, scene->accuracy, commanded, c, err);
    if (st == F3R_OK) f3r_accuracy_apply(c, scene);
    return st;
  }
  unsigned chosen = 0;
  double tolerance = 0.0;
  for (int i = 0; i < 3; ++i)
    if (is_flexible(scene, i) && scene->links[i].modes == F3R_MODES_AUTO) {
      chosen |= 1u << i;
      tolerance = fmax(tolerance, scene->links[i].auto_tolerance);
    }
  if (!chosen) return F3R_OK;
  f3r_scene s = *scene;
  for (int i = 0; i < 3; ++i)
    if (chosen >> i & 1) s.links[i].modes = 1;
  const f3r_status st = f3r_accuracy_modes(&s, chosen, -tolerance, c->modes, &c->model_error,
                                           &c->extent, &c->linear_evaluations, err);
  if (st != F3R_OK) return st;
  snprintf(c->brief, sizeof c->brief,
           "modes auto: %d/%d/%d (linearised path within %.3g m of 3r + 3 modes, auto_tolerance %g "
           "of its extent %.3g m)",
           c->modes[0], c->modes[1], c->modes[2], c->model_error, tolerance, c->extent);
  for (int i = 0; i < 3; ++i) {
    if (chosen >> i & 1) scene->links[i].modes = c->modes[i];
    if (chosen >> i & 1)
      append(c->summary, sizeof c->summary,
             "links[%d]: modes auto -> %d (linearised path within %.3g m of 3r + 3 modes: "
             "auto_tolerance %g of its extent %.3g m)\n",
             i, c->modes[i], c->model_error, tolerance, c->extent);
  }
  return F3R_OK;
}
