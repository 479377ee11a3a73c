/* A whole run measured against its check, with escalation (flex3rpr/measured_run.h). The runs
 * are the shell's; this only sequences them and decides. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/measured_run.h"

void f3r_describe_config(const f3r_scene* s, char* text, size_t size) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_scene* l = &s->links[i];
    const int shapes = l->static_correction ? f3r_link_correction_functions(l) : 0;
    n += l->model == F3R_LINK_RIGID ? snprintf(text + n, size - (size_t)n, "%s-", i ? "/" : "")
         : shapes ? snprintf(text + n, size - (size_t)n, "%s%d+%ds", i ? "/" : "", l->modes, shapes)
                  : snprintf(text + n, size - (size_t)n, "%s%d", i ? "/" : "", l->modes);
  }
  snprintf(text + n, size - (size_t)n, "%s, %s%s%s rtol %g", s->exact_kinematics ? " exact" : "",
           f3r_integrator_name(s->integrator), s->table[0] ? " " : "", s->table, s->rtol);
}

/* Whether a measured error meets the request, with the check's margin. */
static int measured_meets(double measured, double request) {
  return measured <= F3R_CHECK_MARGIN * request; /* false when unmeasured (NaN) */
}

/* Appends one configuration's line to the attempts' text. */
static void note_attempt(f3r_measured_run* v, int attempt, const char* format, ...)
    __attribute__((format(printf, 3, 4)));
static void note_attempt(f3r_measured_run* v, int attempt, const char* format, ...) {
  size_t n = strlen(v->attempts);
  if (attempt) n += (size_t)snprintf(v->attempts + n, sizeof v->attempts - n, "\n%20s", "");
  va_list args;
  va_start(args, format);
  if (n < sizeof v->attempts) vsnprintf(v->attempts + n, sizeof v->attempts - n, format, args);
  va_end(args);
}

/* Whether escalation stops after configuration `current` (attempt > 0: `previous` came before
 * it): its measured error did not shrink, or the next configuration, run and checked, would pass
 * F3R_ESCALATION_COST_LIMIT. Says why in v->stopped. */
static int escalation_stops(f3r_measured_run* v, int attempt, int current, int previous) {
  double spent = 0.0;
  for (int k = 0; k < v->count; ++k) spent += v->costs[k].cpu;
  const double first = v->costs[0].cpu + v->costs[v->count > 1 ? 1 : 0].cpu;
  /* the next configuration is this one's check (run again only for the outputs), and its own
   * check about twice that (one more mode and a tenth of the tolerance: 1.5 to 2.5 times on the
   * shipped scenes) */
  const double next = 2.0 * v->costs[v->count - 1].cpu;
  const long impacts = v->costs[current].impacts;
  char why[160] = "";
  if (attempt > 0 && previous >= 0 &&
      !(v->measured[current] < F3R_ESCALATION_SHRINK * v->measured[previous]))
    snprintf(why, sizeof why, "the measured error did not shrink (%.3g m, then %.3g m)",
             v->measured[previous], v->measured[current]);
  else if (spent + next > F3R_ESCALATION_COST_LIMIT * first)
    snprintf(why, sizeof why,
             "the next configuration would pass %g times the first one's cost (%.3g s so far)",
             F3R_ESCALATION_COST_LIMIT, spent);
  if (!why[0]) return 0;
  int n = snprintf(v->stopped, sizeof v->stopped, "escalation stopped: %s", why);
  if (impacts && n > 0 && (size_t)n < sizeof v->stopped)
    snprintf(v->stopped + n, sizeof v->stopped - (size_t)n,
             "; %ld end-stop impacts, the first at t = %.6g s: past an impact the path need not "
             "converge in the mode count",
             impacts, v->costs[current].first_impact);
  return 1;
}

