/* The linearised model and its modal response (include/flex3rpr/linear.h). Everything comes
 * from the public minimal residual, so the linear model is exactly the simulated one's tangent. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "linear_parts.h"
#include "dense.h"
#include "flex3rpr/linear.h"
#include "model_layout.h"
#include "residual.h"

void f3r_linear_destroy(f3r_linear_model* lin) { free(lin); }

/* One allocation: the struct, then its arrays (n minimal coordinates), zeroed. */
static f3r_linear_model* linear_alloc(int n) {
  const size_t nn = (size_t)n * n, head = (sizeof(f3r_linear_model) + 7) / sizeof(double);
  double* block = calloc(head + 4 * nn + (size_t)n * (F3R_RIGID_FORCES + 3), sizeof(double));
  f3r_linear_model* lin = (f3r_linear_model*)block;
  if (!lin) return NULL;
  lin->n = n;
  lin->mass = block + head;
  lin->damping = lin->mass + nn;
  lin->stiffness = lin->damping + nn;
  lin->shapes = lin->stiffness + nn;
  lin->input = lin->shapes + nn;
  lin->static_force = lin->input + (size_t)n * F3R_RIGID_FORCES;
  lin->omega2 = lin->static_force + n;
  lin->modal_damping = lin->omega2 + n;
  return lin;
}

f3r_status f3r_linear_mass_factor(const f3r_linear_model* lin, double* L, const char* who,
                                  f3r_error* err) {
  memcpy(L, lin->mass, (size_t)lin->n * lin->n * sizeof(double));
  if (f3r_cholesky_factor(L, lin->n))
    return f3r_error_set(err, F3R_ERR_SINGULAR,
                         "%s: the reduced mass matrix is not positive definite", who);
  return F3R_OK;
}

/* Phi and omega^2 of K Phi = M Phi diag(omega^2): M = L L^T, C = L^-1 K L^-T = V diag V^T,
 * Phi = L^-T V; then sorted by omega^2. */
static f3r_status modes(f3r_linear_model* lin, f3r_error* err) {
  const int n = lin->n;
  double* L = malloc((size_t)n * n * sizeof(double));
  double* C = malloc((size_t)n * n * sizeof(double));
  double* V = malloc((size_t)n * n * sizeof(double));
  double* eig = malloc((size_t)n * sizeof(double));
  int* order = malloc((size_t)n * sizeof(int));
  f3r_status st = F3R_OK;
  if (!L || !C || !V || !eig || !order) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "linearisation: out of memory");
    goto done;
  }
  if ((st = f3r_linear_mass_factor(lin, L, "linearisation", err)) != F3R_OK) goto done;
  memcpy(C, lin->stiffness, (size_t)n * n * sizeof(double));
  for (int pass = 0; pass < 2; ++pass) { /* C <- L^-1 C, then transpose: twice gives L^-1 K L^-T */
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double s = F3R_AT(C, n, i, j);
        for (int k = 0; k < i; ++k) s -= F3R_AT(L, n, i, k) * F3R_AT(C, n, k, j);
        F3R_AT(C, n, i, j) = s / F3R_AT(L, n, i, i);
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < j; ++i) {
        const double t = F3R_AT(C, n, i, j);
        F3R_AT(C, n, i, j) = F3R_AT(C, n, j, i);
        F3R_AT(C, n, j, i) = t;
      }
  }
  for (int j = 0; j < n; ++j) /* symmetric up to rounding */
    for (int i = 0; i < j; ++i)
      F3R_AT(C, n, i, j) = F3R_AT(C, n, j, i) = 0.5 * (F3R_AT(C, n, i, j) + F3R_AT(C, n, j, i));
  f3r_symmetric_eigen(C, n, eig, V);
  for (int j = 0; j < n; ++j) { /* Phi = L^-T V: back substitution with L^T */
    for (int i = n - 1; i >= 0; --i) {
      double s = F3R_AT(V, n, i, j);
      for (int k = i + 1; k < n; ++k) s -= F3R_AT(L, n, k, i) * F3R_AT(V, n, k, j);
      F3R_AT(V, n, i, j) = s / F3R_AT(L, n, i, i);
    }
  }
  for (int j = 0; j < n; ++j) order[j] = j;
  for (int a = 1; a < n; ++a) /* insertion sort by eigenvalue: n is at most 63 */
    for (int b = a; b > 0 && eig[order[b]] < eig[order[b - 1]]; --b) {
      const int t = order[b];
      order[b] = order[b - 1];
      order[b - 1] = t;
    }
  for (int j = 0; j < n; ++j) {
    const int from = order[j];
    lin->omega2[j] = eig[from];
    memcpy(lin->shapes + (size_t)j * n, V + (size_t)from * n, (size_t)n * sizeof(double));
    double d = 0.0;
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a)
        d += F3R_AT(lin->shapes, n, a, j) * F3R_AT(lin->damping, n, a, b) *
             F3R_AT(lin->shapes, n, b, j);
    lin->modal_damping[j] = d;
  }
