// The hard-case suite: where a plant model hurts. Each case asserts numbers; docs/testing.md's
// hard-case table lists them with the measured values (printed here as "measured: ...").
#include <gtest/gtest.h>

#include <complex>
#include <cstdio>
#include <fstream>
#include <random>

#include "flex3rpr/beam_modes.h"
#include "flex3rpr/modal.h"
#include "queries.h"
#include "stepper.h"
#include "test_support.h"

namespace {

f3r_scene LoadScene(const std::string& path) {
  f3r_scene s;
  f3r_error err{};
  if (f3r_scene_load(path.c_str(), &s, &err) != F3R_OK) throw std::runtime_error(err.message);
  return s;
}

// The scenes loaded here, whose input tables the process frees at exit: the tests use copies
// of them, which share the tables (scene.h).
struct LoadedScenes {
  std::vector<f3r_scene> scenes;
  ~LoadedScenes() {
    for (f3r_scene& s : scenes) f3r_scene_free(&s);
  }
};

f3r_scene SceneFromText(const std::string& text) {
  static LoadedScenes loaded;
  const std::string path = ::testing::TempDir() + "/hard_case_scene.yaml";
  std::ofstream(path) << text;
  loaded.scenes.push_back(LoadScene(path));
  return loaded.scenes.back();
}

struct Outcome {
  SimPtr sim;
  ModelPtr model;
  f3r_status status = F3R_OK;
  std::string error;
  std::vector<f3r_outputs> samples;
};

// Runs a scene with its own solver settings (or the given ones) to its end, sampling every dt.
Outcome Simulate(const f3r_scene& scene, double dt, const f3r_solver_settings* settings = nullptr) {
  Outcome r;
  r.model = MakeModel(scene);
  f3r_solver_settings set = settings ? *settings : f3r_solver_settings_from_scene(&scene);
  f3r_sim* raw = nullptr;
  f3r_error err{};
  if (f3r_sim_create(r.model.get(), &set, &raw, &err) != F3R_OK)
    throw std::runtime_error(err.message);
  r.sim.reset(raw);
  r.samples.push_back(*f3r_sim_outputs(raw));
  const long n = std::lround(scene.duration / dt);
  for (long k = 1; k <= n; ++k) {
    r.status = f3r_sim_advance(raw, k == n ? scene.duration : k * dt, &err);
    r.samples.push_back(*f3r_sim_outputs(raw));
    if (r.status != F3R_OK) {
      r.error = err.message;
      break;
    }
  }
  return r;
}

double RelativeEnergyError(const Outcome& r) {
  double worst = 0.0, scale = 0.0;
  for (const auto& o : r.samples) {
    worst = std::max(worst, o.energy_balance_error);
    scale = std::max(scale, o.kinetic_energy + o.potential_energy);
  }
  return worst / scale;
}

bool AllFinite(const f3r_outputs& o, int nq) {
  for (int n = 0; n < nq; ++n)
    if (!std::isfinite(o.q[n]) || !std::isfinite(o.v[n]) || !std::isfinite(o.forces[n]))
      return false;
  return std::isfinite(o.kinetic_energy) && std::isfinite(o.potential_energy) &&
         std::isfinite(o.external_work) && std::isfinite(o.actuation_condition);
}

// A force that starts with zero value and zero slope: 20 (1 - cos 2 pi 10 t) N on leg 1, and a
// torque on cylinder 2, so the high modes carry almost no energy.
const char* kSmoothInputs =
    "inputs:\n"
    "  rho_1: {offset: 20.0, amplitude: -20.0, frequency: 10.0}\n"
    "  theta_2: {offset: 0.5, amplitude: -0.5, frequency: 10.0}\n";

// --- 1. many modes ------------------------------------------------------------------------------
class ManyModes : public ::testing::TestWithParam<const char*> {};

TEST_P(ManyModes, TwentyModesRunWithEnergyBalance) {
  const std::string model = GetParam();
  // Mode shapes: orthonormal to 1e-12 (test_beam_modes checks the evaluation itself against an
  // independent MPFR evaluation of the printed formulas, free of cosh/sinh cancellation).
  const f3r_beam_end end = model == "fixed_free" ? F3R_BEAM_FIXED_FREE : F3R_BEAM_FIXED_PINNED;
  std::vector<double> gram(400);
  ASSERT_EQ(f3r_beam_modal_integrals(end, 20, nullptr, nullptr, gram.data(), nullptr, nullptr), 0);
  double gram_error = 0.0;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      gram_error = std::max(gram_error, std::fabs(gram[i * 20 + j] - (i == j)));
  EXPECT_LT(gram_error, 1e-12);

  f3r_scene scene = SceneFromText("links: {model: " + model + ", modes: 20}\n" + kSmoothInputs +
                                  "solver: {rtol: 1.0e-10, atol: 1.0e-12}\nrun: {duration: 0.1}\n");
  Outcome r = Simulate(scene, 1e-3);
  ASSERT_EQ(r.status, F3R_OK) << r.error;
  const double energy = RelativeEnergyError(r);
  std::printf("measured: %s r = 20: Gram error %.1e, energy balance %.1e, %ld steps\n",
              model.c_str(), gram_error, energy, r.samples.back().stats.steps);
  EXPECT_LT(energy, 1e-8);
}

INSTANTIATE_TEST_SUITE_P(BothEnds, ManyModes, ::testing::Values("fixed_pinned", "fixed_free"));

// --- 2. stiff -----------------------------------------------------------------------------------
long StepsWithStiffness(double youngs_modulus, const char* inputs, int max_order, double* energy) {
  char text[1024];
  std::snprintf(text, sizeof text,
                "links: {model: fixed_free, modes: 10}\nlink: {youngs_modulus: %.6g}\n%s"
                "solver: {rtol: 1.0e-6, atol: 1.0e-8, max_order: %d}\nrun: {duration: 0.1}\n",
                youngs_modulus, inputs, max_order);
  Outcome r = Simulate(SceneFromText(text), 1e-3);
  if (r.status != F3R_OK) throw std::runtime_error(r.error);
  if (energy) *energy = RelativeEnergyError(r);
  return r.samples.back().stats.steps;
}

// BDF of order 3 to 5 is not A-stable: an undamped mode whose h omega falls where those orders are
// unstable makes IDA cut the step until the mode is resolved, excited or not. BDF2 is A-stable.
TEST(Stiff, UnexcitedHighModesDoNotLimitTheStep) {
  double energy_stiff = 0.0;
  const long nominal = StepsWithStiffness(73e9, kSmoothInputs, 2, nullptr);
  const long stiff = StepsWithStiffness(73e11, kSmoothInputs, 2, &energy_stiff);
  const long nominal5 = StepsWithStiffness(73e9, kSmoothInputs, 5, nullptr);
  const long stiff5 = StepsWithStiffness(73e11, kSmoothInputs, 5, nullptr);
  std::printf(
      "measured: r = 10, smooth forcing, max_order 2: %ld steps at E, %ld at 100 E (ratio "
      "%.2f); max_order 5: %ld and %ld (ratio %.2f)\n",
      nominal, stiff, double(stiff) / nominal, nominal5, stiff5, double(stiff5) / nominal5);
  // Modes 10x higher in frequency that carry no energy must not cost more steps.
  EXPECT_LT(double(stiff) / nominal, 1.5);
  EXPECT_LT(energy_stiff, 1e-4);
}

TEST(Stiff, AStepAtTimeZeroExcitesHighModesThatMustBeResolved) {
  const char* step = "inputs:\n  rho_1: {offset: 20.0}\n";
  double energy = 0.0;
  const long smooth = StepsWithStiffness(73e11, kSmoothInputs, 2, nullptr);
  const long stepped = StepsWithStiffness(73e11, step, 5, &energy);
  std::printf(
      "measured: r = 10, 100 E, step force at t = 0: %ld steps (max_order 5) against %ld "
      "smooth (max_order 2): %.0fx\n",
      stepped, smooth, double(stepped) / smooth);
  EXPECT_GT(stepped, 20 * smooth);  // the excited modes are resolved, not stepped over
  EXPECT_LT(energy, 1e-6);
}

// --- 3. resonance -------------------------------------------------------------------------------
// Amplitude of link 1's tip deflection over each forcing period.
std::vector<double> PeriodAmplitudes(const Outcome& r, double period, double dt) {
  std::vector<double> amp;
  const int per = int(std::lround(period / dt));
  for (size_t start = 0; start + per <= r.samples.size(); start += per) {
    double lo = 1e300, hi = -1e300;
    for (int k = 0; k < per; ++k) {
      const double w = r.samples[start + k].tip_deflection[0];
      lo = std::min(lo, w);
      hi = std::max(hi, w);
    }
    amp.push_back(0.5 * (hi - lo));
  }
  return amp;
}

// The first natural frequency of the assembled system at the home pose (`flex3rpr_sim --modal`).
constexpr double kFirstNaturalHz = 227.160707;

// Runs a resonance scene for `periods` forcing periods, 64 samples a period, at rtol 1e-9; the
// tip amplitude of link 1 in each period (and the scene as run, when asked).
void ResonanceAmplitudes(const char* file, int periods, f3r_scene* run_scene,
                         std::vector<double>* amp) {
  f3r_scene scene = LoadScene(ScenePath(file));
  scene.rtol = 1e-9;
  scene.atol = 1e-11;
  const double period = 1.0 / kFirstNaturalHz, dt = period / 64.0;
  scene.duration = periods * period;
  Outcome r = Simulate(scene, dt);
  ASSERT_EQ(r.status, F3R_OK) << r.error;
  *amp = PeriodAmplitudes(r, period, dt);
  if (run_scene) *run_scene = scene;
}

TEST(Resonance, UndampedAmplitudeGrowsLinearly) {
  std::vector<double> amp;
  ASSERT_NO_FATAL_FAILURE(ResonanceAmplitudes("resonance.yaml", 50, nullptr, &amp));
  ASSERT_GE(amp.size(), 50u);
  // Secular growth A_k ~ c k: the amplitude per period over the period number is constant.
  const double c = amp[49] / 50.0;
  double worst = 0.0;
  for (int k = 10; k < 50; ++k) worst = std::max(worst, std::fabs(amp[k] / (k + 1) / c - 1.0));
  std::printf(
      "measured: undamped resonance: A_50 / A_25 = %.3f, max deviation from linear growth "
      "%.1f %% (periods 10..50)\n",
      amp[49] / amp[24], 100 * worst);
  EXPECT_NEAR(amp[49] / amp[24], 2.0, 0.1);
  EXPECT_LT(worst, 0.1);
}

// Steady-state amplitude of link 1's tip deflection from the model linearised about the initial
// state: M z'' + C z' + K z = b cos(w t), with M, C, K, b from differences of the public residual.
double LinearisedTipAmplitude(const f3r_scene& scene, double hz, double torque) {
  auto m = MakeModel(scene);
  WorkspacePtr ws(f3r_workspace_create(m.get()));
  const int nz = m->n_independent, ny = f3r_state_size(m.get(), F3R_FORMULATION_MINIMAL);
  std::vector<double> q(F3R_MAX_Q), v(F3R_MAX_Q), y(ny), yp(ny), held(m->nq, 0.0);
  EXPECT_EQ(f3r_model_initial_state(m.get(), q.data(), v.data()), F3R_OK);
  EXPECT_EQ(f3r_consistent_state(m.get(), F3R_FORMULATION_MINIMAL, 0.0, q.data(), v.data(), nullptr,
                                 nullptr, 0.0, y.data(), yp.data(), nullptr, ws.get()),
            F3R_OK);
  // At rest with no forces the equilibrium has y' = 0 apart from z' = u = 0.
  std::fill(yp.begin(), yp.end(), 0.0);
  std::vector<double> r0(ny), r1(ny);
  auto rows = [&](std::vector<double>& yy, std::vector<double>& yyp, std::vector<double>& hh,
                  std::vector<double>& out) {
    f3r_residual(m.get(), F3R_FORMULATION_MINIMAL, 0.0, yy.data(), yyp.data(), hh.data(),
                 out.data(), ws.get());
  };
  rows(y, yp, held, r0);
  using cd = std::complex<double>;
  std::vector<cd> A(nz * nz), b(nz);
  const double w = 2 * M_PI * hz, h = 1e-7;
  for (int j = 0; j < nz; ++j) {
    // K column: d F_u / d z_j; C column: d F_u / d u_j; M column: d F_u / d u'_j.
    std::vector<double> yy = y, yyp = yp;
    yy[j] += h;
    rows(yy, yp, held, r1);
    for (int i = 0; i < nz; ++i) A[i * nz + j] += (r1[nz + i] - r0[nz + i]) / h;
    yy = y;
    yy[nz + j] += h;
    rows(yy, yp, held, r1);
    for (int i = 0; i < nz; ++i) A[i * nz + j] += cd(0, w) * (r1[nz + i] - r0[nz + i]) / h;
    yyp[nz + j] += h;
    rows(y, yyp, held, r1);
    for (int i = 0; i < nz; ++i) A[i * nz + j] += -w * w * (r1[nz + i] - r0[nz + i]) / h;
  }
  std::vector<double> hh = held;
  hh[3] = 1.0;  // unit cylinder torque on theta_1
  rows(y, yp, hh, r1);
  for (int i = 0; i < nz; ++i) b[i] = -torque * (r1[nz + i] - r0[nz + i]);
  // Gaussian elimination with partial pivoting on the complex system.
  for (int k = 0; k < nz; ++k) {
    int p = k;
    for (int i = k + 1; i < nz; ++i)
      if (std::abs(A[i * nz + k]) > std::abs(A[p * nz + k])) p = i;
    for (int j = 0; j < nz; ++j) std::swap(A[k * nz + j], A[p * nz + j]);
    std::swap(b[k], b[p]);
    for (int i = k + 1; i < nz; ++i) {
      const cd f = A[i * nz + k] / A[k * nz + k];
      for (int j = k; j < nz; ++j) A[i * nz + j] -= f * A[k * nz + j];
      b[i] -= f * b[k];
    }
  }
  std::vector<cd> z(nz);
  for (int k = nz - 1; k >= 0; --k) {
    cd s = b[k];
    for (int j = k + 1; j < nz; ++j) s -= A[k * nz + j] * z[j];
    z[k] = s / A[k * nz + k];
  }
  cd tip = 0.0;
  for (int j = 0; j < m->link[0].modes; ++j)
    tip += m->link[0].tip[j] * z[m->link[0].eta_index - 6 + j];
  return std::abs(tip);
}

TEST(Resonance, DampedAmplitudeSettlesAtTheLinearisedSteadyState) {
  f3r_scene scene;
  std::vector<double> amp;
  ASSERT_NO_FATAL_FAILURE(ResonanceAmplitudes("resonance_damped.yaml", 60, &scene, &amp));
  const double settled = amp[amp.size() - 1];
  const double predicted = LinearisedTipAmplitude(scene, kFirstNaturalHz, 0.2);
  std::printf(
      "measured: damped resonance (zeta 0.02): tip amplitude %.4e m, linearised %.4e m (%.2f %%)\n",
      settled, predicted, 100 * (settled / predicted - 1));
  EXPECT_NEAR(amp[amp.size() - 1] / amp[amp.size() - 6], 1.0, 0.01);  // settled
  EXPECT_NEAR(settled / predicted, 1.0, 0.02);
}

// --- 4. long run --------------------------------------------------------------------------------
TEST(LongRun, SixtySecondsOfFreeVibration) {
  f3r_scene scene = LoadScene(ScenePath("free_vibration_long.yaml"));
  f3r_solver_settings erk = f3r_solver_settings_from_scene(&scene);
  erk.integrator = F3R_INTEGRATOR_ERK;
  erk.rtol = 1e-9;
  erk.atol = 1e-11;
  Outcome e = Simulate(scene, 0.5, &erk);
  ASSERT_EQ(e.status, F3R_OK) << e.error;
  // The DAE over the first 20 s: its IDA run is two thirds of this test's CPU (1:54 for 60 s on
  // the 2-core machine, where ERK takes 0:48), and 20 s already hold 10^5 of its steps and
  // metres of travel.
  f3r_scene first = scene;
  first.duration = 20.0;
  f3r_solver_settings dae = f3r_solver_settings_from_scene(&first);
  dae.formulation = F3R_FORMULATION_DAE;
  dae.rtol = 1e-9;
  dae.atol = 1e-11;
  Outcome d = Simulate(first, 0.5, &dae);
  ASSERT_EQ(d.status, F3R_OK) << d.error;
  ASSERT_EQ(d.samples.size(), 41u);
  // Nothing holds the joints: the energy of the initial deflection also sets the whole mechanism
  // moving, and the platform drifts metres in 60 s (3 m in the first 20). The formulations must
  // agree on that path up to the integrators' error, which BDF's numerical damping dominates.
  double constraint = 0.0, apart = 0.0, travelled = 0.0;
  for (const auto& o : d.samples) constraint = std::max(constraint, o.constraint_residual);
  for (size_t k = 0; k < d.samples.size(); ++k) {
    apart = std::max(apart, std::hypot(d.samples[k].q[6] - e.samples[k].q[6],
                                       d.samples[k].q[7] - e.samples[k].q[7]));
    travelled = std::max(travelled, std::hypot(e.samples[k].q[6], e.samples[k].q[7]));
  }
  const double drift_erk = RelativeEnergyError(e), drift_dae = RelativeEnergyError(d);
  std::printf(
      "measured: 60 s free vibration: energy drift %.1e (minimal, ERK 1e-9), %.1e (dae, IDA "
      "1e-9, first 20 s); dae constraint residual %.1e m; platform travelled %.2f m in 20 s, "
      "formulations apart %.1e m\n",
      drift_erk, drift_dae, constraint, travelled, apart);
  EXPECT_LT(drift_erk, 1e-6);
  EXPECT_LT(constraint, 1e-10);
  EXPECT_GT(travelled, 1.0);
  EXPECT_LT(apart / travelled, 5e-3);
}

// --- 5. extreme speed ---------------------------------------------------------------------------
TEST(ExtremeSpeed, PaperSimulation2FormulationsAgree) {
  f3r_scene scene = LoadScene(ScenePath("paper_sim2.yaml"));
  scene.rtol = 1e-10;
  scene.atol = 1e-12;
  f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
  Outcome minimal = Simulate(scene, 1e-3, &set);
  set.formulation = F3R_FORMULATION_DAE;
  Outcome dae = Simulate(scene, 1e-3, &set);
  ASSERT_EQ(minimal.status, F3R_OK) << minimal.error;
  ASSERT_EQ(dae.status, F3R_OK) << dae.error;
  const double turned = minimal.samples.back().q[8],
               gap = std::fabs(turned - dae.samples.back().q[8]);
  double piston_speed = 0.0;
  for (const auto& o : minimal.samples) piston_speed = std::max(piston_speed, std::fabs(o.v[0]));
  std::printf(
      "measured: paper sim. 2: phi_p turns %.1f rad, pistons up to %.1f m/s; formulations "
      "apart %.1e rad; energy balance %.1e / %.1e\n",
      turned, piston_speed, gap, RelativeEnergyError(minimal), RelativeEnergyError(dae));
  EXPECT_GT(std::fabs(turned), 40.0);
  EXPECT_LT(gap, 1e-6);
  EXPECT_LT(RelativeEnergyError(minimal), 1e-7);
  EXPECT_LT(RelativeEnergyError(dae), 1e-7);
}

// --- 6. singular pose ---------------------------------------------------------------------------
TEST(SingularPose, HomeIsTypeTwoSingularAndTheRunGoesThrough) {
  f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 2}\n"
      "inputs: {platform_force_x: {amplitude: 5.0, frequency: 20.0}}\n"
      "run: {duration: 0.1}\n");
  Outcome r = Simulate(scene, 1e-3);
  ASSERT_EQ(r.status, F3R_OK) << r.error;
  EXPECT_GE(r.samples.front().actuation_condition, 1e12);  // legs through P: no moment
  double lowest = 1e300;
  for (const auto& o : r.samples) lowest = std::min(lowest, o.actuation_condition);
  EXPECT_LT(lowest, 1e6);  // it moved away from the singularity and kept integrating
  std::printf("measured: actuation condition %.1e at home, %.1e lowest along the run\n",
              r.samples.front().actuation_condition, lowest);
}

