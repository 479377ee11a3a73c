/* Two split candidates for #59, as benchmark prototypes, not simulation back ends: the minimal
 * ODE y' = f(y) split as f = f_S + f_F with the fast part linear, f_F(y) = J_F (y - y_ref), J_F
 * the columns of f's Jacobian for the modal coordinates and their rates (the elastic
 * oscillations and what they drive), refreshed every `refresh` s of the path. The split is exact
 * (f_S is f minus f_F), so a stale J_F costs accuracy of the method, not of the model.
 *   multirate: SUNDIALS' MRIStep with a fixed slow step (6.4 has no slow adaptivity) over an
 *              adaptive explicit inner ARKStep;
 *   --imex:    ARKStep's additive Runge-Kutta, f_F implicit (linear: one Newton iteration on a
 *              dense LU of I - gamma J_F) and f_S explicit, with ARKODE's adaptive step.
 * Prints the end-effector path at 1 ms (t, X_p, Y_p) as CSV and, on stderr, CPU seconds, steps
 * and right-hand sides.
 *   f3r_mri SCENE.yaml SLOW_STEP INNER_RTOL [REFRESH_S] [ORDER] [INNER_ORDER]
 *   f3r_mri --imex SCENE.yaml RTOL REFRESH_S [ORDER] */
#include <stdio.h> /* first: arkode_butcher.h uses FILE without including it */

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_mristep.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "flex3rpr/sim.h"
#include "model_layout.h"
#include "residual.h"

typedef struct {
  const f3r_model* model;
  f3r_workspace* ws;
  int ny, nz;
  double* JF;    /* ny x ny, column-major: the fast columns only */
  double* yref;  /* the state the fast part is linear about */
  double* work;  /* ny */
  int* fast;     /* 1 for the columns of the modal coordinates and rates */
  long full_rhs; /* f3r_explicit_rhs calls, the Jacobian's included */
  double refresh, refreshed_at;
} split;

static void fast_part(const split* s, const double* y, double* out) {
  for (int i = 0; i < s->ny; ++i) out[i] = 0.0;
  for (int j = 0; j < s->ny; ++j) {
    if (!s->fast[j]) continue;
    const double d = y[j] - s->yref[j];
    const double* col = s->JF + (size_t)j * s->ny;
    for (int i = 0; i < s->ny; ++i) out[i] += col[i] * d;
  }
}

/* J_F at y: central differences of f in the fast columns. */
static void linearise(split* s, double t, const double* y) {
  double* yy = malloc(sizeof(double) * s->ny);
  double* fp = malloc(sizeof(double) * s->ny);
  double* fm = malloc(sizeof(double) * s->ny);
  memcpy(yy, y, sizeof(double) * s->ny);
  memcpy(s->yref, y, sizeof(double) * s->ny);
  for (int j = 0; j < s->ny; ++j) {
    if (!s->fast[j]) continue;
    const double h = 1e-7 * fmax(1.0, fabs(y[j]));
    yy[j] = y[j] + h;
    f3r_explicit_rhs(s->model, t, yy, NULL, fp, s->ws);
    yy[j] = y[j] - h;
    f3r_explicit_rhs(s->model, t, yy, NULL, fm, s->ws);
    yy[j] = y[j];
    s->full_rhs += 2;
    for (int i = 0; i < s->ny; ++i) s->JF[(size_t)j * s->ny + i] = (fp[i] - fm[i]) / (2 * h);
  }
  s->refreshed_at = t;
  free(yy);
  free(fp);
  free(fm);
}

static int slow_rhs(realtype t, N_Vector y, N_Vector ydot, void* user) {
  split* s = user;
  const double* yy = N_VGetArrayPointer(y);
  double* out = N_VGetArrayPointer(ydot);
  ++s->full_rhs;
  if (f3r_explicit_rhs(s->model, t, yy, NULL, out, s->ws) != F3R_OK) return 1;
  fast_part(s, yy, s->work);
  for (int i = 0; i < s->ny; ++i) out[i] -= s->work[i];
  return 0;
}