done:
  free(L), free(C), free(V), free(eig), free(order);
  return st;
}

/* The model with its applied forces taken as held forces (no scripted inputs, no actuator lag:
 * the lag is applied to them already), or NULL when out of memory. A view: the struct alone, on
 * the heap, its arrays still model's (which outlives it); free() it. */
static f3r_model* held_forces_model(const f3r_model* model) {
  f3r_model* m = malloc(sizeof *m);
  if (!m) return NULL;
  *m = *model;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) /* kind F3R_INPUT_NONE, no table */
    m->scene.inputs[k] = (f3r_input){.kind = F3R_INPUT_NONE};
  m->n_lag = 0;
  m->n_breakpoints = 0;
  return m;
}

f3r_status f3r_linearise(const f3r_model* model, f3r_linear_model** out, f3r_error* err) {
  *out = NULL;
  f3r_model* m = held_forces_model(model); /* without the scripted inputs and actuator lag */
  if (!m) return f3r_error_set(err, F3R_ERR_MEMORY, "linearisation: out of memory");
  const int n = m->n_independent, ny = f3r_state_size(m, F3R_FORMULATION_MINIMAL);
  f3r_linear_model* lin = linear_alloc(n);
  f3r_workspace* ws = f3r_workspace_create(m);
  double* y = calloc((size_t)ny, sizeof(double));
  double* yp = calloc((size_t)ny, sizeof(double));
  double* res = calloc((size_t)ny, sizeof(double));
  double* res0 = calloc((size_t)ny, sizeof(double));
  double* J0 = calloc((size_t)ny * ny, sizeof(double));
  double* J1 = calloc((size_t)ny * ny, sizeof(double));
  double held[F3R_MAX_Q] = {0};
  f3r_status st = F3R_OK;
  if (!lin || !ws || !y || !yp || !res || !res0 || !J0 || !J1) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "linearisation: out of memory");
    goto done;
  }
  for (int k = 0; k < 3; ++k) y[k] = m->scene.platform_pose0[k];
  /* Rows n..2n of the residual are the reduced equations B^T (M a + h + k - Q): dF/dz at cj = 0
   * is K, dF/du is D, and the cj = 1 Jacobian less the cj = 0 one on the u columns is M. */
  if ((st = f3r_residual_jacobian(m, F3R_FORMULATION_MINIMAL, 0.0, 0.0, y, yp, NULL, J0, ny, ws)) ||
      (st = f3r_residual_jacobian(m, F3R_FORMULATION_MINIMAL, 0.0, 1.0, y, yp, NULL, J1, ny, ws)) ||
      (st = f3r_residual(m, F3R_FORMULATION_MINIMAL, 0.0, y, yp, NULL, res0, ws))) {
    st = f3r_error_set(err, st, "linearisation: the initial pose cannot be linearised");
    goto done;
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      F3R_AT(lin->stiffness, n, i, j) = F3R_AT(J0, ny, n + i, j);
      F3R_AT(lin->damping, n, i, j) = F3R_AT(J0, ny, n + i, n + j);
      F3R_AT(lin->mass, n, i, j) = F3R_AT(J1, ny, n + i, n + j) - F3R_AT(J0, ny, n + i, n + j);
    }
  for (int j = 0; j < n; ++j) /* symmetric in exact arithmetic; K only up to the static loads */
    for (int i = 0; i < j; ++i) {
      double* mats[2] = {lin->mass, lin->stiffness};
      for (int k = 0; k < 2; ++k)
        F3R_AT(mats[k], n, i, j) = F3R_AT(mats[k], n, j, i) =
            0.5 * (F3R_AT(mats[k], n, i, j) + F3R_AT(mats[k], n, j, i));
    }
  for (int i = 0; i < n; ++i) lin->static_force[i] = -res0[n + i];
  /* The residual is affine in the applied forces: a unit held force less none is -U's column. */
  for (int f = 0; f < F3R_RIGID_FORCES; ++f) {
    held[f] = 1.0;
    st = f3r_residual(m, F3R_FORMULATION_MINIMAL, 0.0, y, yp, held, res, ws);
    held[f] = 0.0;
    if (st != F3R_OK) {
      st = f3r_error_set(err, st, "linearisation: the initial pose cannot be linearised");
      goto done;
    }
    for (int i = 0; i < n; ++i) F3R_AT(lin->input, n, i, f) = -(res[n + i] - res0[n + i]);
  }
  st = modes(lin, err);
