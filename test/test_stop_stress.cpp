// End stops under seeded random pushes and pulls on every leg and on the platform at once: hold
// tables, steps and ramps that drive legs in and out of their stops, with restitution 0,
// intermediate and high, in every formulation and integrator. At every 1 ms output no stroke
// passes a stop by more than 1e-9 m, no locked leg leaves its stop by more than 1e-9 m, the run
// never fails and the energy guard stays quiet. F3R_STOP_STRESS_CASES sets the number of seeds a
// restitution and configuration (default 1), F3R_STOP_STRESS_SECONDS each one's length (default
// 1 s): seconds in CI; F3R_STOP_STRESS_CASES=100 F3R_STOP_STRESS_SECONDS=2 is the long version. The worst figures are printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "test_support.h"

namespace {

constexpr double kTolerance = 1e-9;  // m: the stroke's bound, and a locked leg's
constexpr double kOutputStep = 1e-3;

struct Worst {
  double penetration = -1.0;  // m past a stop (negative: never reached one)
  double locked_drift = 0.0;  // m off its stop while locked
  double energy_ratio = 0.0;  // energy balance error over the largest T + V
  long impacts = 0;
  long locked_outputs = 0;  // outputs with two or more legs locked at once
  int failures = 0;
  std::string where;
};

int CaseCount() {
  const char* text = std::getenv("F3R_STOP_STRESS_CASES");
  return text ? std::max(1, std::atoi(text)) : 1;
}

double Duration() {
  const char* text = std::getenv("F3R_STOP_STRESS_SECONDS");
  return text ? std::max(0.1, std::atof(text)) : 1.0;
}

// One seeded sequence: segments of 20 to 300 ms, each a hold (constant), a step or a ramp of leg
// forces up to 120 N (mostly outward or inward pushes, so legs reach their stops) and a platform
// wrench up to 60 N and 3 N m.
struct Sequence {
  std::mt19937 rng;
  std::vector<double> from, to;  // nq forces at the segment's start and end
  double start = 0.0, end = 0.0;
  bool ramp = false;
  explicit Sequence(unsigned seed, int nq) : rng(seed), from(nq, 0.0), to(nq, 0.0) {}
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(rng); }
  void Next(double t) {
    from = to;
    start = t;
    end = t + Uniform(0.02, 0.3);
    const int kind = static_cast<int>(Uniform(0.0, 3.0));  // hold, step, ramp
    ramp = kind == 2;
    if (kind == 0) from = to;
    for (int i = 0; i < 3; ++i) {
      const double r = Uniform(0.0, 1.0);
      to[i] = r < 0.35  ? Uniform(40.0, 120.0)
              : r < 0.7 ? -Uniform(40.0, 120.0)
                        : Uniform(-20.0, 20.0);
    }
    const bool wrench = Uniform(0.0, 1.0) < 0.4;
    to[F3R_Q_X] = wrench ? Uniform(-60.0, 60.0) : 0.0;
    to[F3R_Q_Y] = wrench ? Uniform(-60.0, 60.0) : 0.0;
    to[F3R_Q_PHI] = wrench ? Uniform(-3.0, 3.0) : 0.0;
    if (!ramp) from = to;
  }
  void At(double t, std::vector<double>* held) const {
    const double s = ramp ? std::clamp((t - start) / (end - start), 0.0, 1.0) : 1.0;
    for (size_t n = 0; n < held->size(); ++n) (*held)[n] = from[n] + s * (to[n] - from[n]);
  }
};

std::string ScenePath(double restitution, const std::string& solver) {
  char name[64];
  std::snprintf(name, sizeof name, "stop_stress_%g_%zu.yaml", restitution,
                std::hash<std::string>()(solver));
  char stops[128];
  std::snprintf(stops, sizeof stops, "  end_stops: {min: 0.0, max: 0.2, restitution: %g}\n",
                restitution);
  return WriteTemp(name,
                   "links: {model: fixed_free, modes: 2, damping_ratio: 0.01}\n"
                   "effects:\n  joint_friction: {prismatic: [5.0, 5.0, 5.0], revolute: [0.01, "
                   "0.01, 0.01]}\n" +
                       std::string(stops) + solver +
                       "initial: {platform_pose: [0.0, 0.0, 0.3]}\nrun: {duration: 2.0}\n");
}