// --- 7. a controller's zero-order hold ------------------------------------------------------------
// Paper sim. 3's forcing held for 1 ms at a time: 500 breakpoints, each a stop and a restart.
// Clipped to a stop, IDA's steps shrank to 3e-10 s and dae's Newton iteration failed 3e-11 s
// before the hold at 0.499 s (rtol 1e-10); now the state there comes from the last step's
// polynomial and the path agrees with the minimal formulation's.
TEST(CommandHold, DaeThroughFiveHundredHoldsAgreesWithMinimal) {
  std::string text = "links: {model: fixed_free, modes: 3}\ninputs:\n";
  const char* names[] = {"rho_1",   "rho_2",   "rho_3",           "theta_1",
                         "theta_2", "theta_3", "platform_force_x"};
  for (int n = 0; n < 7; ++n) {
    std::string times, values;
    for (int k = 0; k < 500; ++k) {
      const double t = k * 1e-3, c20 = std::cos(2 * M_PI * 20 * t),
                   c200 = std::cos(2 * M_PI * 200 * t);
      const double f = n < 3 ? -50 + 50 * c20 : n < 6 ? 5 * c200 : 100 * c20;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s%.3f", k ? ", " : "", t);
      times += buf;
      std::snprintf(buf, sizeof buf, "%s%.12g", k ? ", " : "", f);
      values += buf;
    }
    text += std::string("  ") + names[n] + ": {table: {interpolation: hold, time: [" + times +
            "], value: [" + values + "]}}\n";
  }
  text += "run: {duration: 0.5}\n";
  f3r_scene scene = SceneFromText(text);
  f3r_solver_settings dae = f3r_solver_settings_from_scene(&scene), minimal = dae;
  dae.formulation = F3R_FORMULATION_DAE;
  minimal.formulation = F3R_FORMULATION_MINIMAL;
  dae.rtol = minimal.rtol = 1e-10;
  dae.atol = minimal.atol = 1e-12;
  Outcome d = Simulate(scene, 1e-3, &dae);
  ASSERT_EQ(d.status, F3R_OK) << d.error;
  Outcome m = Simulate(scene, 1e-3, &minimal);
  ASSERT_EQ(m.status, F3R_OK) << m.error;
  ASSERT_EQ(d.samples.size(), m.samples.size());
  double apart = 0.0;
  for (size_t k = 0; k < d.samples.size(); ++k)
    apart = std::max(apart, std::hypot(d.samples[k].q[F3R_Q_X] - m.samples[k].q[F3R_Q_X],
                                       d.samples[k].q[F3R_Q_Y] - m.samples[k].q[F3R_Q_Y]));
  EXPECT_NEAR(d.samples.back().t, 0.5, 1e-12);
  EXPECT_LT(apart, 1e-8);
  EXPECT_GE(d.samples.back().stats.restarts, 499);
  std::printf("measured: 500 holds, dae and minimal at rtol 1e-10 apart by %.1e m\n", apart);
}

