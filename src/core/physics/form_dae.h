/* The redundant-coordinate formulations dae and index3 (form_dae.c; layouts and equations:
 * residual.h). Private. */
#ifndef FLEX3RPR_FORM_DAE_H
#define FLEX3RPR_FORM_DAE_H

#include "workspace.h"

/* form: F3R_FORMULATION_DAE or F3R_FORMULATION_INDEX3. The residual's rows at the state y, its rate
 * yp and the forward pass in d through the acceleration stage (residual.c runs it). */
void f3r_dae_rows(const f3r_model* m, f3r_formulation form, const double* y, const double* yp,
                  const f3r_data* d, double* res);
/* Its Jacobian dF/dy + cj dF/dy' (J cleared) at the forward pass in ws->data through the stops. */
void f3r_dae_jacobian(const f3r_model* m, f3r_formulation form, double cj, const double* y,
                      const double* yp, double* J, int ld, f3r_workspace* ws);

#endif
