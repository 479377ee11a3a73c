// The eigenvalues of the minimal formulation's explicit ODE y' = f(t, y) along a scene's path,
// and the stability bounds of the explicit Runge-Kutta tables on the imaginary and the negative
// real axis: what limits an explicit integrator's step (bench/eigenvalues writes the page).
//   f3r_eigenvalues SCENE.yaml [EVERY_S] [TABLE ...]
//   f3r_eigenvalues --erk-errors SCENE.yaml RTOL [TABLE]
//   f3r_eigenvalues --lawson SCENE.yaml RTOL REFRESH_S [TABLE]   (below, at Lawson)
// The second form runs ERK at RTOL (atol RTOL/100, as the benchmark) and, after each 0.1 ms,
// names the state component whose weighted local error estimate (ARKODE's, |e_i| w_i) is the
// largest of the last step: which motion the error test follows.
// Prints JSON: {"samples": [{"t", "re": [...], "im": [...]}], "tables": [{"name", "imaginary",
// "real"}]}. The Jacobian is f3r_explicit_rhs's by central differences (the ODE IDA and ERK both
// integrate in the minimal formulation); the path is IDA's at rtol 1e-10.
#include <cstdio>  // first: arkode_butcher.h uses FILE without including it

#include <arkode/arkode_butcher_erk.h>
#include <arkode/arkode_erkstep.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "erk_tables.h"
#include "residual.h"
#include "stepper.h"

