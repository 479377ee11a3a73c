/* Scratch memory of the residual, its Jacobian and the right-hand side, sized once per model: the
 * last evaluation's forward pass and the formulations' products. Below the residual and the
 * formulations, which share it. Private. */
#ifndef FLEX3RPR_WORKSPACE_H
#define FLEX3RPR_WORKSPACE_H

#include "equations.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct f3r_workspace {
  int nq, nz, ny;
  f3r_data data;       /* the last evaluation's forward pass: its inputs and stages */
  double* solve_work;  /* f3r_solve_accelerations_work_size */
  double* y_perturbed; /* ny: the end stops' difference quotients (residual.c) */
  /* the minimal formulation's reduced mass B^T M B in its arrow blocks (form_minimal.c) */
  double mass_pp[9];                                /* platform, 3 x 3 */
  double mass_pe[3][3 * F3R_MAX_MODES];             /* link i's modes with the platform, 3 x r_i */
  double mass_ee[3][F3R_MAX_MODES * F3R_MAX_MODES]; /* link i's modes, r_i x r_i */
  double* jac_work;     /* the minimal Jacobian's products: 2 nq^2 + 18 nq + 3 nq nz + 6 nz */
  double* dQ;           /* 2 nq x nq: dQ/dq and dQ/dv of the effects */
  f3r_stop_locks locks; /* the legs held at their stops (f3r_workspace_set_locks) */
  double* stop_work;    /* f3r_stop_forces_work_size */
} f3r_workspace;

f3r_workspace* f3r_workspace_create(const f3r_model* model);
void f3r_workspace_destroy(f3r_workspace* ws);

/* sin/cos pairs the forward pass has evaluated through this workspace since its creation: a
 * counter for tests and the benchmark (one evaluation's share is the difference of two reads). */
long f3r_workspace_sincos_pairs(const f3r_workspace* ws);

/* End stops held as contact: the legs locked at their stops for the workspace's next evaluations
 * (side[i]: -1 at stroke_min, +1 at stroke_max, 0 free; equations.h). */
void f3r_workspace_set_locks(f3r_workspace* ws, const int side[3]);

#ifdef __cplusplus
}
#endif
#endif
