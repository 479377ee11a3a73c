/* f3r_peer: the flex3rpr model for other solvers (the peers of the work-precision benchmark):
 * R deSolve's DASPK through its compiled-code interface, scipy's solve_ivp through ctypes.
 * A shared library over the core without SUNDIALS (sim.c and the steppers are not needed).
 *
 * Handle API (any number of handles; y, yp, res and J are in the handle's component order):
 *   int  f3r_peer_create(const char* scene_path, int formulation, int algebraic_last,
 *                        f3r_peer** out);    formulation 0 dae, 1 minimal, 2 index3.
 *        algebraic_last reorders y by differentiation index, as deSolve's daspk and
 *        deTestSet's mebdfi want it (argument nind): dae as [q | v | lag | W | lambda | mu]
 *        (the index-2 multipliers last), index3 as [q | lag | W | v | lambda] (index 1, 2, 3).
 *        Returns an f3r_status; the message of a failure is f3r_peer_last_error().
 *   void f3r_peer_index_counts(const f3r_peer*, int* counts)  counts[3]: variables of index
 *        1, 2, 3 (index3: nq + lag + 1, nq, 6; the others: differential, algebraic, 0)
 *   void f3r_peer_destroy(f3r_peer*)
 *   int  f3r_peer_state_size(const f3r_peer*)       ny
 *   int  f3r_peer_algebraic_count(const f3r_peer*)  12 for dae, 0 for minimal
 *   void f3r_peer_state_kinds(const f3r_peer*, double* id)  1 differential, 0 algebraic
 *   double f3r_peer_duration(const f3r_peer*)       the scene's run duration (s)
 *   int  f3r_peer_breakpoints(const f3r_peer*, double* times, int max)  kinks of the inputs
 *   int  f3r_peer_end_stops(const f3r_peer*)        1 when the scene has end stops (impacts
 *                                                   are not handled here)
 *   int  f3r_peer_initial_state(f3r_peer*, double* y, double* yp)
 *        the scene's initial state, consistent, forces at their right limit at t = 0 (as the CLI)
 *   int  f3r_peer_restart_state(f3r_peer*, double t, double* y, double* yp)
 *        y, yp made consistent again at a breakpoint t from the positions, rates, lag states and
 *        work in y (forces at their right limit), as the CLI restarts there
 *   int  f3r_peer_residual(f3r_peer*, double t, const double* y, const double* yp, double* res)
 *   int  f3r_peer_jacobian(f3r_peer*, double t, double cj, const double* y, const double* yp,
 *                          double* J)    dF/dy + cj dF/dy', ny x ny column-major (ld = ny)
 *   int  f3r_peer_rhs(f3r_peer*, double t, const double* y, double* ydot)   minimal only:
 *        f3r_explicit_rhs
 *   int  f3r_peer_rhs_jacobian(f3r_peer*, double t, const double* y, const double* ydot,
 *                              double* J)   minimal only: d ydot/dy by forward differences of
 *        the explicit RHS (ny evaluations, counted in rhs_evals), ROW-major (numpy's order);
 *        ydot = f(t, y) or NULL to evaluate it
 *   int  f3r_peer_end_effector(const f3r_peer*, const double* y, double* xy)  (x_p, y_p)
 *   void f3r_peer_counts(const f3r_peer*, long* counts)  residual, jacobian, rhs evaluations
 *   void f3r_peer_reset_counts(f3r_peer*)
 *   const char* f3r_peer_last_error(void)
 *
 * deSolve (R) interface: deSolve passes no user pointer, so these use one static handle,
 * opened with .C and used by daspk(res = "f3r_peer_desolve_res", jacres = "f3r_peer_desolve_jac",
 * dllname = "libf3r_peer", initfunc = NULL):
 *   f3r_peer_r_open(char** path, int* formulation, int* ny, int* nalg, double* duration,
 *                   int* n_breakpoints, int* status)   opens (closing any open handle),
 *                   algebraic components last
 *   f3r_peer_r_index_counts(int* counts)               f3r_peer_index_counts of the handle
 *   f3r_peer_r_close(void)
 *   f3r_peer_r_initial(double* y, double* yp, int* status)
 *   f3r_peer_r_restart(double* t, double* y, double* yp, int* status)
 *   f3r_peer_r_breakpoints(double* times, int* n)      n in: room, out: count
 *   f3r_peer_r_end_effector(int* rows, double* Y, double* x, double* y)
 *                   Y is an R matrix rows x ny (column-major): one state per row
 *   f3r_peer_r_counts(double* counts)                  residual, jacobian, rhs; then reset
 *   f3r_peer_r_message(char** message)                 the last error, into a string of 511
 *   f3r_peer_desolve_res(double* t, double* y, double* yprime, double* cj, double* delta,
 *                        int* ires, double* yout, int* ip)   DASPK's RES: ires = -1 on a
 *                        configuration the model cannot evaluate (DASPK cuts the step), -2 with
 *                        no open handle
 *   f3r_peer_desolve_jac(double* t, double* y, double* yprime, double* pd, double* cj,
 *                        double* rpar, int* ipar)    DASPK's JAC (dense, leading dimension ny)
 *
 * deTestSet's mebdfi (R) calls compiled code with deSolve's DASPK argument lists, so its
 * residual is f3r_peer_desolve_res (the 6th argument is MEBDFI's IERR: nonzero makes it halve
 * the step), but the scalar its Jacobian gets is MEBDFI's CON = h * beta_0, the reciprocal of
 * DASPK's cj: it wants dF/dy + (1/CON) dF/dy' (see PSET in deTestSet's mebdfi.f, whose
 * difference quotients perturb y' by r/CON). Hence
 *   f3r_peer_mebdfi_jac(double* t, double* y, double* yprime, double* pd, double* con,
 *                       double* rpar, int* ipar)    mebdfi(res = "f3r_peer_desolve_res",
 *                       jacres = "f3r_peer_mebdfi_jac", jactype = "fullusr", ...):
 *                       f3r_peer_desolve_jac with cj = 1 / con
 *
 * Nothing here prints; every failure is returned. Not thread-safe (the deSolve handle and the
 * last error are static). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/model.h"
#include "residual.h"
#include "flex3rpr/scene.h"
#include "model_layout.h"
#include "queries.h"

#define F3R_PEER_EXPORT __attribute__((visibility("default")))

typedef struct f3r_peer {
  f3r_model* model;
  f3r_formulation form;
  f3r_workspace* ws;
  int ny, nalg;
  int index_counts[3];
  int* perm;                       /* perm[k]: natural index of the handle's component k */
  double *y, *yp, *res, *J, *ydot; /* natural-order scratch (ny; J ny x ny) */
  double* y_perturbed;
  long residual_evals, jacobian_evals, rhs_evals;
} f3r_peer;

