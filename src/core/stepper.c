/* What the two integrator back ends share (stepper.h). */
#include <stdio.h>

#include "stepper.h"

void f3r_stepper_error_handler(int code, const char* module, const char* function, char* msg,
                               void* user) {
  f3r_stepper* st = user;
  (void)code;
  snprintf(st->message, sizeof st->message, "%s %s: %s", module, function, msg);
}

int f3r_stepper_roots(const f3r_stepper* st, const double* y, double* g) {
  return f3r_event_roots(st->model, st->settings.formulation, y, g);
}
