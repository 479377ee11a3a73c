/* The options as scene overrides (cli_overrides.h). */
#include "cli_overrides.h"

#include <stdio.h>
#include <string.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/scene.h"

static void add_number(override_list* l, const char* field, double value) {
  if (value > 0) snprintf(l->own[l->n_own++], sizeof l->own[0], "%s=%.17g", field, value);
}

/* A string as a YAML single-quoted scalar, so that the name is read as it is. */
static void add_string(override_list* l, const char* field, const char* value) {
  char* out = l->own[l->n_own++];
  size_t n = (size_t)snprintf(out, sizeof l->own[0], "%s='", field);
  for (const char* c = value; *c && n + 3 < sizeof l->own[0]; ++c) {
    if (*c == '\'') out[n++] = '\'';
    out[n++] = *c;
  }
  snprintf(out + n, sizeof l->own[0] - n, "'");
}

int cli_integrator_minimal_only(const cli_options* o) {
  f3r_integrator integrator;
  if (!o->integrator || f3r_integrator_from_name(o->integrator, &integrator) != 0) return 0;
  return !(f3r_integrator_kind_at((int)integrator)->formulations & (1u << F3R_FORMULATION_DAE));
}

/* The options' overrides, then the user's --set: applied in order, so a --set wins over an
 * option (--set solver.rtol=1e-5 --rtol 1e-6 runs at 1e-5). An integrator of the minimal formulation
 * only (--erk, --dirk) forces it, over --formulation but not over a --set, with force_minimal only (resolve_model). */
void cli_build_overrides(const cli_options* o, int force_minimal, override_list* l) {
  memset(l, 0, sizeof *l);
  if (o->formulation) add_string(l, "solver.formulation", o->formulation);
  if (o->integrator) {
    add_string(l, "solver.integrator", o->integrator);
    if (force_minimal) add_string(l, "solver.formulation", "minimal");
  }
  if (o->table) add_string(l, "solver.table", o->table);
  add_number(l, "solver.rtol", o->rtol);
  add_number(l, "solver.atol", o->atol);
  add_number(l, "solver.max_order", o->max_order);
  add_number(l, "run.output_step", o->output_step);
  add_number(l, "run.duration", o->duration);
  add_number(l, "accuracy.escalations", o->escalations);
  if (o->no_verify) snprintf(l->own[l->n_own++], sizeof l->own[0], "%s", "accuracy.verify=false");
  if (o->exact_kinematics)
    snprintf(l->own[l->n_own++], sizeof l->own[0], "%s", "effects.exact_kinematics=true");
  for (int k = 0; k < l->n_own; ++k) l->all[l->n_all++] = l->own[k];
  for (int k = 0; k < o->n_sets; ++k) l->all[l->n_all++] = o->sets[k];
}

/* A message about an option's override ("--set solver.rtol=0.5: ...") names the scene instead,
 * as it did when the options were written into the loaded scene. */
void cli_report_load_error(const cli_options* o, const override_list* l, const f3r_error* err) {
  for (int k = 0; k < l->n_own; ++k) {
    char prefix[128];
    const int n = snprintf(prefix, sizeof prefix, "--set %s: ", l->own[k]);
    if (!strncmp(err->message, prefix, (size_t)n)) {
      cli_fail(f3r_status_name(err->code), "%s: %s", o->scene_path, err->message + n);
      return;
    }
  }
  cli_fail(f3r_status_name(err->code), "%s", err->message);
}