static char last_error[512];

static int fail(int code, const char* format, ...) {
  va_list ap;
  va_start(ap, format);
  vsnprintf(last_error, sizeof last_error, format, ap);
  va_end(ap);
  return code;
}

F3R_PEER_EXPORT const char* f3r_peer_last_error(void) { return last_error; }

F3R_PEER_EXPORT void f3r_peer_destroy(f3r_peer* p) {
  if (!p) return;
  f3r_workspace_destroy(p->ws);
  f3r_model_destroy(p->model);
  free(p->perm);
  free(p->y);
  free(p->yp);
  free(p->res);
  free(p->J);
  free(p->ydot);
  free(p->y_perturbed);
  free(p);
}

F3R_PEER_EXPORT int f3r_peer_create(const char* scene_path, int formulation, int algebraic_last,
                                    f3r_peer** out) {
  if (!scene_path || !out) return fail(F3R_ERR_ARGUMENT, "f3r_peer_create: NULL argument");
  *out = NULL;
  if (formulation != F3R_FORMULATION_DAE && formulation != F3R_FORMULATION_MINIMAL &&
      formulation != F3R_FORMULATION_INDEX3)
    return fail(F3R_ERR_ARGUMENT, "formulation %d: 0 (dae), 1 (minimal) or 2 (index3)",
                formulation);
  f3r_scene scene;
  f3r_error err = {0};
  f3r_status st = f3r_scene_load(scene_path, &scene, &err);
  if (st != F3R_OK) return fail(st, "%s", err.message);
  /* the model does not depend on the formulation; a scene names only those a simulation runs */
  scene.formulation =
      formulation == F3R_FORMULATION_MINIMAL ? F3R_FORMULATION_MINIMAL : F3R_FORMULATION_DAE;
  if (scene.integrator == F3R_INTEGRATOR_ERK) scene.integrator = F3R_INTEGRATOR_IDA;
  f3r_peer* p = calloc(1, sizeof *p);
  if (!p) return fail(F3R_ERR_MEMORY, "f3r_peer_create: out of memory");
  st = f3r_model_create(&scene, &p->model, &err);
  f3r_scene_free(&scene); /* the model keeps its own copy of the tables */
  if (st != F3R_OK) {
    f3r_peer_destroy(p);
    return fail(st, "%s: %s", scene_path, err.message);
  }
  p->form = (f3r_formulation)formulation;
  p->ny = f3r_state_size(p->model, p->form);
  const size_t n = (size_t)p->ny;
  p->ws = f3r_workspace_create(p->model);
  p->perm = calloc(n, sizeof(int));
  p->y = calloc(n, sizeof(double));
  p->yp = calloc(n, sizeof(double));
  p->res = calloc(n, sizeof(double));
  p->J = calloc(n * n, sizeof(double));
  p->ydot = calloc(n, sizeof(double));
  p->y_perturbed = calloc(n, sizeof(double));
  if (!p->ws || !p->perm || !p->y || !p->yp || !p->res || !p->J || !p->ydot || !p->y_perturbed) {
    f3r_peer_destroy(p);
    return fail(F3R_ERR_MEMORY, "f3r_peer_create: out of memory");
  }
  /* each component's class: its differentiation index less one (index3), or 1 for the
   * algebraic components of the other forms; algebraic_last sorts y by class, stably */
  int* cls = p->perm; /* borrowed: the classes move to y before perm is written */
  f3r_state_kinds(p->model, p->form, p->y); /* borrow y for the kinds */
  for (int i = 0; i < p->ny; ++i) p->nalg += p->y[i] == 0.0;
  if (p->form == F3R_FORMULATION_INDEX3) {
    f3r_index3_variable_indices(p->model, cls, p->index_counts);
    for (int i = 0; i < p->ny; ++i) p->y[i] = cls[i] - 1;
  } else {
    p->index_counts[0] = p->ny - p->nalg;
    p->index_counts[1] = p->nalg;
    for (int i = 0; i < p->ny; ++i) p->y[i] = p->y[i] == 0.0;
  }
  int k = 0;
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < p->ny; ++i)
      if (algebraic_last ? p->y[i] == c : c == 0) p->perm[k++] = i;
  memset(p->y, 0, n * sizeof(double));
  *out = p;
  return F3R_OK;
}