// An explicit method evaluates its first stage at the restart time itself, where a held force
// jumps. The consistent state there takes the force's right limit; the stage must too, or every
// segment starts with the old force: ERK then lost 2 to 4 digits against IDA on 1 kHz holds.
TEST(CommandHold, ExplicitStagesAtARestartTakeTheNewForce) {
  std::string times, values;
  for (int k = 0; k < 50; ++k) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%.3f", k ? ", " : "", k * 1e-3);
    times += buf;
    std::snprintf(buf, sizeof buf, "%s%.6g", k ? ", " : "",
                  5.0 * std::cos(2 * M_PI * 200 * k * 1e-3));
    values += buf;
  }
  f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 3}\ninputs:\n  theta_1: {table: "
      "{interpolation: hold, time: [" +
      times + "], value: [" + values + "]}}\nrun: {duration: 0.05}\n");
  f3r_solver_settings ida = f3r_solver_settings_from_scene(&scene), erk = ida;
  ida.rtol = 1e-11;
  ida.atol = 1e-13;
  erk.integrator = F3R_INTEGRATOR_ERK;
  erk.rtol = 1e-8;
  erk.atol = 1e-10;
  Outcome reference = Simulate(scene, 1e-3, &ida);
  ASSERT_EQ(reference.status, F3R_OK) << reference.error;
  for (f3r_integrator integrator : {F3R_INTEGRATOR_ERK, F3R_INTEGRATOR_DIRK}) {
    erk.integrator = integrator;
    Outcome e = Simulate(scene, 1e-3, &erk);
    ASSERT_EQ(e.status, F3R_OK) << e.error;
    double apart = 0.0;
    for (size_t k = 0; k < e.samples.size(); ++k)
      apart =
          std::max(apart, std::hypot(e.samples[k].q[F3R_Q_X] - reference.samples[k].q[F3R_Q_X],
                                     e.samples[k].q[F3R_Q_Y] - reference.samples[k].q[F3R_Q_Y]));
    std::printf("measured: 50 holds, %s at rtol 1e-8 apart from IDA at 1e-11 by %.1e m\n",
                integrator == F3R_INTEGRATOR_ERK ? "ERK" : "DIRK", apart);
    EXPECT_LT(apart, 2e-8) << integrator;  // 5.5e-7 (ERK) with the old force at the first stage
    EXPECT_GE(e.samples.back().stats.restarts, 49);
  }
}