done:
  f3r_workspace_destroy(ws);
  free(y), free(yp), free(res), free(res0), free(J0), free(J1), free(m);
  if (st == F3R_OK)
    *out = lin;
  else
    f3r_linear_destroy(lin);
  return st;
}

/* E = exp(A h) of the 4 x 4 augmented mode [xi, xi', p, p'] with xi'' = -c xi' - k xi + p and p
 * linear in time (p'' = 0): scaling and squaring of a Taylor series. */
static void mode_transition(double k, double c, double h, double E[4][4]) {
  double A[4][4] = {{0, h, 0, 0}, {-k * h, -c * h, h, 0}, {0, 0, 0, h}, {0, 0, 0, 0}};
  double norm = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) norm = fmax(norm, fabs(A[i][j]));
  int squarings = 0;
  while (norm > 0.25 && squarings < 60) {
    norm *= 0.5;
    ++squarings;
  }
  const double scale = ldexp(1.0, -squarings);
  double term[4][4], next[4][4];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      A[i][j] *= scale;
      E[i][j] = term[i][j] = i == j ? 1.0 : 0.0;
    }
  for (int order = 1; order <= 14; ++order) {
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = 0.0;
        for (int l = 0; l < 4; ++l) s += term[i][l] * A[l][j];
        next[i][j] = s / order;
      }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) E[i][j] += (term[i][j] = next[i][j]);
  }
  for (int s = 0; s < squarings; ++s) {
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double v = 0.0;
        for (int l = 0; l < 4; ++l) v += E[i][l] * E[l][j];
        next[i][j] = v;
      }
    memcpy(E, next, sizeof next);
  }
}

/* The scripted inputs at t_k, through the actuator lag when there is one: u[k * 9 + f]. */
void f3r_linear_sample_inputs(const f3r_model* model, double dt, int count, double* u) {
  const f3r_scene* s = &model->scene;
  for (int f = 0; f < F3R_RIGID_FORCES; ++f) {
    const int lagged = model->n_lag && f < 3;
    const double decay = lagged ? exp(-dt / model->lag_time_constant) : 0.0;
    double applied = 0.0; /* the lag states start at zero */
    for (int k = 0; k < count; ++k) {
      const double command = f3r_input_value(&s->inputs[f], k * dt);
      if (lagged && k) applied = decay * applied + (1.0 - decay) * command; /* held over a sample */
      u[(size_t)k * F3R_RIGID_FORCES + f] = lagged ? applied : command;
    }
  }
}

/* Modal forces P (count per mode, mode after mode) of the forces F (n per sample): phi_j^T F_k. */
static void project(const f3r_linear_model* lin, int count, const double* F, double* P) {
  const int n = lin->n;
  for (int j = 0; j < n; ++j) {
    const double* phi = lin->shapes + (size_t)j * n;
    double* Pj = P + (size_t)j * count;
    for (int k = 0; k < count; ++k) {
      const double* Fk = F + (size_t)k * n;
      double v = 0.0;
      for (int a = 0; a < n; ++a) v += phi[a] * Fk[a];
      Pj[k] = v;
    }
  }
}