F3R_PEER_EXPORT int f3r_peer_state_size(const f3r_peer* p) { return p->ny; }
F3R_PEER_EXPORT int f3r_peer_algebraic_count(const f3r_peer* p) { return p->nalg; }
F3R_PEER_EXPORT void f3r_peer_index_counts(const f3r_peer* p, int* counts) {
  for (int k = 0; k < 3; ++k) counts[k] = p->index_counts[k];
}
F3R_PEER_EXPORT double f3r_peer_duration(const f3r_peer* p) { return p->model->scene.duration; }
F3R_PEER_EXPORT int f3r_peer_end_stops(const f3r_peer* p) { return p->model->scene.end_stops; }

F3R_PEER_EXPORT int f3r_peer_breakpoints(const f3r_peer* p, double* times, int max) {
  int count = 0;
  for (int k = 0; k < p->model->n_breakpoints; ++k)
    if (p->model->breakpoints[k] > 0.0 && p->model->breakpoints[k] < p->model->scene.duration) {
      if (count < max) times[count] = p->model->breakpoints[k];
      ++count;
    }
  return count;
}

/* Handle order <-> natural order. */
static void to_natural(const f3r_peer* p, const double* in, double* out) {
  for (int k = 0; k < p->ny; ++k) out[p->perm[k]] = in[k];
}
static void from_natural(const f3r_peer* p, const double* in, double* out) {
  for (int k = 0; k < p->ny; ++k) out[k] = in[p->perm[k]];
}