// Outputs that do not fall on the scripted inputs' breakpoints: the step taken to reach an output
// just before a breakpoint must not cross it (found by the accuracy knob's pilot, whose samples
// fell off end_stop_impact's table times: IDASetStopTime was then behind the solver's time).
// Every integrator, unpaced and against the same run sampled on the breakpoints.
TEST(HardCases, OutputsOffTheBreakpointsNeverStepAcrossOne) {
  f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 2}\ninputs:\n  rho_1:\n    table:\n"
      "      time:  [0.0, 0.001, 0.010, 0.011]\n"
      "      value: [0.0, 20.0, 20.0, 0.0]\nrun: {duration: 0.03}\n");
  for (f3r_integrator integrator : {F3R_INTEGRATOR_IDA, F3R_INTEGRATOR_ERK, F3R_INTEGRATOR_DIRK}) {
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    set.integrator = integrator;
    set.rtol = 1e-4;  // long steps: each crosses the next breakpoint unless it is told not to
    set.atol = 1e-6;
    ModelPtr model = MakeModel(scene);
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(model.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    for (double t : {0.0009999, 0.0099999, 0.0109999, 0.03}) {
      ASSERT_EQ(f3r_sim_advance(raw, t, &err), F3R_OK)
          << integrator << " to " << t << ": " << err.message;
    }
    const f3r_outputs end = *f3r_sim_outputs(raw);
    Outcome on_grid = Simulate(scene, 1e-3, &set);  // outputs on every breakpoint
    ASSERT_EQ(on_grid.status, F3R_OK) << on_grid.error;
    const f3r_outputs& ref = on_grid.samples.back();
    EXPECT_LT(std::hypot(end.q[F3R_Q_X] - ref.q[F3R_Q_X], end.q[F3R_Q_Y] - ref.q[F3R_Q_Y]), 1e-5)
        << integrator;
    EXPECT_GE(end.stats.restarts, 3) << integrator << ": a restart at each breakpoint";
  }
}

