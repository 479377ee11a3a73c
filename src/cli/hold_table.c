/* The --hold table (hold_table.h). */
#include "hold_table.h"

#include <string.h>

#include "flex3rpr/session.h"

/* The --hold table as commands from outside: the command held after each hold, checked by the
 * session's rule (flex3rpr/session.h) with the value named as every shell names it. 0 when one
 * is refused (said). */
int cli_check_holds(const cli_options* o, const f3r_scene* scene, const f3r_model* model) {
  const int nq = f3r_model_nq(model);
  f3r_error err = {0};
  for (int h = 0; h < o->n_holds; ++h) {
    const hold_event* e = &o->holds[h];
    if (e->index >= nq) {
      cli_fail("usage", "--hold %g:%d:%g: index %d is out of range 0..%d (nq = %d)", e->t, e->index,
               e->value, e->index, nq - 1, nq);
      return 0;
    }
    /* the command from e's time: each index at its latest hold by then (later in the list on
     * a tie, as apply_holds applies them) */
    double held[F3R_MAX_Q] = {0}, since[F3R_MAX_Q];
    for (int n = 0; n < nq; ++n) since[n] = -1.0;
    for (int k = 0; k < o->n_holds; ++k) {
      const hold_event* x = &o->holds[k];
      if (x->t <= e->t && x->t >= since[x->index]) {
        held[x->index] = x->value;
        since[x->index] = x->t;
      }
    }
    if (f3r_command_check(scene, model, held, nq, &err) != F3R_OK) {
      cli_fail(f3r_status_name(err.code), "--hold %g:%d:%g: %s", e->t, e->index, e->value,
               err.message);
      return 0;
    }
  }
  return 1;
}

/* Held forces change only at output times, exactly as in the node. */
f3r_status cli_apply_holds(const cli_options* o, double output_step, f3r_sim* sim, double* held,
                           f3r_error* err) {
  int changed = 0;
  const double t_now = f3r_sim_time(sim);
  for (int h = 0; h < o->n_holds; ++h)
    if (o->holds[h].t <= t_now + 1e-12 && held[o->holds[h].index] != o->holds[h].value &&
        o->holds[h].t > t_now - 0.5 * output_step) {
      held[o->holds[h].index] = o->holds[h].value;
      changed = 1;
    }
  return changed ? f3r_sim_set_forces(sim, held, err) : F3R_OK;
}