// Runs one seeded sequence for `duration` s and folds its figures into worst.
void RunSequence(const std::string& scene, unsigned seed, double duration, Worst* worst) {
  ModelPtr model = LoadModel(scene);
  const f3r_geometry g = f3r_model_geometry(model.get());
  f3r_sim* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(model.get(), nullptr, &raw, &err), F3R_OK) << err.message;
  SimPtr sim(raw);
  Sequence seq(seed, model->nq);
  std::vector<double> held(model->nq, 0.0);
  double largest_energy = 0.0;
  for (int k = 1; k * kOutputStep <= duration + 1e-12; ++k) {
    const double t0 = (k - 1) * kOutputStep, t = k * kOutputStep;
    if (t0 >= seq.end) seq.Next(t0);
    seq.At(t0, &held);
    if (f3r_sim_set_forces(sim.get(), held.data(), &err) != F3R_OK ||
        f3r_sim_advance(sim.get(), t, &err) != F3R_OK) {
      ++worst->failures;
      ADD_FAILURE() << scene << " seed " << seed << " t " << t << ": " << err.message;
      return;
    }
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    int locked = 0;
    for (int i = 0; i < 3; ++i) {
      const double past = std::max(o->q[i] - g.stroke_max, g.stroke_min - o->q[i]);
      if (past > worst->penetration) {
        worst->penetration = past;
        if (past > kTolerance)
          worst->where = scene + " seed " + std::to_string(seed) + " t " + std::to_string(t) +
                         " leg " + std::to_string(i + 1);
      }
      if (o->stop_locked[i]) {
        ++locked;
        const double stop = o->stop_locked[i] < 0 ? g.stroke_min : g.stroke_max;
        worst->locked_drift = std::max(worst->locked_drift, std::fabs(o->q[i] - stop));
      }
    }
    worst->locked_outputs += locked >= 2;
    largest_energy = std::max(largest_energy, o->kinetic_energy + o->potential_energy);
    if (largest_energy > 0.0 && o->energy_balance_error > F3R_ENERGY_GUARD_FLOOR)
      worst->energy_ratio = std::max(worst->energy_ratio, o->energy_balance_error / largest_energy);
    EXPECT_FALSE(f3r_energy_guard_tripped(o->energy_balance_error, largest_energy))
        << scene << " seed " << seed << " t " << t << ": energy balance error "
        << o->energy_balance_error << " J of the largest T + V " << largest_energy << " J";
  }
  worst->impacts += f3r_sim_outputs(sim.get())->impacts;
}

void Stress(const char* name, const std::string& solver) {
  Worst worst;
  const int cases = CaseCount();
  for (double e : {0.0, 0.3, 0.8}) {
    const std::string scene = ScenePath(e, solver);
    for (int c = 0; c < cases; ++c)
      RunSequence(scene, 1000u * static_cast<unsigned>(e * 10) + c, Duration(), &worst);
  }
  std::printf(
      "measured (%s): %d sequences of %g s: worst penetration %.2e m, worst locked drift %.2e m, "
      "worst energy balance %.1e of T+V, %ld impacts, %ld outputs with two or more legs "
      "locked\n",
      name, 3 * cases, Duration(), worst.penetration, worst.locked_drift, worst.energy_ratio,
      worst.impacts, worst.locked_outputs);
  EXPECT_EQ(worst.failures, 0);
  EXPECT_LE(worst.penetration, kTolerance) << worst.where;
  EXPECT_LE(worst.locked_drift, kTolerance);
  EXPECT_GT(worst.impacts, 0);         // the sequences reach the stops
  EXPECT_GT(worst.locked_outputs, 0);  // and hold several legs at once
}

// The guard's floor: a mechanism at rest balances its 5e-30 J to 1e-29 J, which is rounding.
TEST(EnergyGuard, IgnoresRoundingAtRestAndTripsOnGarbage) {
  EXPECT_FALSE(f3r_energy_guard_tripped(1.2e-29, 5.0e-30));
  EXPECT_FALSE(f3r_energy_guard_tripped(0.05, 1.0));
  EXPECT_TRUE(f3r_energy_guard_tripped(0.5, 1.0));
  EXPECT_TRUE(f3r_energy_guard_tripped(2e-9, 1e-8));
}

TEST(StopStress, MinimalIda) { Stress("minimal, IDA", ""); }
TEST(StopStress, DaeIda) { Stress("dae, IDA", "solver: {formulation: dae}\n"); }
TEST(StopStress, MinimalErk) { Stress("minimal, ERK", "solver: {integrator: erk}\n"); }
// The accuracy check's table (accuracy_check.c) and the work-precision report's fastest at six
// digits (#59): several legs in contact on them too.
TEST(StopStress, MinimalErkTheChecksTable) {
  Stress("minimal, ERK dormand_prince_8_5",
         "solver: {integrator: erk, table: dormand_prince_8_5}\n");
}
TEST(StopStress, MinimalErkVerner87) {
  Stress("minimal, ERK verner_8_7", "solver: {integrator: erk, table: verner_8_7}\n");
}
TEST(StopStress, MinimalDirk) { Stress("minimal, DIRK", "solver: {integrator: dirk}\n"); }

}  // namespace