/* Mode phi's load phi^T (f0 + U u) as a constant and a gain per applied force. */
static void modal_load(const f3r_linear_model* lin, const double* phi, double* constant,
                       double gain[F3R_RIGID_FORCES]) {
  const int n = lin->n;
  *constant = 0.0;
  for (int f = 0; f < F3R_RIGID_FORCES; ++f) gain[f] = 0.0;
  for (int a = 0; a < n; ++a) {
    *constant += phi[a] * lin->static_force[a];
    for (int f = 0; f < F3R_RIGID_FORCES; ++f) gain[f] += phi[a] * F3R_AT(lin->input, n, a, f);
  }
}

/* The modal load at one sample of the applied forces u (F3R_RIGID_FORCES of them). */
static double modal_force(double constant, const double gain[F3R_RIGID_FORCES], const double* u) {
  double v = constant;
  for (int f = 0; f < F3R_RIGID_FORCES; ++f) v += gain[f] * u[f];
  return v;
}

/* Mode phi's initial coordinate and rate: phi^T M dz0 and phi^T M vz0. */
static void modal_start(const f3r_linear_model* lin, const double* phi, const double* dz0,
                        const double* vz0, double* xi, double* rate) {
  const int n = lin->n;
  *xi = *rate = 0.0;
  for (int a = 0; a < n; ++a) {
    double mdz = 0.0, mvz = 0.0;
    for (int b = 0; b < n; ++b) {
      mdz += F3R_AT(lin->mass, n, a, b) * dz0[b];
      mvz += F3R_AT(lin->mass, n, a, b) * vz0[b];
    }
    *xi += phi[a] * mdz;
    *rate += phi[a] * mvz;
  }
}

/* One modal superposition of modal forces P (linear between samples) from the initial deviation
 * dz0 and rate vz0 in z. Adds the pose deviation to pose (3 per sample) and, when z is not NULL,
 * writes the deviation, rate and acceleration of every coordinate (z, zd, zdd: n per sample). */
static void superpose(const f3r_linear_model* lin, double dt, int count, const double* P,
                      const double* dz0, const double* vz0, double* pose, double* z, double* zd,
                      double* zdd) {
  const int n = lin->n;
  if (z) {
    memset(z, 0, (size_t)n * count * sizeof(double));
    memset(zd, 0, (size_t)n * count * sizeof(double));
    memset(zdd, 0, (size_t)n * count * sizeof(double));
  }
  for (int j = 0; j < n; ++j) {
    const double* phi = lin->shapes + (size_t)j * n;
    const double* p = P + (size_t)j * count;
    double xi, rate;
    modal_start(lin, phi, dz0, vz0, &xi, &rate);
    double E[4][4];
    const double k2 = lin->omega2[j], c = lin->modal_damping[j];
    mode_transition(k2, c, dt, E);
    for (int k = 0; k < count; ++k) {
      if (k) {
        const double slope = (p[k] - p[k - 1]) / dt;
        const double x1 = E[0][0] * xi + E[0][1] * rate + E[0][2] * p[k - 1] + E[0][3] * slope;
        const double v1 = E[1][0] * xi + E[1][1] * rate + E[1][2] * p[k - 1] + E[1][3] * slope;
        xi = x1;
        rate = v1;
      }
      for (int a = 0; a < 3; ++a) pose[3 * k + a] += phi[a] * xi;
      if (z) {
        const double acc = p[k] - c * rate - k2 * xi;
        double *zk = z + (size_t)k * n, *zdk = zd + (size_t)k * n, *zddk = zdd + (size_t)k * n;
        for (int a = 0; a < n; ++a) {
          zk[a] += phi[a] * xi;
          zdk[a] += phi[a] * rate;
          zddk[a] += phi[a] * acc;
        }
      }
    }
  }
}

/* The modes superposed side by side in pose_superpose: each mode's step is a chain of dependent
 * sums, and POSE_BLOCK modes in the lanes of one vector (GCC's and Clang's vector extension)
 * step together. Each vector operation is the same IEEE operation on every lane, so the lanes
 * hold the scalar code's values. */
#define POSE_BLOCK 4
typedef double pose_lanes __attribute__((vector_size(POSE_BLOCK * sizeof(double))));

