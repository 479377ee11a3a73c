/* What the integrator back ends share (stepper.h). */
#include "stepper.h" /* first: it includes stdio.h, which arkode_butcher.h needs */

#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>
#include <stdio.h>

void f3r_stepper_error_handler(int code, const char* module, const char* function, char* msg,
                               void* user) {
  f3r_stepper* st = user;
  (void)code;
  snprintf(st->message, sizeof st->message, "%s %s: %s", module, function, msg);
}

int f3r_stepper_roots(const f3r_stepper* st, const double* y, double* g) {
  return f3r_event_roots(st->model, st->settings.formulation, y, g);
}

ARKodeButcherTable f3r_stepper_load_table(int implicit, const char* name) {
  if (!name) return NULL;
  return implicit ? ARKodeButcherTable_LoadDIRKByName(name) : ARKodeButcherTable_LoadERKByName(name);
}