F3R_PEER_EXPORT void f3r_peer_state_kinds(const f3r_peer* p, double* id) {
  f3r_state_kinds(p->model, p->form, p->res);
  from_natural(p, p->res, id);
}

/* Consistent y, yp (handle order) at t from full q, v, lag states and work. */
static int consistent(f3r_peer* p, double t, const double* q, const double* v, const double* lag,
                      double work, double* y, double* yp) {
  const double t_forces = nextafter(t, INFINITY); /* the right limit, as the CLI */
  const f3r_status st = f3r_consistent_state(p->model, p->form, t_forces, q, v, NULL, lag, work,
                                             p->y, p->yp, NULL, p->ws);
  if (st != F3R_OK)
    return fail(
        st, "no consistent state at t = %.9g: %s", t,
        st == F3R_ERR_SINGULAR ? "the constrained mass matrix is singular" : "non-finite values");
  from_natural(p, p->y, y);
  from_natural(p, p->yp, yp);
  return F3R_OK;
}

F3R_PEER_EXPORT int f3r_peer_initial_state(f3r_peer* p, double* y, double* yp) {
  double q[F3R_MAX_Q], v[F3R_MAX_Q];
  if (f3r_model_initial_state(p->model, q, v) != F3R_OK)
    return fail(F3R_ERR_SCENE, "initial.platform_pose: the legs cannot reach it");
  return consistent(p, 0.0, q, v, NULL, 0.0, y, yp);
}

F3R_PEER_EXPORT int f3r_peer_restart_state(f3r_peer* p, double t, double* y, double* yp) {
  double q[F3R_MAX_Q], v[F3R_MAX_Q], lag[3];
  double* natural = p->y_perturbed;
  to_natural(p, y, natural);
  const f3r_status st = f3r_state_to_full(p->model, p->form, natural, q, v);
  if (st != F3R_OK) return fail(st, "the state at t = %.9g does not close the loops", t);
  for (int i = 0; i < p->model->n_lag; ++i) lag[i] = natural[f3r_lag_index(p->model, p->form) + i];
  return consistent(p, t, q, v, p->model->n_lag ? lag : NULL, natural[p->ny - 1], y, yp);
}

F3R_PEER_EXPORT int f3r_peer_residual(f3r_peer* p, double t, const double* y, const double* yp,
                                      double* res) {
  ++p->residual_evals;
  to_natural(p, y, p->y);
  to_natural(p, yp, p->yp);
  const f3r_status st = f3r_residual(p->model, p->form, t, p->y, p->yp, NULL, p->res, p->ws);
  if (st != F3R_OK) return fail(st, "residual at t = %.9g: %s", t, f3r_status_name(st));
  from_natural(p, p->res, res);
  return F3R_OK;
}