class LegCollapse : public ::testing::TestWithParam<std::tuple<f3r_formulation, f3r_integrator>> {};

TEST_P(LegCollapse, StopsWithASpecificErrorAndAGoodState) {
  f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 2}\ninputs: {rho_1: {offset: -200.0}}\n"
      "run: {duration: 0.3}\n");
  f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
  set.formulation = std::get<0>(GetParam());
  set.integrator = std::get<1>(GetParam());
  Outcome r = Simulate(scene, 1e-3, &set);
  ASSERT_EQ(r.status, F3R_ERR_SINGULAR);
  EXPECT_NE(r.error.find("leg 1 collapsed"), std::string::npos) << r.error;
  const f3r_outputs& last = r.samples.back();
  EXPECT_TRUE(AllFinite(last, r.model->nq));
  EXPECT_NEAR(last.q[0] + r.model->link_length, 0.1 * r.model->link_length, 1e-9);
  EXPECT_LT(last.energy_balance_error, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(
    Formulations, LegCollapse,
    ::testing::Values(std::make_tuple(F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_IDA),
                      std::make_tuple(F3R_FORMULATION_DAE, F3R_INTEGRATOR_IDA),
                      std::make_tuple(F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_ERK),
                      std::make_tuple(F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_DIRK)));

TEST(SingularPose, WithEndStopsTheLegBouncesInstead) {
  f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 2}\ninputs: {rho_1: {offset: -20.0}}\n"
      "effects: {end_stops: {min: -0.1, max: 0.3, restitution: 0.5}}\n"
      "run: {duration: 0.3}\n");
  Outcome r = Simulate(scene, 1e-3);
  EXPECT_GT(r.samples.back().impacts, 0);
  for (const auto& o : r.samples) EXPECT_TRUE(AllFinite(o, r.model->nq));
  double lowest = 1e300;
  for (const auto& o : r.samples) lowest = std::min(lowest, o.q[0]);
  EXPECT_GT(lowest, -0.1 - 1e-9);
}