/* Runs configuration k into its path (allocated here on its first run). */
static f3r_status run_config(const f3r_config_runner* runner, f3r_measured_run* v, double** paths,
                             int k, int keep, int count, f3r_error* err) {
  if (!paths[k] && !(paths[k] = malloc((size_t)count * 2 * sizeof(double))))
    return f3r_error_set(err, F3R_ERR_MEMORY, "no memory for a path of %d outputs", count);
  const f3r_status st =
      runner->run(runner->context, k, &v->scenes[k], keep, paths[k], &v->costs[k]);
  v->failed[k] = st != F3R_OK;
  return F3R_OK;
}

/* The sequence itself; paths[k] is configuration k's, NULL until it ran. */
static f3r_status sequence(const f3r_scene* scene, int keep, const f3r_config_runner* runner,
                           f3r_measured_run* v, double** paths, f3r_error* err) {
  const double request = scene->accuracy;
  const int escalations = scene->accuracy_escalations,
            count = (int)llround(scene->duration / scene->output_step) + 1;
  int current = 0, best = -1, previous = -1;
  int ran[F3R_MEASURED_MAX_CONFIGS] = {0};
  v->count = 1;
  v->scenes[0] = *scene;
  for (int attempt = 0;; ++attempt) {
    char text[256], checked[128];
    f3r_describe_config(&v->scenes[current], text, sizeof text);
    int check = -1;
    f3r_status st = F3R_OK;
    if (!ran[current] && (st = run_config(runner, v, paths, current, keep, count, err)) != F3R_OK)
      return st;
    ran[current] = 1;
    if (v->failed[current]) {
      note_attempt(v, attempt, "%s: the run failed", text); /* reported; a richer one may not */
    } else {
      check = v->count++;
      f3r_accuracy_check_scene(&v->scenes[current], 0, &v->scenes[check]);
      f3r_describe_config(&v->scenes[check], checked, sizeof checked);
      if ((st = run_config(runner, v, paths, check, 0, count, err)) != F3R_OK) return st;
      ran[check] = 1;
      if (v->failed[check]) {
        note_attempt(v, attempt, "%s: its check %s failed", text, checked);
      } else {
        v->measured[current] = f3r_path_distance(paths[current], paths[check], count);
        note_attempt(v, attempt, "%s: measured %.3g m against %s", text, v->measured[current],
                     checked);
      }
    }
    if (!v->failed[current] &&
        (best < 0 || v->measured[current] < v->measured[best] || isnan(v->measured[best])))
      best = current;
    if (measured_meets(v->measured[current], request) || attempt == escalations) break;
    if (escalation_stops(v, attempt, current, previous)) break;
    previous = current;
    f3r_scene next;
    if (!f3r_accuracy_check_scene(&v->scenes[current], 1, &next)) break; /* the scene fixes it */
    if (check >= 0 && !v->failed[check] && !memcmp(&next, &v->scenes[check], sizeof next) &&
        !keep) {
      current = check; /* the check is the next configuration, and has run */
      continue;
    }
    /* the next configuration runs (again, where it was the check: with the outputs kept,
     * which a check's run does not format) */
    current = v->count++;
    v->scenes[current] = next;
  }
  v->accepted = best;
  if (best < 0) return F3R_OK; /* every run failed: reported by the shell */
  for (int k = 0; k < v->count; ++k)
    if (k != best) v->check_cpu += v->costs[k].cpu;
  v->measured_error = v->measured[best];
  v->request_met = measured_meets(v->measured_error, request);
  return F3R_OK;
}

f3r_status f3r_measured_run_sequence(const f3r_scene* scene, int keep,
                                     const f3r_config_runner* runner, f3r_measured_run* v,
                                     f3r_error* err) {
  memset(v, 0, sizeof *v);
  v->accepted = -1;
  v->measured_error = NAN;
  for (int k = 0; k < F3R_MEASURED_MAX_CONFIGS; ++k) v->measured[k] = NAN;
  double* paths[F3R_MEASURED_MAX_CONFIGS] = {0};
  const f3r_status st = sequence(scene, keep, runner, v, paths, err);
  for (int k = 0; k < F3R_MEASURED_MAX_CONFIGS; ++k) free(paths[k]);
  return st;
}
