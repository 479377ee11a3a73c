/* Natural frequencies of the constrained system linearised about the initial pose (linear.h). */
#include <math.h>
#include <stddef.h>

#include "flex3rpr/linear.h"
#include "flex3rpr/modal.h"

f3r_status f3r_modal_frequencies(const f3r_model* model, double* hz, int* count, f3r_error* err) {
  f3r_linear_model* lin = NULL;
  const f3r_status st = f3r_linearise(model, &lin, err);
  if (st != F3R_OK) return st;
  for (int k = 0; k < lin->n; ++k) hz[k] = sqrt(fmax(lin->omega2[k], 0.0)) / (2.0 * M_PI);
  *count = lin->n;
  f3r_linear_destroy(lin);
  return F3R_OK;
}