// --- 7. discontinuous commands ------------------------------------------------------------------
TEST(DiscontinuousCommands, HeldStepsEveryMillisecondEqualAScriptedProfile) {
  const int n = 1000;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<double> values(n);
  for (double& v : values) v = u(rng);
  std::string table = "inputs:\n  rho_2:\n    table:\n      interpolation: hold\n      time: [";
  std::string vals = "]\n      value: [";
  for (int k = 0; k < n; ++k) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", k * 1e-3);
    table += buf;
    std::snprintf(buf, sizeof buf, "%s%.17g", k ? ", " : "", values[k]);
    vals += buf;
  }
  // the tolerance the bound was set at (the default is looser: 6 digits on the headline)
  const std::string common =
      "links: {model: fixed_free, modes: 2}\nrun: {duration: 1.0}\n"
      "solver: {rtol: 1.0e-8, atol: 1.0e-10}\n";
  f3r_scene scripted = SceneFromText(common + table + vals + "]\n");
  f3r_scene held_scene = SceneFromText(common);
  Outcome a = Simulate(scripted, 1e-3);
  ASSERT_EQ(a.status, F3R_OK) << a.error;

  auto m = MakeModel(held_scene);
  f3r_solver_settings set = f3r_solver_settings_from_scene(&held_scene);
  f3r_sim* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
  SimPtr sim(raw);
  std::vector<double> held(m->nq, 0.0);
  double apart = 0.0;
  for (int k = 0; k < n; ++k) {
    held[1] = values[k];  // from t = k ms on, as a controller's command
    ASSERT_EQ(f3r_sim_set_forces(raw, held.data(), &err), F3R_OK) << err.message;
    ASSERT_EQ(f3r_sim_advance(raw, (k + 1) * 1e-3, &err), F3R_OK) << err.message;
    const f3r_outputs* o = f3r_sim_outputs(raw);
    apart = std::max(apart,
                     std::hypot(o->q[6] - a.samples[k + 1].q[6], o->q[7] - a.samples[k + 1].q[7]));
  }
  const f3r_sim_stats stats = f3r_sim_outputs(raw)->stats;
  std::printf(
      "measured: 1000 held steps: %ld restarts, %ld nonlinear failures, %ld error test "
      "failures; apart from the scripted run by %.1e m\n",
      stats.restarts, stats.nonlinear_failures, stats.error_test_failures, apart);
  EXPECT_GE(stats.restarts, n - 1);
  EXPECT_LT(apart, 1e-9);
}