namespace {

// |R(z)| of an explicit table's solution (weights b; embedded: its embedding's, d): R(z) = 1 +
// z b^T (I - z A)^{-1} 1, by forward substitution.
double Amplification(ARKodeButcherTable t, std::complex<double> z, bool embedded = false) {
  const int s = t->stages;
  std::vector<std::complex<double>> k(static_cast<size_t>(s));
  std::complex<double> sum = 0.0;
  for (int i = 0; i < s; ++i) {
    std::complex<double> ki = 1.0;
    for (int j = 0; j < i; ++j) ki += z * t->A[i][j] * k[static_cast<size_t>(j)];
    k[static_cast<size_t>(i)] = ki;
    sum += (embedded ? t->d[i] : t->b[i]) * ki;
  }
  return std::abs(1.0 + z * sum);
}

// The largest y with |R(y d)| <= 1 on the whole segment from 0 (d = i: the imaginary axis, -1:
// the negative real axis), to 1e-4.
double Bound(ARKodeButcherTable t, std::complex<double> d, bool embedded = false) {
  double y = 0.0;
  const double h = 1e-4;
  while (y < 50.0 && Amplification(t, (y + h) * d, embedded) <= 1.0 + 1e-12) y += h;
  return y;
}

// The group of minimal state component i (y = [z | u | W], z = (X_p, Y_p, phi_p, eta)): "pose",
// "pose rate", "mode j" or "mode j rate" (j of each link's basis, from 1), "work".
std::string Group(const f3r_model* m, int i) {
  const int nz = f3r_model_nq(m) - F3R_Q_INDEPENDENT;
  if (i == 2 * nz) return "work";
  const bool rate = i >= nz;
  const int q = (rate ? i - nz : i) + F3R_Q_INDEPENDENT;
  if (q < F3R_Q_MODAL) return rate ? "pose rate" : "pose";
  for (int l = 0; l < 3; ++l) {
    const f3r_link_params* lp = f3r_model_link(m, l);
    if (q >= lp->eta_index && q < lp->eta_index + lp->modes)
      return "mode " + std::to_string(q - lp->eta_index + 1) + (rate ? " rate" : "");
  }
  return "?";
}

// A scene in the minimal formulation with one solver, its model and its simulation.
struct Run {
  f3r_scene scene;
  f3r_model* model = nullptr;
  f3r_sim* sim = nullptr;
  ~Run() {
    f3r_sim_destroy(sim);
    f3r_model_destroy(model);
    f3r_scene_free(&scene);
  }
};

// Loads path into run with the solver given; false (said on stderr) on an error.
bool Open(const char* path, f3r_integrator integrator, double rtol, double atol, const char* table,
          Run* run) {
  f3r_error err{};
  run->scene = f3r_default_scene();
  if (f3r_scene_load(path, &run->scene, &err) == F3R_OK) {
    f3r_scene& s = run->scene;
    s.formulation = F3R_FORMULATION_MINIMAL;
    s.integrator = integrator;
    s.rtol = rtol;
    s.atol = atol;
    std::snprintf(s.table, sizeof s.table, "%s", table ? table : "");
    if (f3r_model_create(&s, &run->model, &err) == F3R_OK &&
        f3r_sim_create(run->model, nullptr, &run->sim, &err) == F3R_OK)
      return true;
  }
  std::fprintf(stderr, "%s\n", err.message);
  return false;
}

// --erk-errors: the histogram of the groups that set ERK's steps, and the mean step.
int ErkErrors(const char* path, double rtol, const char* table) {
  Run run;
  if (!Open(path, F3R_INTEGRATOR_ERK, rtol, rtol / 100, table, &run)) return 1;
  const f3r_scene& scene = run.scene;
  const f3r_model* model = run.model;
  f3r_sim* sim = run.sim;
  f3r_error err{};
  const int ny = f3r_state_size(model, F3R_FORMULATION_MINIMAL);
  SUNContext ctx = nullptr;
  SUNContext_Create(nullptr, &ctx);
  N_Vector ele = N_VNew_Serial(ny, ctx), ewt = N_VNew_Serial(ny, ctx);
  std::vector<std::pair<std::string, int>> counts;
  void* mem = f3r_sim_stepper(sim)->mem;
  long samples = 0;
  double norm_sum = 0.0;
  for (int k = 1; k * 1e-4 <= scene.duration + 1e-12; ++k) {
    if (f3r_sim_advance(sim, k * 1e-4, &err) != F3R_OK) {
      std::fprintf(stderr, "%s\n", err.message);
      return 1;
    }
    if (ERKStepGetEstLocalErrors(mem, ele) < 0 || ERKStepGetErrWeights(mem, ewt) < 0) continue;
    int worst = 0;
    double largest = -1.0, squares = 0.0;
    for (int i = 0; i < ny; ++i) {
      const double w = std::fabs(NV_Ith_S(ele, i)) * NV_Ith_S(ewt, i);
      squares += w * w;
      if (w > largest) largest = w, worst = i;
    }
    norm_sum += std::sqrt(squares / ny);
    const std::string g = Group(model, worst);
    bool found = false;
    for (auto& c : counts)
      if (c.first == g) ++c.second, found = true;
    if (!found) counts.push_back({g, 1});
    ++samples;
  }
  const f3r_sim_stats stats = f3r_sim_outputs(sim)->stats;
  std::printf(
      "{\"rtol\": %g, \"steps\": %ld, \"fails\": %ld, \"mean_step\": %.6g, \"samples\": %ld, "
      "\"mean_error_norm\": %.3g, \"largest\": {",
      rtol, stats.steps, stats.error_test_failures,
      scene.duration / static_cast<double>(stats.steps), samples,
      norm_sum / static_cast<double>(samples));
  for (size_t c = 0; c < counts.size(); ++c)
    std::printf("%s\"%s\": %d", c ? ", " : "", counts[c].first.c_str(), counts[c].second);
  std::printf("}}\n");
  N_VDestroy(ele);
  N_VDestroy(ewt);
  SUNContext_Free(&ctx);
  return 0;
}

double Cpu() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// --lawson: an integrating-factor (Lawson) Runge-Kutta method on the minimal ODE, a prototype
// for #59. f = L y + N(y), L the columns of f's Jacobian for the modal coordinates and rates
// (central differences) refreshed every `refresh` s, diagonalised once per refresh (L = V Λ V⁻¹);
// each step applies the explicit table to v = exp(-(t - t_n) L) y, so the linearised elastic
// oscillation is exact and only N is left to the steps. Embedded error estimate and a standard
// step controller (atol = rtol / 100). Prints the path at 1 ms as CSV (t, x_p, y_p) and, on
// stderr, CPU seconds, steps, rejections and right-hand sides. LAWSON_NO_L=1 sets L = 0: the same
// loop as a plain explicit Runge-Kutta method, the control.
int Lawson(const char* path, double rtol, double refresh, const char* table_name) {
  using cvec = Eigen::VectorXcd;
  Run run;
  if (!Open(path, F3R_INTEGRATOR_IDA, 1e-10, 1e-12, nullptr, &run)) return 1;
  const f3r_model* m = run.model;
  f3r_workspace* ws = f3r_workspace_create(m);
  const int ny = f3r_state_size(m, F3R_FORMULATION_MINIMAL), nz = (ny - 1) / 2;
  ARKodeButcherTable tb =
      f3r_stepper_load_table(0, table_name ? table_name : "ARKODE_FEHLBERG_13_7_8");
  const int s = tb->stages, p = std::min(tb->q, tb->p);
  const double atol = rtol / 100;
  Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(f3r_sim_state(run.sim), ny);
  Eigen::MatrixXd L(ny, ny);
  Eigen::MatrixXcd V, Vinv;
  cvec lam;
  long rhs = 0, steps = 0, rejected = 0, refreshes = 0;
  auto f = [&](double t, const Eigen::VectorXd& x, Eigen::VectorXd* out) {
    ++rhs;
    return f3r_explicit_rhs(m, t, x.data(), nullptr, out->data(), ws) == F3R_OK;
  };
  auto linearise = [&](double t) {
    L.setZero();
    Eigen::VectorXd xp = y, fp(ny), fm(ny);
    for (int j = 3; j < 2 * nz; ++j) {
      if (j >= nz && j < nz + 3) continue;  // the pose rates
      const double h = 1e-7 * std::max(1.0, std::fabs(y[j]));
      xp[j] = y[j] + h;
      f(t, xp, &fp);
      xp[j] = y[j] - h;
      f(t, xp, &fm);
      xp[j] = y[j];
      L.col(j) = (fp - fm) / (2 * h);
    }
    if (std::getenv("LAWSON_NO_L")) L.setZero();
    Eigen::EigenSolver<Eigen::MatrixXd> es(L);
    V = es.eigenvectors();
    lam = es.eigenvalues();
    Vinv = V.inverse();
    ++refreshes;
  };
  const double t0 = Cpu();
  double t = 0.0, t_ref = -1e9, h = 1e-5;
  std::vector<cvec> u(static_cast<size_t>(s));
  Eigen::VectorXd Y(ny), F(ny), ynew(ny);
  std::printf("t,x_p,y_p\n%.6g,%.17g,%.17g\n", 0.0, y[0], y[1]);
  const double duration = run.scene.duration;
  for (int k = 1; k * 1e-3 <= duration + 1e-12; ++k) {
    const double t_out = k * 1e-3;
    while (t < t_out - 1e-14) {
      if (t - t_ref >= refresh - 1e-12) linearise(t), t_ref = t;
      const double hh = std::min(h, t_out - t);
      const cvec w0 = Vinv * y.cast<std::complex<double>>();
      for (int i = 0; i < s; ++i) {
        cvec acc = cvec::Zero(ny);
        for (int j = 0; j < i; ++j) acc += tb->A[i][j] * u[static_cast<size_t>(j)];
        const cvec e = (tb->c[i] * hh * lam).array().exp();
        Y = (V * (e.array() * (w0 + hh * acc).array()).matrix()).real();
        if (!f(t + tb->c[i] * hh, Y, &F)) return 1;
        F -= L * Y;
        u[static_cast<size_t>(i)] = (Vinv * F.cast<std::complex<double>>()).array() / e.array();
      }
      cvec sol = cvec::Zero(ny), est = cvec::Zero(ny);
      for (int i = 0; i < s; ++i) {
        sol += tb->b[i] * u[static_cast<size_t>(i)];
        est += (tb->b[i] - tb->d[i]) * u[static_cast<size_t>(i)];
      }
      const cvec eh = (hh * lam).array().exp();
      ynew = (V * (eh.array() * (w0 + hh * sol).array()).matrix()).real();
      const Eigen::VectorXd err = (V * (eh.array() * (hh * est).array()).matrix()).real();
      double sq = 0.0;
      for (int n = 0; n < ny; ++n) {
        const double w = err[n] / (rtol * std::fabs(y[n]) + atol);
        sq += w * w;
      }
      const double norm = std::sqrt(sq / ny);
      const double grow = norm > 0 ? 0.9 * std::pow(norm, -1.0 / (p + 1)) : 5.0;
      if (norm <= 1.0) {
        t += hh, y = ynew, ++steps;
        if (hh == h) h = hh * std::min(5.0, std::max(0.2, grow));
      } else {
        ++rejected;
        h = hh * std::min(1.0, std::max(0.2, grow));
      }
    }
    std::printf("%.6g,%.17g,%.17g\n", t_out, y[0], y[1]);
  }
  std::fprintf(stderr, "cpu %.6f steps %ld rejected %ld rhs %ld refreshes %ld\n", Cpu() - t0, steps,
               rejected, rhs, refreshes);
  f3r_workspace_destroy(ws);
  ARKodeButcherTable_Free(tb);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 5 && std::string(argv[1]) == "--lawson")
    return Lawson(argv[2], std::atof(argv[3]), std::atof(argv[4]), argc > 5 ? argv[5] : nullptr);
  if (argc >= 4 && std::string(argv[1]) == "--erk-errors")
    return ErkErrors(argv[2], std::atof(argv[3]), argc > 4 ? argv[4] : nullptr);
  if (argc < 2) {
    std::fprintf(stderr, "usage: f3r_eigenvalues SCENE.yaml [EVERY_S] [TABLE ...]\n");
    return 2;
  }
  const double every = argc > 2 ? std::atof(argv[2]) : 0.005;
  Run run;  // IDA's path at rtol 1e-10
  if (!Open(argv[1], F3R_INTEGRATOR_IDA, 1e-10, 1e-12, nullptr, &run)) return 1;
  const f3r_scene& scene = run.scene;
  const f3r_model* model = run.model;
  f3r_sim* sim = run.sim;
  f3r_error err{};
  f3r_workspace* ws = f3r_workspace_create(model);
  const int ny = f3r_state_size(model, F3R_FORMULATION_MINIMAL);
  const int n = ny - 1;  // the last component, W, is the work: no dynamics of its own
  std::printf("{\"state_size\": %d, \"samples\": [", n);
  std::vector<double> y(static_cast<size_t>(ny)), fp(y), fm(y);
  for (int k = 0; k * every <= scene.duration + 1e-12; ++k) {
    const double t = k * every;
    if (k > 0 && f3r_sim_advance(sim, t, &err) != F3R_OK) {
      std::fprintf(stderr, "%s\n", err.message);
      return 1;
    }
    const double* state = f3r_sim_state(sim);
    y.assign(state, state + ny);
    Eigen::MatrixXd A(n, n);
    for (int j = 0; j < n; ++j) {
      const double h = 1e-6 * std::max(1.0, std::fabs(y[static_cast<size_t>(j)]));
      const double keep = y[static_cast<size_t>(j)];
      y[static_cast<size_t>(j)] = keep + h;
      f3r_explicit_rhs(model, t, y.data(), nullptr, fp.data(), ws);
      y[static_cast<size_t>(j)] = keep - h;
      f3r_explicit_rhs(model, t, y.data(), nullptr, fm.data(), ws);
      y[static_cast<size_t>(j)] = keep;
      for (int i = 0; i < n; ++i)
        A(i, j) = (fp[static_cast<size_t>(i)] - fm[static_cast<size_t>(i)]) / (2 * h);
    }
    Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
    std::printf("%s{\"t\": %.6g, \"re\": [", k ? ", " : "", t);
    for (int i = 0; i < n; ++i) std::printf("%s%.9g", i ? ", " : "", es.eigenvalues()[i].real());
    std::printf("], \"im\": [");
    for (int i = 0; i < n; ++i) std::printf("%s%.9g", i ? ", " : "", es.eigenvalues()[i].imag());
    std::printf("]}");
  }
  std::printf("], \"tables\": [");
  for (int a = 3; a < argc; ++a) {
    ARKodeButcherTable t = f3r_stepper_load_table(0, argv[a]);
    if (!t) continue;
    std::printf(
        "%s{\"name\": \"%s\", \"stages\": %d, \"order\": %d, \"embedded_order\": %d, "
        "\"imaginary\": %.4f, \"real\": %.4f, \"embedded_imaginary\": %.4f, "
        "\"embedded_real\": %.4f}",
        a > 3 ? ", " : "", argv[a], t->stages, t->q, t->p, Bound(t, {0.0, 1.0}),
        Bound(t, {-1.0, 0.0}), t->d ? Bound(t, {0.0, 1.0}, true) : 0.0,
        t->d ? Bound(t, {-1.0, 0.0}, true) : 0.0);
    ARKodeButcherTable_Free(t);
  }
  std::printf("]}\n");
  f3r_workspace_destroy(ws);
  return 0;
}
