/* The command line's options as scene overrides "FIELD=VALUE" for the loader, before the user's
 * --set ones, and the loader's errors about them named as the scene's. */
#ifndef FLEX3RPR_CLI_OVERRIDES_H
#define FLEX3RPR_CLI_OVERRIDES_H

#include "cli_options.h"
#include "flex3rpr/status.h"

/* The scene fields the options set, as overrides (numbers with %.17g, which round-trip): they
 * pass the file's checks and fix what the file would, so the accuracy knob keeps them. */
#define MAX_OPTION_SETS 16
typedef struct {
  char own[MAX_OPTION_SETS][96];
  const char* all[MAX_OPTION_SETS + MAX_SETS];
  int n_own, n_all;
} override_list;

/* The options' overrides, then the user's --set, in order (a --set wins over an option); an
 * integrator of the minimal formulation only (--erk, --dirk) forces it with force_minimal only. */
void cli_build_overrides(const cli_options* o, int force_minimal, override_list* l);
/* 1 when the options name an integrator that integrates the minimal formulation only. */
int cli_integrator_minimal_only(const cli_options* o);
/* A message about an option's override names the scene instead. */
void cli_report_load_error(const cli_options* o, const override_list* l, const f3r_error* err);

#endif