F3R_PEER_EXPORT int f3r_peer_jacobian(f3r_peer* p, double t, double cj, const double* y,
                                      const double* yp, double* J) {
  ++p->jacobian_evals;
  const int ny = p->ny;
  to_natural(p, y, p->y);
  to_natural(p, yp, p->yp);
  const f3r_status st =
      f3r_residual_jacobian(p->model, p->form, t, cj, p->y, p->yp, NULL, p->J, ny, p->ws);
  if (st != F3R_OK) return fail(st, "Jacobian at t = %.9g: %s", t, f3r_status_name(st));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < ny; ++i) J[(size_t)j * ny + i] = p->J[(size_t)p->perm[j] * ny + p->perm[i]];
  return F3R_OK;
}

F3R_PEER_EXPORT int f3r_peer_rhs(f3r_peer* p, double t, const double* y, double* ydot) {
  if (p->form != F3R_FORMULATION_MINIMAL)
    return fail(F3R_ERR_ARGUMENT, "the explicit RHS is the minimal formulation's");
  ++p->rhs_evals;
  const f3r_status st = f3r_explicit_rhs(p->model, t, y, NULL, ydot, p->ws);
  if (st != F3R_OK) return fail(st, "RHS at t = %.9g: %s", t, f3r_status_name(st));
  return F3R_OK;
}

F3R_PEER_EXPORT int f3r_peer_rhs_jacobian(f3r_peer* p, double t, const double* y,
                                          const double* ydot, double* J) {
  if (p->form != F3R_FORMULATION_MINIMAL)
    return fail(F3R_ERR_ARGUMENT, "the explicit RHS is the minimal formulation's");
  ++p->jacobian_evals;
  const int ny = p->ny;
  int st = F3R_OK;
  if (!ydot) {
    if ((st = f3r_peer_rhs(p, t, y, p->ydot)) != F3R_OK) return st;
    ydot = p->ydot;
  }
  double* f1 = p->res;
  memcpy(p->y_perturbed, y, (size_t)ny * sizeof(double));
  for (int j = 0; j < ny; ++j) {
    /* W (the last component) enters nothing: its column is zero */
    if (j == ny - 1) {
      for (int i = 0; i < ny; ++i) J[(size_t)i * ny + j] = 0.0;
      continue;
    }
    const double inc = 1.5e-8 * fmax(fabs(y[j]), 1e-3);
    p->y_perturbed[j] = y[j] + inc;
    st = f3r_peer_rhs(p, t, p->y_perturbed, f1);
    p->y_perturbed[j] = y[j];
    if (st != F3R_OK) return st;
    for (int i = 0; i < ny; ++i) J[(size_t)i * ny + j] = (f1[i] - ydot[i]) / inc;
  }
  return F3R_OK;
}

F3R_PEER_EXPORT int f3r_peer_end_effector(const f3r_peer* p, const double* y, double* xy) {
  double q[F3R_MAX_Q], v[F3R_MAX_Q];
  double* natural = p->y_perturbed;
  to_natural(p, y, natural);
  const f3r_status st = f3r_state_to_full(p->model, p->form, natural, q, v);
  if (st != F3R_OK) return fail(st, "the state does not close the loops");
  xy[0] = q[6];
  xy[1] = q[7];
  return F3R_OK;
}

F3R_PEER_EXPORT void f3r_peer_counts(const f3r_peer* p, long* counts) {
  counts[0] = p->residual_evals;
  counts[1] = p->jacobian_evals;
  counts[2] = p->rhs_evals;
}

F3R_PEER_EXPORT void f3r_peer_reset_counts(f3r_peer* p) {
  p->residual_evals = p->jacobian_evals = p->rhs_evals = 0;
}

/* --- deSolve (R) ----------------------------------------------------------------------------- */

static f3r_peer* r_handle;

F3R_PEER_EXPORT void f3r_peer_r_close(void) {
  f3r_peer_destroy(r_handle);
  r_handle = NULL;
}