static int fast_rhs(realtype t, N_Vector y, N_Vector ydot, void* user) {
  (void)t;
  fast_part(user, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  return 0;
}

/* After each slow step: a new linearisation when refresh has passed (the split changes only
 * between slow steps, where f = f_S + f_F holds for either). */
static int after_step(realtype t, N_Vector y, void* user) {
  split* s = user;
  if (s->refresh > 0 && t - s->refreshed_at >= s->refresh - 1e-12)
    linearise(s, t, N_VGetArrayPointer(y));
  return 0;
}

static int imex_after_step(realtype t, N_Vector y, void* user) { return after_step(t, y, user); }

/* The implicit part's Jacobian: J_F, exact for the linear fast part. */
static int fast_jacobian(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user, N_Vector t1,
                         N_Vector t2, N_Vector t3) {
  (void)t, (void)y, (void)fy, (void)t1, (void)t2, (void)t3;
  const split* s = user;
  for (int j = 0; j < s->ny; ++j) {
    double* col = SUNDenseMatrix_Column(J, j);
    for (int i = 0; i < s->ny; ++i) col[i] = s->fast[j] ? s->JF[(size_t)j * s->ny + i] : 0.0;
  }
  return 0;
}

static double cpu(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* The path at 1 ms (t, X_p, Y_p) as CSV from either stepper's Evolve; 1 when it fails. */
typedef int evolve_fn(void* mem, realtype tout, N_Vector y, realtype* t, int task);
static int print_path(evolve_fn* evolve, const char* name, void* mem, N_Vector y, double duration) {
  printf("t,x_p,y_p\n");
  const double* yy = N_VGetArrayPointer(y);
  printf("%.6g,%.17g,%.17g\n", 0.0, yy[0], yy[1]);
  for (int k = 1; k * 1e-3 <= duration + 1e-12; ++k) {
    realtype t = 0.0;
    const int flag = evolve(mem, k * 1e-3, y, &t, ARK_NORMAL);
    if (flag < 0) {
      fprintf(stderr, "%s: %d at t = %g\n", name, flag, t);
      return 1;
    }
    printf("%.6g,%.17g,%.17g\n", k * 1e-3, yy[0], yy[1]);
  }
  return 0;
}

/* The path under ARKStep IMEX; prints it and the counts as main's multirate run does. */
static int run_imex(split* s, const f3r_scene* scene, N_Vector y, SUNContext ctx, double rtol,
                    int order, double t0) {
  void* ark = ARKStepCreate(slow_rhs, fast_rhs, 0.0, y, ctx);
  /* F3R_MRI_LOOSE=K: the error test's weights on the links' last modes (coordinate and rate)
   * K times looser, so that the step may pass over them (the quasi-static limit of L-stable ARK) */
  N_Vector atol = N_VNew_Serial(s->ny, ctx);
  double* a = N_VGetArrayPointer(atol);
  for (int i = 0; i < s->ny; ++i) a[i] = rtol * 1e-2;
  const char* loose = getenv("F3R_MRI_LOOSE");
  const int per_link = (s->nz - 3) / 3;
  if (loose)
    for (int l = 0; l < 3; ++l) {
      const int k = 3 + per_link * l + per_link - 1;
      a[k] *= atof(loose);
      a[s->nz + k] *= atof(loose);
    }
  ARKStepSVtolerances(ark, rtol, atol);
  ARKStepSetUserData(ark, s);
  ARKStepSetMaxNumSteps(ark, 100000000L);
  ARKStepSetOrder(ark, order);
  SUNMatrix A = SUNDenseMatrix(s->ny, s->ny, ctx);
  SUNLinearSolver ls = SUNLinSol_Dense(y, A, ctx);
  ARKStepSetLinearSolver(ark, ls, A);
  ARKStepSetJacFn(ark, fast_jacobian);
  ARKStepSetLinear(ark, 0); /* J_F changes at refreshes: a new matrix each step is cheap */
  ARKStepSetLSetupFrequency(ark, 1);
  ARKStepSetJacEvalFrequency(ark, 1);
  ARKStepSetPostprocessStepFn(ark, imex_after_step);
  if (print_path(ARKStepEvolve, "ARKStepEvolve", ark, y, scene->duration)) return 1;
  const double seconds = cpu() - t0;
  long steps = 0, fe = 0, fi = 0, setups = 0, nni = 0;
  ARKStepGetNumSteps(ark, &steps);
  ARKStepGetNumRhsEvals(ark, &fe, &fi);
  ARKStepGetNumLinSolvSetups(ark, &setups);
  ARKStepGetNumNonlinSolvIters(ark, &nni);
  fprintf(stderr,
          "cpu %.6f steps %ld explicit_rhs %ld implicit_rhs %ld lu %ld newton %ld full_rhs %ld\n",
          seconds, steps, fe, fi, setups, nni, s->full_rhs);
  ARKStepFree(&ark);
  SUNLinSolFree(ls);
  SUNMatDestroy(A);
  return 0;
}

int main(int argc, char** argv) {
  const int imex = argc > 1 && strcmp(argv[1], "--imex") == 0;
  if (imex) ++argv, --argc;
  if (argc < 4) {
    fprintf(stderr,
            "usage: f3r_mri SCENE.yaml SLOW_STEP INNER_RTOL [REFRESH_S] [ORDER] [INNER_ORDER]\n");
    return 2;
  }
  const double slow_step = atof(argv[2]), inner_rtol = atof(argv[3]), rtol = atof(argv[2]);
  f3r_scene scene;
  f3r_error err = {0};
  if (f3r_scene_load(argv[1], &scene, &err) != F3R_OK) {
    fprintf(stderr, "%s\n", err.message);
    return 1;
  }
  scene.formulation = F3R_FORMULATION_MINIMAL;
  f3r_model* model = NULL;
  f3r_sim* sim = NULL;
  if (f3r_model_create(&scene, &model, &err) != F3R_OK ||
      f3r_sim_create(model, NULL, &sim, &err) != F3R_OK) {
    fprintf(stderr, "%s\n", err.message);
    return 1;
  }
  split s = {0};
  s.model = model;
  s.ws = f3r_workspace_create(model);
  s.ny = f3r_state_size(model, F3R_FORMULATION_MINIMAL);
  s.nz = (s.ny - 1) / 2;
  s.refresh = argc > 4 ? atof(argv[4]) : 0.0;
  if (imex) s.refresh = atof(argv[3]);
  s.JF = calloc((size_t)s.ny * s.ny, sizeof(double));
  s.yref = calloc(s.ny, sizeof(double));
  s.work = calloc(s.ny, sizeof(double));
  s.fast = calloc(s.ny, sizeof(int));
  for (int k = 3; k < s.nz; ++k) s.fast[k] = s.fast[s.nz + k] = 1; /* eta and eta' */
  SUNContext ctx = NULL;
  SUNContext_Create(NULL, &ctx);
  N_Vector y = N_VNew_Serial(s.ny, ctx);
  memcpy(N_VGetArrayPointer(y), f3r_sim_state(sim), sizeof(double) * s.ny);
  const double t0 = cpu();
  linearise(&s, 0.0, N_VGetArrayPointer(y));
  if (imex) return run_imex(&s, &scene, y, ctx, rtol, argc > 4 ? atoi(argv[4]) : 4, t0);
  void* inner = ARKStepCreate(fast_rhs, NULL, 0.0, y, ctx);
  ARKStepSStolerances(inner, inner_rtol, inner_rtol * 1e-2);
  ARKStepSetUserData(inner, &s);
  ARKStepSetMaxNumSteps(inner, 100000000L);
  ARKStepSetOrder(inner, argc > 6 ? atoi(argv[6]) : 5);
  MRIStepInnerStepper stepper = NULL;
  ARKStepCreateMRIStepInnerStepper(inner, &stepper);
  void* mri = MRIStepCreate(slow_rhs, NULL, 0.0, y, stepper, ctx);
  MRIStepSetUserData(mri, &s);
  MRIStepSetFixedStep(mri, slow_step);
  MRIStepSetMaxNumSteps(mri, 100000000L);
  if (argc > 5) MRIStepSetOrder(mri, atoi(argv[5]));
  MRIStepSetPostprocessStepFn(mri, after_step);
  if (print_path(MRIStepEvolve, "MRIStepEvolve", mri, y, scene.duration)) return 1;
  const double seconds = cpu() - t0;
  long slow = 0, fast = 0, fe = 0, fi = 0;
  MRIStepGetNumSteps(mri, &slow);
  ARKStepGetNumSteps(inner, &fast);
  ARKStepGetNumRhsEvals(inner, &fe, &fi);
  fprintf(stderr, "cpu %.6f slow_steps %ld fast_steps %ld fast_rhs %ld full_rhs %ld\n", seconds,
          slow, fast, fe, s.full_rhs);
  MRIStepFree(&mri);
  MRIStepInnerStepper_Free(&stepper);
  ARKStepFree(&inner);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  return 0;
}
