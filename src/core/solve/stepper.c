/* What the integrator back ends share (stepper.h). */
#include "stepper.h" /* first: it includes stdio.h, which arkode_butcher.h needs */

#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>
#include <stdio.h>

#include "erk_tables.h"

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
  if (implicit) return ARKodeButcherTable_LoadDIRKByName(name);
  const f3r_erk_table* own = f3r_erk_table_find(name);
  if (!own) return ARKodeButcherTable_LoadERKByName(name);
  /* ARKODE copies the arrays; it only takes them non-const */
  return ARKodeButcherTable_Create(own->stages, own->order, own->embedded_order, (double*)own->c,
                                   (double*)own->A, (double*)own->b, (double*)own->b_embedded);
}

int f3r_stepper_explicit_rhs(realtype t, N_Vector y, N_Vector ydot, void* user) {
  f3r_stepper* st = user;
  const f3r_status s =
      f3r_explicit_rhs(st->model, f3r_stepper_force_time(st, t), N_VGetArrayPointer(y), st->held,
                       N_VGetArrayPointer(ydot), st->ws);
  if (s == F3R_OK) return 0;
  st->recoverable++;
  return 1; /* recoverable: ARKODE retries with a smaller step */
}

int f3r_stepper_explicit_roots(realtype t, N_Vector y, realtype* g, void* user) {
  (void)t;
  return f3r_stepper_roots(user, N_VGetArrayPointer(y), g);
}
