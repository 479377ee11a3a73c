/* flex3rpr_sim's option parsing (cli_options.h). */
#include "cli_options.h"

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/scene.h"

void cli_usage(FILE* to) {
  fprintf(
      to,
      "usage: flex3rpr_sim SCENE.yaml [--out FILE.csv] [--formulation dae|minimal]\n"
      "                    [--rtol R] [--atol A] [--max-order K] [--output-step DT] [--duration "
      "T]\n"
      "                    [--fd-jacobian] [--dense-linear-solver] [--exact-kinematics]\n"
      "                    [--integrator NAME] [--table NAME]   (also --NAME: --erk)\n"
      "                    [--stop-at-outputs] [--hold T:INDEX:VALUE ...]\n"
      "                    [--accuracy METRES [--no-verify] [--escalations N]]\n"
      "                    [--linear-path FILE.csv] [--linearise FILE.mat]\n"
      "                    [--set FIELD=VALUE ...]   (any scene field: --set links[0].modes=4)\n"
      "                    [--summary-json FILE|-]   (the summary as JSON; -: on stdout)\n"
      "       flex3rpr_sim --modal SCENE.yaml [--modal-csv FILE.csv] [--set FIELD=VALUE ...]\n"
      "       flex3rpr_sim --geometry SCENE.yaml\n"
      "       flex3rpr_sim --check SCENE.yaml [--set FIELD=VALUE ...]   (load and build only)\n"
      "integrators:\n");
  for (int k = 0; k < f3r_integrator_kind_count(); ++k)
    fprintf(to, "  %-6s %s\n", f3r_integrator_kind_at(k)->name,
            f3r_integrator_kind_at(k)->description);
}

/* The first failure, for the JSON summary's error: a status (f3r_status_name, or "usage" and
 * "io" for the CLI's own) and the message, which cli_fail() also prints. */
static struct {
  const char* status;
  char message[4096 + 512]; /* a path, and an f3r_error's message */
} failure;

const char* cli_failure_status(void) { return failure.status; }
void cli_clear_failure(void) { failure.status = NULL; }
const char* cli_failure_message(void) { return failure.message; }

void cli_fail(const char* status, const char* format, ...) {
  char text[sizeof failure.message];
  va_list args;
  va_start(args, format);
  vsnprintf(text, sizeof text, format, args);
  va_end(args);
  fprintf(stderr, "flex3rpr_sim: %s\n", text);
  if (!failure.status) {
    failure.status = status;
    snprintf(failure.message, sizeof failure.message, "%s", text);
  }
}

static int parse_number(const char* flag, const char* text, double* out) {
  char* end = NULL;
  const double v = text ? strtod(text, &end) : NAN;
  if (!text || end == text || *end || !isfinite(v) || v <= 0.0) {
    cli_fail("usage", "%s needs a positive number, got '%s'", flag, text ? text : "");
    return 0;
  }
  *out = v;
  return 1;
}

/* The options, by kind: a switch sets an int to 1, a path keeps its argument, a number takes a
 * positive one (parse_number). */
typedef struct {
  const char* flag;
  size_t offset;
} option_field;

static const option_field switches[] = {
    {"--modal", offsetof(cli_options, modal)},
    {"--geometry", offsetof(cli_options, geometry)},
    {"--check", offsetof(cli_options, check)},
    {"--fd-jacobian", offsetof(cli_options, fd_jacobian)},
    {"--dense-linear-solver", offsetof(cli_options, dense_linear_solver)},
    {"--exact-kinematics", offsetof(cli_options, exact_kinematics)},
    {"--stop-at-outputs", offsetof(cli_options, stop_at_outputs)},
    {"--no-verify", offsetof(cli_options, no_verify)},
};
static const option_field paths[] = {
    {"--table", offsetof(cli_options, table)},
    {"--out", offsetof(cli_options, out_path)},
    {"--linear-path", offsetof(cli_options, linear_path)},
    {"--linearise", offsetof(cli_options, linearise_path)},
    {"--modal-csv", offsetof(cli_options, modal_csv)},
    {"--formulation", offsetof(cli_options, formulation)},
    {"--summary-json", offsetof(cli_options, summary_json)},
};
static const option_field numbers[] = {
    {"--accuracy", offsetof(cli_options, accuracy)},
    {"--rtol", offsetof(cli_options, rtol)},
    {"--atol", offsetof(cli_options, atol)},
    {"--max-order", offsetof(cli_options, max_order)},
    {"--output-step", offsetof(cli_options, output_step)},
    {"--duration", offsetof(cli_options, duration)},
    {"--escalations", offsetof(cli_options, escalations)},
};
#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static const option_field* find_option(const option_field* table, size_t n, const char* flag) {
  for (size_t k = 0; k < n; ++k)
    if (!strcmp(table[k].flag, flag)) return &table[k];
  return NULL;
}

