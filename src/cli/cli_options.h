/* flex3rpr_sim's options: what the command line says, its parsing, the usage text, and the first
 * failure the CLI reports (for the JSON summary's error). */
#ifndef FLEX3RPR_CLI_OPTIONS_H
#define FLEX3RPR_CLI_OPTIONS_H

#include <stdio.h>

#define MAX_HOLDS 64
#define MAX_SETS 64

/* A held generalized force from a time on, as a node command would give it. */
typedef struct {
  double t;
  int index;
  double value;
} hold_event;

typedef struct {
  const char* scene_path;
  const char* out_path;
  int modal;
  const char* modal_csv; /* --modal-csv FILE: the frequencies as CSV, to 17 digits */
  int geometry;
  int check;
  int fd_jacobian;
  int dense_linear_solver;
  int exact_kinematics;
  const char* formulation;
  double rtol, atol, max_order, output_step, duration, accuracy;
  int no_verify;      /* --no-verify: accuracy.verify = false */
  double escalations; /* --escalations N: accuracy.escalations = N */
  const char* linear_path;
  const char* linearise_path; /* --linearise FILE.mat: the state-space model, and FILE.json */
  const char* summary_json;   /* --summary-json FILE: the summary as JSON; "-": on stdout */
  int stop_at_outputs;
  const char* integrator;  /* --integrator NAME or --NAME (kinds.h's table) */
  int integrator_conflict; /* two different integrators given */
  const char* table;
  int n_holds;
  hold_event holds[MAX_HOLDS];
  int n_sets;
  const char* sets[MAX_SETS]; /* "FIELD=VALUE" scene overrides, in order */
} cli_options;

void cli_usage(FILE* to);
/* Fills o from the arguments; 0 (after cli_fail) on a bad one. --help prints the usage. */
int cli_parse_args(int argc, char** argv, cli_options* o);
/* Prints "flex3rpr_sim: <message>" on stderr and keeps the first failure: its status
 * (f3r_status_name, or "usage" and "io" for the CLI's own) and message. */
void cli_fail(const char* status, const char* format, ...);
const char* cli_failure_status(void); /* NULL: nothing failed */
/* Forgets the failure kept (a run that a richer configuration replaced; its message was printed). */
void cli_clear_failure(void);
const char* cli_failure_message(void);

#endif