/* On x86-64, pose_superpose also in an AVX2 clone, chosen at load time where the processor has it:
 * its four lanes in one register. AVX2 without FMA: the same operations, the same bits. On
 * paper simulation 3 at 1e-4 m: the choosing 5.46 -> 5.18 ms. */
#if defined(__x86_64__) && defined(__GNUC__)
#define POSE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define POSE_CLONES
#endif

/* POSE_BLOCK modes from j0, a mode a lane (the last block padded with lanes that stay zero). */
typedef struct {
  int count;                         /* the real modes in the block */
  const double* phi[POSE_BLOCK];     /* their shapes */
  pose_lanes constant;               /* modal_load's constant */
  pose_lanes gain[F3R_RIGID_FORCES]; /* and gains */
  pose_lanes E[2][4];                /* mode_transition's first two rows */
  pose_lanes xi, rate, p_prev;       /* the modal coordinate, its rate and the last load */
} pose_block;

static void pose_block_start(const f3r_linear_model* lin, int j0, double dt, const double* u0,
                             const double* dz0, const double* vz0, pose_block* pb) {
  memset(pb, 0, sizeof *pb);
  pb->count = lin->n - j0 < POSE_BLOCK ? lin->n - j0 : POSE_BLOCK;
  for (int m = 0; m < pb->count; ++m) {
    const int j = j0 + m;
    const double* phi = pb->phi[m] = lin->shapes + (size_t)j * lin->n;
    double constant, gain[F3R_RIGID_FORCES], E[4][4], xi, rate;
    modal_load(lin, phi, &constant, gain);
    modal_start(lin, phi, dz0, vz0, &xi, &rate);
    mode_transition(lin->omega2[j], lin->modal_damping[j], dt, E);
    pb->constant[m] = constant;
    for (int f = 0; f < F3R_RIGID_FORCES; ++f) pb->gain[f][m] = gain[f];
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 4; ++c) pb->E[r][c][m] = E[r][c];
    pb->xi[m] = xi;
    pb->rate[m] = rate;
    pb->p_prev[m] = modal_force(constant, gain, u0);
  }
}

/* The first-order pose alone (superpose with z NULL and P = phi_j^T (f0 + U u_k)), fused: the
 * modal forces are formed per sample instead of stored, and POSE_BLOCK modes step side by side.
 * Every sum is formed in the same order as superpose's (pose[k] gains the modes by ascending j),
 * so the pose is bit-identical to it. On paper simulation 3 at 1e-4 m, where the choosing forms
 * nine such paths of 6 to 39 coordinates, it took the choosing from 7.4 to 6.4 ms. */
POSE_CLONES static void pose_superpose(const f3r_linear_model* lin, double dt, int count,
                                       const double* u, const double* dz0, const double* vz0,
                                       double* pose) {
  for (int j0 = 0; j0 < lin->n; j0 += POSE_BLOCK) {
    pose_block b;
    pose_block_start(lin, j0, dt, u, dz0, vz0, &b);
    for (int m = 0; m < b.count; ++m)
      for (int a = 0; a < 3; ++a) pose[a] += b.phi[m][a] * b.xi[m];
    for (int k = 1; k < count; ++k) {
      const double* uk = u + (size_t)k * F3R_RIGID_FORCES;
      pose_lanes p = b.constant;
      for (int f = 0; f < F3R_RIGID_FORCES; ++f) p += b.gain[f] * uk[f];
      const pose_lanes slope = (p - b.p_prev) / dt;
      const pose_lanes xi =
          b.E[0][0] * b.xi + b.E[0][1] * b.rate + b.E[0][2] * b.p_prev + b.E[0][3] * slope;
      b.rate = b.E[1][0] * b.xi + b.E[1][1] * b.rate + b.E[1][2] * b.p_prev + b.E[1][3] * slope;
      b.xi = xi;
      b.p_prev = p;
      double* pk = pose + 3 * (size_t)k;
      for (int m = 0; m < b.count; ++m)
        for (int a = 0; a < 3; ++a) pk[a] += b.phi[m][a] * xi[m];
    }
  }
}