F3R_PEER_EXPORT void f3r_peer_r_open(char** path, int* formulation, int* ny, int* nalg,
                                     double* duration, int* n_breakpoints, int* status) {
  f3r_peer_r_close();
  *status = f3r_peer_create(path[0], *formulation, 1, &r_handle);
  if (*status != F3R_OK) return;
  *ny = r_handle->ny;
  *nalg = r_handle->nalg;
  *duration = f3r_peer_duration(r_handle);
  *n_breakpoints = f3r_peer_breakpoints(r_handle, NULL, 0);
  *status = r_handle->model->scene.end_stops
                ? fail(F3R_ERR_ARGUMENT, "end stops (impacts) are not supported by the peers")
                : F3R_OK;
}

F3R_PEER_EXPORT void f3r_peer_r_index_counts(int* counts) {
  for (int k = 0; k < 3; ++k) counts[k] = r_handle ? r_handle->index_counts[k] : 0;
}

F3R_PEER_EXPORT void f3r_peer_r_initial(double* y, double* yp, int* status) {
  *status =
      r_handle ? f3r_peer_initial_state(r_handle, y, yp) : fail(F3R_ERR_ARGUMENT, "no open handle");
}

F3R_PEER_EXPORT void f3r_peer_r_restart(double* t, double* y, double* yp, int* status) {
  *status = r_handle ? f3r_peer_restart_state(r_handle, *t, y, yp)
                     : fail(F3R_ERR_ARGUMENT, "no open handle");
}

F3R_PEER_EXPORT void f3r_peer_r_breakpoints(double* times, int* n) {
  *n = r_handle ? f3r_peer_breakpoints(r_handle, times, *n) : 0;
}

F3R_PEER_EXPORT void f3r_peer_r_end_effector(int* rows, double* Y, double* x, double* y) {
  if (!r_handle) return;
  const int ny = r_handle->ny;
  double* state = r_handle->ydot; /* scratch */
  for (int r = 0; r < *rows; ++r) {
    for (int k = 0; k < ny; ++k) state[k] = Y[(size_t)k * (size_t)(*rows) + (size_t)r];
    double xy[2] = {NAN, NAN};
    f3r_peer_end_effector(r_handle, state, xy);
    x[r] = xy[0];
    y[r] = xy[1];
  }
}

F3R_PEER_EXPORT void f3r_peer_r_counts(double* counts) {
  long c[3] = {0, 0, 0};
  if (r_handle) {
    f3r_peer_counts(r_handle, c);
    f3r_peer_reset_counts(r_handle);
  }
  for (int i = 0; i < 3; ++i) counts[i] = (double)c[i];
}

F3R_PEER_EXPORT void f3r_peer_r_message(char** message) {
  snprintf(message[0], 512, "%s", last_error);
}

F3R_PEER_EXPORT void f3r_peer_desolve_res(double* t, double* y, double* yprime, double* cj,
                                          double* delta, int* ires, double* yout, int* ip) {
  (void)cj, (void)yout, (void)ip;
  if (!r_handle) {
    *ires = -2;
    return;
  }
  if (f3r_peer_residual(r_handle, *t, y, yprime, delta) != F3R_OK) *ires = -1;
}

F3R_PEER_EXPORT void f3r_peer_desolve_jac(double* t, double* y, double* yprime, double* pd,
                                          double* cj, double* rpar, int* ipar) {
  (void)rpar, (void)ipar;
  if (!r_handle) return;
  if (f3r_peer_jacobian(r_handle, *t, *cj, y, yprime, pd) != F3R_OK)
    /* a zero matrix is singular: DASPK then cuts the step, as for a failed residual */
    memset(pd, 0, (size_t)r_handle->ny * (size_t)r_handle->ny * sizeof(double));
}

F3R_PEER_EXPORT void f3r_peer_mebdfi_jac(double* t, double* y, double* yprime, double* pd,
                                         double* con, double* rpar, int* ipar) {
  double cj = 1.0 / *con;
  f3r_peer_desolve_jac(t, y, yprime, pd, &cj, rpar, ipar);
}