// --- 8. impacts ---------------------------------------------------------------------------------
TEST(Impacts, RepeatedImpactsAreLocatedLoseRestitutionSquaredAndComeToRest) {
  f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 2}\n"
      "inputs: {rho_1: {offset: 200.0}}\n"
      "effects: {end_stops: {min: -0.1, max: 0.15, restitution: 0.6}}\n"
      "solver: {rtol: 1.0e-10, atol: 1.0e-12}\nrun: {duration: 0.2}\n");
  auto m = MakeModel(scene);
  f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
  f3r_sim* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK);
  SimPtr sim(raw);
  long seen = 0;
  double worst_location = 0.0, worst_law = 0.0, worst_energy = 0.0, deepest = 0.0;
  for (int k = 1; k <= 2000; ++k) {
    ASSERT_EQ(f3r_sim_advance(raw, k * 1e-4, &err), F3R_OK) << err.message;
    const f3r_outputs* o = f3r_sim_outputs(raw);
    deepest = std::max(deepest, o->q[0] - 0.15);
    if (o->impacts > seen && o->last_impact.rate_after != 0.0) { /* a rebound, not the rest */
      const f3r_impact_record& rec = o->last_impact;
      // The event time is off by the stroke error over the rate: 1e-10 s is ~1e-10 m here.
      worst_location =
          std::max(worst_location, std::fabs(rec.rho - 0.15) / std::fabs(rec.rate_before));
      // Newton's law: the normal component keeps e^2 of its kinetic energy.
      worst_energy = std::max(
          worst_energy,
          std::fabs(rec.rate_after * rec.rate_after / (rec.rate_before * rec.rate_before) - 0.36));
      // Newton's law on the constrained system: the normal rate reverses with factor e.
      worst_law = std::max(worst_law, std::fabs(rec.rate_after + 0.6 * rec.rate_before) /
                                          std::fabs(rec.rate_before));
      seen = o->impacts;
    }
  }
  // The rebounds shrink below the resting speed: the leg then rests on its stop, held by it
  // (the undamped beams' vibration may lift it off again: test_end_stops holds it for 10 s).
  const f3r_outputs* o = f3r_sim_outputs(raw);
  std::printf("measured: at 0.2 s leg 1 %s, stop force %.6g N\n",
              o->stop_locked[0] ? "rests on its stop" : "is free", o->stop_force[0]);
  EXPECT_LE(o->q[0], 0.15 + 1e-9);
  std::printf(
      "measured: %ld impacts; located within %.1e s; restitution law within %.1e, normal "
      "energy ratio e^2 within %.1e; deepest penetration %.1e m\n",
      seen, worst_location, worst_law, worst_energy, deepest);
  EXPECT_GE(seen, 3);
  EXPECT_LT(worst_location, 1e-10);
  EXPECT_LT(worst_energy, 1e-9);
  EXPECT_LT(worst_law, 1e-9);
  EXPECT_LT(deepest, 1e-9);
}

// --- 9. huge inputs -----------------------------------------------------------------------------
class HugeInputs : public ::testing::TestWithParam<std::string> {};

TEST_P(HugeInputs, CompleteWithEnergyBalanceOrStopClearly) {
  f3r_scene scene = SceneFromText("links: {model: fixed_free, modes: 3}\ninputs: {" + GetParam() +
                                  "}\nrun: {duration: 0.05}\n");
  Outcome r = Simulate(scene, 1e-4);
  for (const auto& o : r.samples) ASSERT_TRUE(AllFinite(o, r.model->nq)) << "at t = " << o.t;
  if (r.status == F3R_OK) {
    EXPECT_LT(RelativeEnergyError(r), 1e-6);
  } else {
    EXPECT_FALSE(r.error.empty());
  }
  std::printf("measured: %s: %s\n", GetParam().c_str(),
              r.status == F3R_OK ? "completed" : r.error.c_str());
}

INSTANTIATE_TEST_SUITE_P(ForceAndTorque, HugeInputs,
                         ::testing::Values("rho_1: {offset: 1.0e5}", "rho_2: {offset: -1.0e5}",
                                           "theta_1: {offset: 1.0e3}",
                                           "platform_torque: {offset: 1.0e3}"));

}  // namespace

