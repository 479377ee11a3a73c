/* The CLI's reports on a model (model_reports.c): each returns the process exit code, or prints. */
#ifndef FLEX3RPR_CLI_MODEL_REPORTS_H
#define FLEX3RPR_CLI_MODEL_REPORTS_H

#include <stdio.h>

#include "cli_options.h"
#include "flex3rpr/model.h"

/* --geometry: geometry, masses and stroke as JSON on stdout (nodes/make_urdf.py reads it). */
void f3r_cli_print_geometry(const f3r_model* m);
/* --modal: the linearised natural frequencies (Hz) at the initial pose and each link's basis;
 * with csv_path (--modal-csv) also as CSV there, to 17 digits. */
int f3r_cli_run_modal(const f3r_model* m, const char* csv_path);
/* --linear-path FILE.csv: the linear model's platform path. */
int f3r_cli_write_linear_path(const f3r_model* m, const char* path);
/* --linearise FILE.mat: the state-space model, and FILE.json beside it. */
int f3r_cli_write_state_space(const f3r_model* m, const char* path);

/* --check and --geometry: the model only, before the accuracy knob's report; 0. */
int f3r_cli_describe_model(FILE* human, const cli_options* o, const f3r_model* model);
/* The analyses that replace a simulation (--linear-path, --linearise, --modal): the exit code,
 * or -1 when none was asked for. */
int f3r_cli_analyse(const cli_options* o, const f3r_model* model);

#endif
