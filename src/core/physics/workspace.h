/* Scratch memory of the residual and Jacobian, sized once per model. Private. */
#ifndef FLEX3RPR_WORKSPACE_H
#define FLEX3RPR_WORKSPACE_H

#include "data.h"
#include "residual.h"
#include "stages.h"

struct f3r_workspace {
  int nq, nz, ny;
  f3r_data data; /* the last evaluation's forward pass: its inputs and stages */
  double tmp[F3R_MAX_Q];
  double* solve_work;  /* f3r_solve_accelerations_work_size */
  double* y_perturbed; /* ny: the zero rate of the explicit right-hand side */
  double* res_base;    /* ny */
  /* the minimal formulation's reduced mass B^T M B in its arrow blocks (form_minimal.c) */
  double mass_pp[9];                                /* platform, 3 x 3 */
  double mass_pe[3][3 * F3R_MAX_MODES];             /* link i's modes with the platform, 3 x r_i */
  double mass_ee[3][F3R_MAX_MODES * F3R_MAX_MODES]; /* link i's modes, r_i x r_i */
  double* jac_work;     /* the minimal Jacobian's products: 2 nq^2 + 18 nq + 3 nq nz + 6 nz */
  double* dQ;           /* 2 nq x nq: dQ/dq and dQ/dv of the effects */
  f3r_stop_locks locks; /* the legs held at their stops (f3r_workspace_set_locks) */
  double stop_force[3]; /* the last forward pass's stop forces (N), with locks */
  double* stop_work;    /* f3r_stop_forces_work_size */
};

/* With legs locked: the stops' forces at the forward pass in d (q, v, Q; closed: the minimal
 * formulation's closed stages, whose q lacks theta) into ws->stop_force, added to d->Q and to
 * the power d->power. Nothing when no leg is locked. */
f3r_status f3r_workspace_add_stop_forces(const f3r_model* m, f3r_workspace* ws, int closed);

/* form: F3R_FORMULATION_DAE or F3R_FORMULATION_INDEX3 (form_dae.c serves both) */
f3r_residual_fn f3r_dae_residual;
f3r_jacobian_fn f3r_dae_jacobian;
f3r_status f3r_minimal_residual(const f3r_model* m, double t, const double* y, const double* yp,
                                const double* held, double* res, f3r_workspace* ws);
f3r_status f3r_minimal_jacobian(const f3r_model* m, double t, double cj, const double* y,
                                const double* yp, const double* held, double* J, int ld,
                                f3r_workspace* ws);

/* The minimal formulation's accelerations and loop forces (d->a, d->R, d->lambda) from the
 * independent accelerations in yp, given the position, velocity and force stages in d. */
void f3r_minimal_multipliers(const f3r_model* m, const double* yp, f3r_data* d);

/* y' with K's low-rank structure, and with K assembled and factored whole (form_minimal.c). */
f3r_rhs_fn f3r_minimal_rhs, f3r_minimal_rhs_dense;

/* The reduced mass K = B^T M B in its arrow blocks (ws->mass_pp, mass_pe, mass_ee) at the position
 * stage in ws->data, and scale K added into A (leading dimension ld): the dense right-hand side's
 * and the Jacobian's (form_minimal.c). */
void f3r_minimal_reduced_mass_blocks(const f3r_model* m, f3r_workspace* ws);
void f3r_minimal_add_reduced_mass(const f3r_model* m, const f3r_workspace* ws, double scale,
                                  double* A, int ld);

#endif