/* --hold T:INDEX:VALUE and --set FIELD=VALUE, which collect. 1 taken, 0 an error (said). */
static int collect_option(const char* a, const char* next, cli_options* o) {
  if (!strcmp(a, "--hold")) {
    hold_event* h = &o->holds[o->n_holds];
    /* the value is checked with the command it makes (the session's rule: check_holds) */
    if (o->n_holds >= MAX_HOLDS || sscanf(next, "%lf:%d:%lf", &h->t, &h->index, &h->value) != 3 ||
        !(h->t >= 0.0) || h->index < 0) {
      cli_fail("usage", "--hold needs T:INDEX:VALUE (T >= 0), got '%s'", next);
      return 0;
    }
    ++o->n_holds;
    return 1;
  }
  if (o->n_sets >= MAX_SETS) {
    cli_fail("usage", "at most %d --set overrides", MAX_SETS);
    return 0;
  }
  o->sets[o->n_sets++] = next;
  return 1;
}

/* One argument (and its value, which *k then passes): 1 taken, 0 an error (said). */
static int parse_arg(int argc, char** argv, int* k, cli_options* o) {
  const char* a = argv[*k];
  const char* next = *k + 1 < argc ? argv[*k + 1] : NULL;
  const option_field* f;
  /* --integrator NAME, and --NAME for each integrator of the table (--ida, --erk, --dirk) */
  f3r_integrator named;
  const char* integrator = !strcmp(a, "--integrator") ? next
                           : !strncmp(a, "--", 2) && f3r_integrator_from_name(a + 2, &named) == 0
                               ? a + 2
                               : NULL;
  if (integrator) {
    if (integrator == next) ++*k;
    if (o->integrator && strcmp(o->integrator, integrator)) o->integrator_conflict = 1;
    o->integrator = integrator;
    return 1;
  }
  if ((f = find_option(switches, COUNT(switches), a))) {
    *(int*)((char*)o + f->offset) = 1;
    return 1;
  }
  if (next && (f = find_option(paths, COUNT(paths), a))) {
    *(const char**)((char*)o + f->offset) = next;
    ++*k;
    return 1;
  }
  if ((f = find_option(numbers, COUNT(numbers), a))) {
    ++*k;
    return parse_number(a, next, (double*)((char*)o + f->offset));
  }
  if (next && (!strcmp(a, "--hold") || !strcmp(a, "--set"))) {
    ++*k;
    return collect_option(a, next, o);
  }
  if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
    cli_usage(stdout);
    exit(0);
  }
  if (a[0] != '-' && !o->scene_path) {
    o->scene_path = a;
    return 1;
  }
  cli_fail("usage", "unknown or incomplete option '%s'", a);
  return 0;
}

int cli_parse_args(int argc, char** argv, cli_options* o) {
  memset(o, 0, sizeof *o);
  for (int k = 1; k < argc; ++k)
    if (!parse_arg(argc, argv, &k, o)) return 0;
  if (!o->scene_path) {
    cli_fail("usage", "no scene given");
    return 0;
  }
  char names[256];
  f3r_integrator integrator;
  if (o->integrator && f3r_integrator_from_name(o->integrator, &integrator) != 0) {
    cli_fail("usage", "--integrator must be one of %s, got '%s'",
             f3r_integrator_names(names, sizeof names), o->integrator);
    return 0;
  }
  if (o->integrator_conflict) {
    cli_fail("usage", "give one integrator: --integrator NAME (one of %s) or --NAME",
             f3r_integrator_names(names, sizeof names));
    return 0;
  }
  f3r_formulation formulation;
  if (o->formulation && f3r_formulation_from_name(o->formulation, &formulation) != 0) {
    cli_fail("usage", "--formulation must be %s or %s, got '%s'",
             f3r_formulation_name(F3R_FORMULATION_DAE),
             f3r_formulation_name(F3R_FORMULATION_MINIMAL), o->formulation);
    return 0;
  }
  const int to_stdout = o->geometry || o->modal || o->modal_csv || o->linear_path ||
                        o->linearise_path; /* what writes its own output on stdout */
  if (o->summary_json && !strcmp(o->summary_json, "-") && to_stdout) {
    cli_fail("usage",
             "--summary-json - needs stdout, which --geometry, --modal, --linear-path and "
             "--linearise use: give a file");
    return 0;
  }
  return 1;
}