/* The residual's remainder along the linear path: e = F_b(z, z', z''; u) less its linear part
 * M z'' + D z' + K dz - f0 - U u, second order in the motion. With `other` (a model of the same
 * coordinates), e is instead the difference of the two residuals, F_b of model less F_b of other:
 * what other adds along the path. A sample the loop closure cannot reach gets e = 0 and is
 * counted in *unreachable. */
static f3r_status second_order_remainder(const f3r_linear_model* lin, const f3r_model* model,
                                         const f3r_model* other, int count, const double* u,
                                         const double* z, const double* zd, const double* zdd,
                                         double* e, int* unreachable, f3r_error* err) {
  const int n = lin->n;
  f3r_model* m = held_forces_model(model);
  f3r_model* o = other ? held_forces_model(other) : NULL;
  const int ny = m ? f3r_state_size(m, F3R_FORMULATION_MINIMAL) : 0;
  f3r_workspace* ws = m ? f3r_workspace_create(m) : NULL;
  double* y = calloc((size_t)ny, sizeof(double));
  double* yp = calloc((size_t)ny, sizeof(double));
  double* res = calloc((size_t)ny, sizeof(double));
  double* res_other = calloc((size_t)ny, sizeof(double));
  double held[F3R_MAX_Q] = {0};
  if (!m || !ws || !y || !yp || !res || !res_other || (other && !o)) {
    f3r_workspace_destroy(ws);
    free(y), free(yp), free(res), free(res_other), free(o), free(m);
    return f3r_error_set(err, F3R_ERR_MEMORY, "linear response: out of memory");
  }
  *unreachable = 0;
  for (int k = 0; k < count; ++k) {
    const double *zk = z + (size_t)k * n, *zdk = zd + (size_t)k * n, *zddk = zdd + (size_t)k * n;
    double* ek = e + (size_t)k * n;
    for (int a = 0; a < n; ++a) {
      y[a] = zk[a] + (a < 3 ? model->scene.platform_pose0[a] : 0.0);
      y[n + a] = zdk[a];
      yp[a] = zdk[a];
      yp[n + a] = zddk[a];
    }
    memcpy(held, u + (size_t)k * F3R_RIGID_FORCES, F3R_RIGID_FORCES * sizeof(double));
    if (f3r_residual(m, F3R_FORMULATION_MINIMAL, 0.0, y, yp, held, res, ws) != F3R_OK ||
        (o &&
         f3r_residual(o, F3R_FORMULATION_MINIMAL, 0.0, y, yp, held, res_other, ws) != F3R_OK)) {
      memset(ek, 0, (size_t)n * sizeof(double));
      ++*unreachable;
      continue;
    }
    if (o) {
      for (int a = 0; a < n; ++a) ek[a] = res[n + a] - res_other[n + a];
      continue;
    }
    /* The linear part a column at a time: contiguous in the column-major matrices, where row by
     * row strode across them; each sum keeps its order, so e is the same to the bit. */
    double linear[F3R_MAX_Q];
    for (int a = 0; a < n; ++a) linear[a] = -lin->static_force[a];
    for (int b = 0; b < n; ++b) {
      const double *M = &F3R_AT(lin->mass, n, 0, b), *D = &F3R_AT(lin->damping, n, 0, b),
                   *K = &F3R_AT(lin->stiffness, n, 0, b);
      for (int a = 0; a < n; ++a) linear[a] += M[a] * zddk[b] + D[a] * zdk[b] + K[a] * zk[b];
    }
    for (int f = 0; f < F3R_RIGID_FORCES; ++f) {
      const double* U = &F3R_AT(lin->input, n, 0, f);
      for (int a = 0; a < n; ++a) linear[a] -= U[a] * held[f];
    }
    for (int a = 0; a < n; ++a)
      ek[a] = -(res[n + a] - linear[a]); /* a force: the correction solves M dz'' + ... = -e */
  }
  f3r_workspace_destroy(ws);
  free(y), free(yp), free(res), free(res_other), free(o), free(m);
  return F3R_OK;
}

/* The linear path (order 1 or 2) into pose; with `other`, the response to what other adds along
 * the first-order path instead (pose: the deviation from it). */