namespace {

// --- recoverable errors -------------------------------------------------------------------------
// An impossible configuration (a tip deflection longer than the leg can reach) or a NaN makes the
// residual fail with a status, never with a NaN in its output: IDA's wrapper turns that status into
// its recoverable error (> 0) so the step is cut, and counts it in f3r_sim_stats.recoverable_errors.
TEST(RecoverableErrors, ImpossibleConfigurationsAndNaNGiveAStatusNotNaN) {
  auto m = MakeModel(SceneFromText("links: {model: fixed_free, modes: 2}\n"));
  WorkspacePtr ws(f3r_workspace_create(m.get()));
  for (f3r_formulation form : {F3R_FORMULATION_MINIMAL, F3R_FORMULATION_DAE}) {
    const int ny = f3r_state_size(m.get(), form);
    std::vector<double> q(F3R_MAX_Q), v(F3R_MAX_Q), y(ny), yp(ny), res(ny, 0.0);
    ASSERT_EQ(f3r_model_initial_state(m.get(), q.data(), v.data()), F3R_OK);
    ASSERT_EQ(f3r_consistent_state(m.get(), form, 0.0, q.data(), v.data(), nullptr, nullptr, 0.0,
                                   y.data(), yp.data(), nullptr, ws.get()),
              F3R_OK);
    std::vector<double> bad = y;
    bad[0] = std::nan("");
    EXPECT_NE(
        f3r_residual(m.get(), form, 0.0, bad.data(), yp.data(), nullptr, res.data(), ws.get()),
        F3R_OK);
    if (form == F3R_FORMULATION_MINIMAL) {
      bad = y;
      bad[3] = 5.0;  // eta_11 = 5 m: a tip deflection no leg can close
      EXPECT_EQ(
          f3r_residual(m.get(), form, 0.0, bad.data(), yp.data(), nullptr, res.data(), ws.get()),
          F3R_ERR_SINGULAR);
    }
  }
}

}  // namespace

// ERK after a restart from a quiet state: at a held step in the force, ARKODE's fresh estimate of
// the first step took 0.13 s at once, into a pose the legs cannot reach, and ERKStep (SUNDIALS
// 6.4.1) turns the right-hand side's request for a smaller step into ARK_UNREC_RHSFUNC_ERR: the
// run stopped at t = 0.143 s. A restart now starts from the step the run had reached.
TEST(CommandHold, ErkRestartsFromAQuietStateWithTheStepItHad) {
  const f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 1}\n"
      "inputs:\n"
      "  rho_2: {step: {time: 0.01, before: 0, after: 3}}\n"
      "run: {duration: 0.35}\n");
  f3r_solver_settings erk = f3r_solver_settings_from_scene(&scene);
  erk.integrator = F3R_INTEGRATOR_ERK;
  snprintf(erk.rk_table, sizeof erk.rk_table, "%s", "ARKODE_DORMAND_PRINCE_7_4_5");
  const Outcome r = Simulate(scene, 1e-3, &erk);
  ASSERT_EQ(r.status, F3R_OK) << r.error;
  EXPECT_NEAR(r.samples.back().t, 0.35, 1e-12);
  EXPECT_TRUE(AllFinite(r.samples.back(), f3r_model_nq(r.model.get())));
}

// ERK after a breakpoint that ends a quiet segment: with table_pulses_fixed_free's inputs on 2
// modes + the pair a link (the accuracy check's basis), the restart at the first pulse (4 ms) took
// the quiet segment's step, its stages reached a state the right-hand side refuses, and ERKStep
// (6.4.1) stopped with ARK_UNREC_RHSFUNC_ERR about 2 ms later, whatever the table. The attempt is
// now made again from its start with a hundredth of the step (sim.c). Against IDA at rtol 1e-10.
TEST(CommandHold, ErkMakesAnAttemptAgainWhenAStageIsRefused) {
  const f3r_scene scene = SceneFromText(
      "links: {model: fixed_free, modes: 2, static_correction: true}\n"
      "effects: {exact_kinematics: true}\n"
      "inputs:\n"
      "  rho_2:\n"
      "    table: {time: [0.0, 0.01, 0.03], value: [0.0, 3.0, -3.0], interpolation: hold}\n"
      "  theta_3:\n"
      "    table: {time: [0.0, 0.004, 0.008, 0.012], value: [0.0, 0.5, -0.5, 0.0], "
      "interpolation: hold}\n"
      "run: {duration: 0.04, output_step: 1.0e-3}\n");
  f3r_solver_settings ida = f3r_solver_settings_from_scene(&scene);
  ida.rtol = 1e-10;
  ida.atol = 1e-12;
  const Outcome ref = Simulate(scene, 1e-3, &ida);
  ASSERT_EQ(ref.status, F3R_OK) << ref.error;
  for (const char* table :
       {"ARKODE_FEHLBERG_13_7_8", "ARKODE_DORMAND_PRINCE_7_4_5", "dormand_prince_8_5"}) {
    SCOPED_TRACE(table);
    f3r_solver_settings erk = f3r_solver_settings_from_scene(&scene);
    erk.integrator = F3R_INTEGRATOR_ERK;
    erk.rtol = 1e-5;
    erk.atol = 1e-7;
    snprintf(erk.rk_table, sizeof erk.rk_table, "%s", table);
    const Outcome r = Simulate(scene, 1e-3, &erk);
    ASSERT_EQ(r.status, F3R_OK) << r.error;
    EXPECT_GT(f3r_sim_stepper(r.sim.get())->recoverable, 0);  // a stage was refused
    ASSERT_EQ(r.samples.size(), ref.samples.size());
    double worst = 0.0;
    for (size_t k = 0; k < r.samples.size(); ++k)
      worst = std::max(worst, std::hypot(r.samples[k].q[F3R_Q_X] - ref.samples[k].q[F3R_Q_X],
                                         r.samples[k].q[F3R_Q_Y] - ref.samples[k].q[F3R_Q_Y]));
    EXPECT_LT(worst, 5e-7);  // Dormand-Prince 5(4) 1.3e-7 m, the eighth-order pairs less
  }
}
