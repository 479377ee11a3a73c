/* The linearised model and its modal response (include/flex3rpr/linear.h). Everything comes
 * from the public minimal residual, so the linear model is exactly the simulated one's tangent. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dense.h"
#include "flex3rpr/linear.h"
#include "flex3rpr/residual.h"

void f3r_linear_destroy(f3r_linear_model* lin) {
  if (!lin) return;
  free(lin->mass);
  free(lin->damping);
  free(lin->stiffness);
  free(lin->input);
  free(lin->static_force);
  free(lin->shapes);
  free(lin->omega2);
  free(lin->modal_damping);
  free(lin);
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
  memcpy(L, lin->mass, (size_t)n * n * sizeof(double));
  if (f3r_cholesky_factor(L, n)) {
    st = f3r_error_set(err, F3R_ERR_SINGULAR, "linearisation: the reduced mass matrix is not positive definite");
    goto done;
  }
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
        d += F3R_AT(lin->shapes, n, a, j) * F3R_AT(lin->damping, n, a, b) * F3R_AT(lin->shapes, n, b, j);
    lin->modal_damping[j] = d;
  }
done:
  free(L), free(C), free(V), free(eig), free(order);
  return st;
}

f3r_status f3r_linearise(const f3r_model* model, f3r_linear_model** out, f3r_error* err) {
  *out = NULL;
  f3r_model m = *model; /* without the scripted inputs and the actuator lag */
  memset(m.scene.inputs, 0, sizeof m.scene.inputs);
  m.n_lag = 0;
  m.n_breakpoints = 0;
  const int n = m.n_independent, ny = f3r_state_size(&m, F3R_FORMULATION_MINIMAL);
  f3r_linear_model* lin = calloc(1, sizeof *lin);
  f3r_workspace* ws = f3r_workspace_create(&m);
  double* y = calloc((size_t)ny, sizeof(double));
  double* yp = calloc((size_t)ny, sizeof(double));
  double* res = calloc((size_t)ny, sizeof(double));
  double* res0 = calloc((size_t)ny, sizeof(double));
  double* J0 = calloc((size_t)ny * ny, sizeof(double));
  double* J1 = calloc((size_t)ny * ny, sizeof(double));
  double held[F3R_MAX_Q] = {0};
  f3r_status st = F3R_OK;
  if (lin) {
    lin->n = n;
    lin->mass = calloc((size_t)n * n, sizeof(double));
    lin->damping = calloc((size_t)n * n, sizeof(double));
    lin->stiffness = calloc((size_t)n * n, sizeof(double));
    lin->input = calloc((size_t)n * F3R_RIGID_FORCES, sizeof(double));
    lin->static_force = calloc((size_t)n, sizeof(double));
    lin->shapes = calloc((size_t)n * n, sizeof(double));
    lin->omega2 = calloc((size_t)n, sizeof(double));
    lin->modal_damping = calloc((size_t)n, sizeof(double));
  }
  if (!lin || !ws || !y || !yp || !res || !res0 || !J0 || !J1 || !lin->mass || !lin->damping ||
      !lin->stiffness || !lin->input || !lin->static_force || !lin->shapes || !lin->omega2 ||
      !lin->modal_damping) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "linearisation: out of memory");
    goto done;
  }
  for (int k = 0; k < 3; ++k) y[k] = m.scene.platform_pose0[k];
  /* Rows n..2n of the residual are the reduced equations B^T (M a + h + k - Q): dF/dz at cj = 0
   * is K, dF/du is D, and the cj = 1 Jacobian less the cj = 0 one on the u columns is M. */
  if ((st = f3r_residual_jacobian(&m, F3R_FORMULATION_MINIMAL, 0.0, 0.0, y, yp, NULL, J0, ny, ws)) ||
      (st = f3r_residual_jacobian(&m, F3R_FORMULATION_MINIMAL, 0.0, 1.0, y, yp, NULL, J1, ny, ws)) ||
      (st = f3r_residual(&m, F3R_FORMULATION_MINIMAL, 0.0, y, yp, NULL, res0, ws))) {
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
    st = f3r_residual(&m, F3R_FORMULATION_MINIMAL, 0.0, y, yp, held, res, ws);
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
  free(y), free(yp), free(res), free(res0), free(J0), free(J1);
  if (st == F3R_OK) *out = lin;
  else f3r_linear_destroy(lin);
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

f3r_status f3r_linear_response(const f3r_linear_model* lin, const f3r_model* model, double dt,
                               int count, double* pose, f3r_error* err) {
  const int n = lin->n;
  if (count < 1 || !(dt > 0.0))
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "linear response: needs count >= 1 and dt > 0");
  double* u = malloc((size_t)count * F3R_RIGID_FORCES * sizeof(double)); /* inputs at t_k */
  double* p = malloc((size_t)count * sizeof(double));                     /* one mode's force */
  if (!u || !p) {
    free(u), free(p);
    return f3r_error_set(err, F3R_ERR_MEMORY, "linear response: out of memory");
  }
  const f3r_scene* s = &model->scene;
  for (int f = 0; f < F3R_RIGID_FORCES; ++f) {
    const int lagged = model->n_lag && f < 3;
    const double decay = lagged ? exp(-dt / model->lag_time_constant) : 0.0;
    double applied = 0.0; /* the lag states start at zero */
    for (int k = 0; k < count; ++k) {
      const double command = f3r_input_value(&s->inputs[f], k * dt);
      if (lagged) { /* first-order lag, command held over each sample */
        if (k) applied = decay * applied + (1.0 - decay) * command;
        u[(size_t)k * F3R_RIGID_FORCES + f] = applied;
      } else {
        u[(size_t)k * F3R_RIGID_FORCES + f] = command;
      }
    }
  }
  /* Initial deviation from the linearisation point and its rate, in z. */
  double dz0[F3R_MAX_Q] = {0}, vz0[F3R_MAX_Q] = {0};
  for (int k = 0; k < 3; ++k) vz0[k] = s->platform_velocity0[k];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < model->link[i].modes; ++j) {
      dz0[model->link[i].eta_index - F3R_Q_INDEPENDENT + j] = s->links[i].eta0[j];
      vz0[model->link[i].eta_index - F3R_Q_INDEPENDENT + j] = s->links[i].eta_rate0[j];
    }
  for (int k = 0; k < count; ++k)
    for (int c = 0; c < 3; ++c) pose[3 * k + c] = s->platform_pose0[c];
  for (int j = 0; j < n; ++j) {
    const double* phi = lin->shapes + (size_t)j * n;
    double ui[F3R_RIGID_FORCES], p0 = 0.0, xi = 0.0, rate = 0.0;
    for (int f = 0; f < F3R_RIGID_FORCES; ++f) {
      ui[f] = 0.0;
      for (int a = 0; a < n; ++a) ui[f] += phi[a] * F3R_AT(lin->input, n, a, f);
    }
    for (int a = 0; a < n; ++a) {
      p0 += phi[a] * lin->static_force[a];
      double mdz = 0.0, mvz = 0.0; /* xi0 = phi^T M dz0 */
      for (int b = 0; b < n; ++b) {
        mdz += F3R_AT(lin->mass, n, a, b) * dz0[b];
        mvz += F3R_AT(lin->mass, n, a, b) * vz0[b];
      }
      xi += phi[a] * mdz;
      rate += phi[a] * mvz;
    }
    for (int k = 0; k < count; ++k) {
      const double* uk = u + (size_t)k * F3R_RIGID_FORCES;
      double v = p0;
      for (int f = 0; f < F3R_RIGID_FORCES; ++f) v += ui[f] * uk[f];
      p[k] = v;
    }
    double E[4][4];
    mode_transition(lin->omega2[j], lin->modal_damping[j], dt, E);
    for (int c = 0; c < 3; ++c) pose[c] += phi[c] * xi;
    for (int k = 0; k + 1 < count; ++k) {
      const double slope = (p[k + 1] - p[k]) / dt;
      const double x1 = E[0][0] * xi + E[0][1] * rate + E[0][2] * p[k] + E[0][3] * slope;
      const double v1 = E[1][0] * xi + E[1][1] * rate + E[1][2] * p[k] + E[1][3] * slope;
      xi = x1;
      rate = v1;
      for (int c = 0; c < 3; ++c) pose[3 * (k + 1) + c] += phi[c] * xi;
    }
  }
  free(u), free(p);
  return F3R_OK;
}