static f3r_status response(const f3r_linear_model* lin, const f3r_model* model,
                           const f3r_model* other, const double* inputs, double dt, int count,
                           int order, double* pose, int* unreachable, f3r_error* err) {
  const int n = lin->n;
  if (unreachable) *unreachable = 0;
  if (count < 1 || !(dt > 0.0))
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "linear response: needs count >= 1 and dt > 0");
  const size_t series = (size_t)n * count;
  const int second = order >= 2 || other;
  double* sampled = inputs ? NULL : malloc((size_t)count * F3R_RIGID_FORCES * sizeof(double));
  const double* u = inputs ? inputs : sampled;
  double* P = second ? malloc(series * sizeof(double)) : NULL;
  double* F = second ? malloc(series * sizeof(double)) : NULL;
  double* z = second ? malloc(series * sizeof(double)) : NULL;
  double* zd = second ? malloc(series * sizeof(double)) : NULL;
  double* zdd = second ? malloc(series * sizeof(double)) : NULL;
  f3r_status st = F3R_OK;
  if (!u || (second && (!P || !F || !z || !zd || !zdd))) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "linear response: out of memory");
    goto done;
  }
  if (sampled) f3r_linear_sample_inputs(model, dt, count, sampled);
  const f3r_scene* s = &model->scene;
  double dz0[F3R_MAX_Q] = {0}, vz0[F3R_MAX_Q] = {0}, zero[F3R_MAX_Q] = {0};
  for (int k = 0; k < 3; ++k) vz0[k] = s->platform_velocity0[k];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < model->link[i].modes; ++j) {
      dz0[model->link[i].eta_index - F3R_Q_INDEPENDENT + j] = s->links[i].eta0[j];
      vz0[model->link[i].eta_index - F3R_Q_INDEPENDENT + j] = s->links[i].eta_rate0[j];
    }
  for (int k = 0; k < count; ++k)
    for (int c = 0; c < 3; ++c) pose[3 * k + c] = s->platform_pose0[c];
  if (!second) {
    pose_superpose(lin, dt, count, u, dz0, vz0, pose);
    goto done;
  }
  for (int j = 0; j < n; ++j) { /* modal forces phi_j^T (f0 + U u): 10 products a sample */
    const double* phi = lin->shapes + (size_t)j * n;
    double constant, gain[F3R_RIGID_FORCES];
    modal_load(lin, phi, &constant, gain);
    double* Pj = P + (size_t)j * count;
    for (int k = 0; k < count; ++k)
      Pj[k] = modal_force(constant, gain, u + (size_t)k * F3R_RIGID_FORCES);
  }
  superpose(lin, dt, count, P, dz0, vz0, pose, z, zd, zdd);
  if (other) memset(pose, 0, (size_t)count * 3 * sizeof(double));
  int missed = 0;
  st = second_order_remainder(lin, model, other, count, u, z, zd, zdd, F, &missed, err);
  if (st == F3R_OK) {
    project(lin, count, F, P);
    superpose(lin, dt, count, P, zero, zero, pose, NULL, NULL, NULL);
  }
  if (unreachable) *unreachable = missed;
done:
  free(sampled), free(P), free(F), free(z), free(zd), free(zdd);
  return st;
}

f3r_status f3r_linear_response(const f3r_linear_model* lin, const f3r_model* model, double dt,
                               int count, int order, double* pose, int* unreachable,
                               f3r_error* err) {
  return f3r_linear_response_sampled(lin, model, NULL, NULL, dt, count, order, pose, unreachable,
                                     err);
}

f3r_status f3r_linear_response_sampled(const f3r_linear_model* lin, const f3r_model* model,
                                       const f3r_model* other, const double* inputs, double dt,
                                       int count, int order, double* pose, int* unreachable,
                                       f3r_error* err) {
  if (other && other->nq != model->nq)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "linear response: the other model needs the same coordinates");
  return response(lin, model, other, inputs, dt, count, other ? 1 : order, pose, unreachable, err);
}

f3r_status f3r_linear_difference_response(const f3r_linear_model* lin, const f3r_model* model,
                                          const f3r_model* other, double dt, int count,
                                          double* pose, int* unreachable, f3r_error* err) {
  if (!other) return f3r_error_set(err, F3R_ERR_ARGUMENT, "linear response: needs the other model");
  return f3r_linear_response_sampled(lin, model, other, NULL, dt, count, 1, pose, unreachable, err);
}
