/* The minimal formulation: its residual and right-hand side (form_minimal.c) and its Jacobian
 * (form_minimal_jacobian.c); layout and equations: residual.h. Private. */
#ifndef FLEX3RPR_FORM_MINIMAL_H
#define FLEX3RPR_FORM_MINIMAL_H

#include "workspace.h"

/* The residual's rows at the state y, its rate yp and the forward pass in d through the closed
 * acceleration stage at u' (residual.c runs it, with d->reduced at res + nz: those rows are
 * written). */
void f3r_minimal_rows(const f3r_model* m, const double* y, const double* yp, const f3r_data* d,
                      double* res);
/* Its Jacobian dF/dy + cj dF/dy' (J cleared) at the forward pass in ws->data through the closed
 * acceleration stage at u'. */
void f3r_minimal_jacobian(const f3r_model* m, double cj, double* J, int ld, f3r_workspace* ws);
/* y' at the forward pass in ws->data through the closed acceleration stage at u' = 0 (its reduced
 * equations written at ydot + nz), with K's
 * low-rank structure (structured 1), or with K assembled and factored whole (0). */
f3r_status f3r_minimal_rhs(const f3r_model* m, int structured, const double* y, double* ydot,
                           f3r_workspace* ws);

/* The reduced mass K = B^T M B in its arrow blocks (ws->mass_pp, mass_pe, mass_ee) at the position
 * stage in ws->data, and scale K added into A (leading dimension ld): the dense right-hand side's
 * and the Jacobian's. */
void f3r_minimal_reduced_mass_blocks(const f3r_model* m, f3r_workspace* ws);
void f3r_minimal_add_reduced_mass(const f3r_model* m, const f3r_workspace* ws, double scale,
                                  double* A, int ld);

#endif
