// Simulated sensors (sensors.h): the strain gauges against an independent curvature (finite
// differences of the beam deflection from the textbook mode shapes), the accelerometer against a
// finite difference of the platform velocity, noise determinism per seed and independence of the
// update calls, rate, delay, quantisation, bad fields, and the CLI's extra CSV columns.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "flex3rpr/beam_modes.h"
#include "flex3rpr/sensors.h"
#include "test_support.h"

namespace {

struct SensorsDeleter {
  void operator()(f3r_sensors* s) const { f3r_sensors_destroy(s); }
};
using SensorsPtr = std::unique_ptr<f3r_sensors, SensorsDeleter>;

SimPtr MakeSim(const f3r_model* m, double rtol) {
  f3r_solver_settings set = f3r_solver_settings_from_scene(&m->scene);
  set.rtol = rtol;
  set.atol = rtol * 1e-2;
  set.stop_at_outputs = 1;
  f3r_sim* raw = nullptr;
  f3r_error err{};
  if (f3r_sim_create(m, &set, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  return SimPtr(raw);
}

SensorsPtr MakeSensors(const f3r_model* m, const f3r_sensors_scene& config) {
  f3r_sensors* raw = nullptr;
  f3r_error err{};
  if (f3r_sensors_create(m, &config, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  return SensorsPtr(raw);
}

f3r_sensors_scene AllOn() {
  f3r_sensors_scene c{};
  f3r_sensor_scene_defaults(&c.kind[F3R_SENSOR_ENCODERS]);
  f3r_sensor_scene_defaults(&c.kind[F3R_SENSOR_STRAIN]);
  f3r_sensor_scene_defaults(&c.kind[F3R_SENSOR_ACCELEROMETER]);
  return c;
}

// Link 1 fixed-free (3 modes), link 2 fixed-pinned (3 modes), link 3 fixed-free (2 modes), set
// swinging by initial deflections and a platform torque, the platform turned by 0.3 rad.
f3r_scene VibratingScene() {
  f3r_scene s =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_PINNED, 3, F3R_LINK_FIXED_FREE, 2);
  s.links[0].eta0[0] = 2e-3;
  s.links[0].eta0[1] = -3e-4;
  s.links[1].eta0[0] = 1e-3;
  s.links[1].eta0[2] = 1e-4;
  s.links[2].eta_rate0[0] = 0.2;
  s.platform_pose0[0] = 0.01;
  s.platform_pose0[2] = 0.3;
  s.gravity[0] = 0.8;
  s.gravity[1] = -1.7;
  s.inputs[F3R_FORCE_PLATFORM + 2].kind = F3R_INPUT_HARMONIC;
  s.inputs[F3R_FORCE_PLATFORM + 2].amplitude = 0.05;
  s.inputs[F3R_FORCE_PLATFORM + 2].omega = 2 * M_PI * 30;
  s.inputs[F3R_FORCE_PLATFORM].kind = F3R_INPUT_CONSTANT;
  s.inputs[F3R_FORCE_PLATFORM].offset = 0.4;
  return s;
}

// The textbook mode shape (include/flex3rpr/beam_modes.h's printed form, eqs. 3-6), evaluated
// directly in the hyperbolic form: no code of the core but the roots.
double TextbookMode(f3r_beam_end end, double a, double xi) {
  const double sigma = end == F3R_BEAM_FIXED_FREE ? (cos(a) + cosh(a)) / (sin(a) + sinh(a))
                                                  : (cos(a) - cosh(a)) / (sin(a) - sinh(a));
  return (cos(a * xi) - cosh(a * xi)) - sigma * (sin(a * xi) - sinh(a * xi));
}

// w_i(xi) = sum_j psi_j(xi) eta_j (m) of link i at q, from the textbook shapes.
double Deflection(const f3r_model* m, const double* q, int link, double xi) {
  const f3r_link_params* lp = &m->link[link];
  double alpha[F3R_MAX_MODES];
  f3r_beam_roots(static_cast<f3r_beam_end>(lp->model), lp->modes, alpha);
  double w = 0.0;
  for (int j = 0; j < lp->modes; ++j)
    w += TextbookMode(static_cast<f3r_beam_end>(lp->model), alpha[j], xi) * q[lp->eta_index + j];
  return w;
}

// eps = (d/2) w''(0): w'' by the one-sided second difference (2 w0 - 5 w1 + 4 w2 - w3) / h^2,
// second order, over x = 0, h, 2h, 3h (x = xi l).
double FiniteDifferenceStrain(const f3r_model* m, const double* q, int link, double h_xi) {
  double w[4];
  for (int k = 0; k < 4; ++k) w[k] = Deflection(m, q, link, k * h_xi);
  const double h = h_xi * m->link_length;
  return 0.5 * m->scene.link_diameter * (2 * w[0] - 5 * w[1] + 4 * w[2] - w[3]) / (h * h);
}

TEST(Sensors, StrainGaugesMatchTheCurvatureOfTheDeflectionAtTheClamp) {
  const f3r_scene scene = VibratingScene();
  auto m = MakeModel(scene);
  auto sim = MakeSim(m.get(), 1e-8);
  auto sensors = MakeSensors(m.get(), AllOn());
  f3r_error err{};
  double worst = 0.0, largest = 0.0;
  for (int k = 1; k <= 20; ++k) {
    ASSERT_EQ(f3r_sim_advance(sim.get(), k * 5e-4, &err), F3R_OK) << err.message;
    const f3r_outputs* out = f3r_sim_outputs(sim.get());
    double truth[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS];
    ASSERT_EQ(f3r_sensors_truth(sensors.get(), out, truth, &err), F3R_OK) << err.message;
    for (int i = 0; i < 3; ++i) {
      const double fd = FiniteDifferenceStrain(m.get(), out->q, i, 1e-4);
      worst = std::max(worst, std::fabs(truth[F3R_SENSOR_STRAIN][i] - fd));
      largest = std::max(largest, std::fabs(fd));
    }
  }
  std::printf("strain: largest |eps| %.4g, largest |gauge - finite difference| %.3g (%.2g)\n",
              largest, worst, worst / largest);
  EXPECT_GT(largest, 1e-5);  // the links do bend
  EXPECT_LT(worst, 1e-6 * largest);
}

// The sign: a fixed-free link bent by a positive first mode (tip along +n) curves towards +n at
// the clamp, w''(0) > 0, which stretches the fibre on the -n side: the gauge reads tension.
TEST(Sensors, StrainSignAndRigidLinks) {
  f3r_scene s = SceneWithLinks(F3R_LINK_FIXED_FREE, 1, F3R_LINK_RIGID, 0, F3R_LINK_FIXED_FREE, 1);
  auto m = MakeModel(s);
  double c[F3R_MAX_MODES];
  ASSERT_EQ(f3r_sensors_strain_row(m.get(), 0, c), 1);
  EXPECT_GT(m->link[0].tip[0] * c[0], 0.0);  // the same sign as the tip deflection
  EXPECT_EQ(f3r_sensors_strain_row(m.get(), 1, c), 0);
  // psi_1''(0) = -2 alpha^2 (the textbook form), so c = (d/2) 2 alpha^2 |...| / l^2
  const double a = m->link[0].alpha[0];
  EXPECT_NEAR(std::fabs(c[0]), 0.5 * s.link_diameter * 2 * a * a / (s.link_length * s.link_length),
              1e-12 * std::fabs(c[0]));
}

TEST(Sensors, AccelerometerMatchesTheDifferenceOfThePlatformVelocity) {
  const f3r_scene scene = VibratingScene();
  auto m = MakeModel(scene);
  auto sim = MakeSim(m.get(), 1e-11);
  auto sensors = MakeSensors(m.get(), AllOn());
  f3r_error err{};
  // the fourth-order central difference over t - 2h .. t + 2h: the fastest mode (fixed-pinned
  // alpha_3, about 37000 rad/s) has omega h = 0.07 and a truncation of (omega h)^4 / 30 = 1e-6
  const double h = 2e-6;
  double worst = 0.0, largest = 0.0, gyro = 0.0;
  for (int k = 1; k <= 5; ++k) {
    const double t = k * 2e-3;
    f3r_outputs at[5];
    for (int n = 0; n < 5; ++n) {
      ASSERT_EQ(f3r_sim_advance(sim.get(), t + (n - 2) * h, &err), F3R_OK) << err.message;
      at[n] = *f3r_sim_outputs(sim.get());
    }
    const f3r_outputs& now = at[2];
    double truth[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS];
    ASSERT_EQ(f3r_sensors_truth(sensors.get(), &now, truth, &err), F3R_OK) << err.message;
    auto diff = [&](int j) {
      return (8 * (at[3].v[j] - at[1].v[j]) - (at[4].v[j] - at[0].v[j])) / (12 * h);
    };
    const double ax = diff(F3R_Q_X) - scene.gravity[0];
    const double ay = diff(F3R_Q_Y) - scene.gravity[1];
    const double phi = now.q[F3R_Q_PHI], c = cos(phi), s = sin(phi);
    const double fd[2] = {c * ax + s * ay, -s * ax + c * ay};
    for (int j = 0; j < 2; ++j) {
      worst = std::max(worst, std::fabs(truth[F3R_SENSOR_ACCELEROMETER][j] - fd[j]));
      largest = std::max(largest, std::fabs(fd[j]));
    }
    gyro = std::max(gyro, std::fabs(truth[F3R_SENSOR_ACCELEROMETER][2] - now.v[F3R_Q_PHI]));
  }
  std::printf("accelerometer: largest |f| %.4g m/s^2, largest |f - difference| %.3g (%.2g)\n",
              largest, worst, worst / largest);
  EXPECT_GT(largest, 1.0);
  EXPECT_LT(worst, 1e-5 * largest);
  EXPECT_EQ(gyro, 0.0);
}

// Runs scene with config to t_end, updating every `every` outputs of 1e-4 s; the readings
// (value and sample index) of sensor kind after each update that took a sample.
struct Taken {
  long sample;
  double measured_at;
  std::vector<double> value;
};
std::vector<Taken> Record(const f3r_model* m, const f3r_sensors_scene& config, int kind, int every,
                          double t_end, std::vector<std::vector<double>>* truth) {
  auto sim = MakeSim(m, 1e-8);
  auto sensors = MakeSensors(m, config);
  f3r_error err{};
  std::vector<Taken> got;
  const long steps = std::lround(t_end / 1e-4);
  for (long k = 0; k <= steps; ++k) {
    if (k > 0 && f3r_sim_advance(sim.get(), k * 1e-4, &err) != F3R_OK)
      throw std::runtime_error(err.message);
    const f3r_outputs* out = f3r_sim_outputs(sim.get());
    if (truth) {
      double tv[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS];
      f3r_sensors_truth(sensors.get(), out, tv, &err);
      truth->emplace_back(tv[kind], tv[kind] + F3R_SENSOR_MAX_CHANNELS);
    }
    if (k % every) continue;
    if (f3r_sensors_update(sensors.get(), out, &err) != F3R_OK)
      throw std::runtime_error(err.message);
    const f3r_sensor_reading* r = f3r_sensors_reading(sensors.get(), kind);
    if (r->fresh)
      got.push_back({r->sample, r->measured_at, std::vector<double>(r->value, r->value + 6)});
  }
  return got;
}

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(Sensors, NoiseIsDeterministicPerSeedAndIndependentOfTheUpdateCalls) {
  auto m = MakeModel(VibratingScene());
  f3r_sensors_scene c = AllOn();
  c.kind[F3R_SENSOR_STRAIN].noise[0] = 1e-6;
  c.kind[F3R_SENSOR_STRAIN].seed = 7;
  const auto a = Record(m.get(), c, F3R_SENSOR_STRAIN, 1, 0.01, nullptr);
  const auto b = Record(m.get(), c, F3R_SENSOR_STRAIN, 1, 0.01, nullptr);
  // updated at every 1 ms only: the same samples, bit for bit
  const auto sparse = Record(m.get(), c, F3R_SENSOR_STRAIN, 10, 0.01, nullptr);
  c.kind[F3R_SENSOR_STRAIN].seed = 8;
  const auto other = Record(m.get(), c, F3R_SENSOR_STRAIN, 1, 0.01, nullptr);
  ASSERT_EQ(a.size(), 11u);  // samples 0..10 at 1 kHz over 10 ms
  ASSERT_EQ(sparse.size(), a.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].sample, static_cast<long>(k));
    EXPECT_TRUE(SameBits(a[k].value, b[k].value)) << k;
    EXPECT_TRUE(SameBits(a[k].value, sparse[k].value)) << k;
    EXPECT_NE(a[k].value[0], other[k].value[0]) << k;
  }
}

TEST(Sensors, TheNormalDrawsAreStandardAndIndependentOfChannelAndSeed) {
  const int n = 40000;
  double sum = 0, sq = 0, cross = 0;
  for (int k = 0; k < n; ++k) {
    const double x = f3r_sensor_normal(3, 1, 2, k), y = f3r_sensor_normal(3, 1, 1, k);
    sum += x;
    sq += x * x;
    cross += x * y;
  }
  EXPECT_LT(std::fabs(sum / n), 4.0 / std::sqrt(n));
  EXPECT_NEAR(sq / n, 1.0, 0.03);
  EXPECT_LT(std::fabs(cross / n), 4.0 / std::sqrt(n));
  EXPECT_EQ(f3r_sensor_normal(3, 1, 2, 17), f3r_sensor_normal(3, 1, 2, 17));
  EXPECT_NE(f3r_sensor_normal(3, 1, 2, 17), f3r_sensor_normal(4, 1, 2, 17));
}

TEST(Sensors, RateAndDelay) {
  auto m = MakeModel(VibratingScene());
  f3r_sensors_scene c{};
  f3r_sensor_scene_defaults(&c.kind[F3R_SENSOR_ACCELEROMETER]);
  c.kind[F3R_SENSOR_ACCELEROMETER].rate = 2000;  // every 5 outputs of 0.1 ms
  c.kind[F3R_SENSOR_ACCELEROMETER].delay = 3;
  std::vector<std::vector<double>> truth;
  const auto got = Record(m.get(), c, F3R_SENSOR_ACCELEROMETER, 1, 0.01, &truth);
  ASSERT_EQ(got.size(), 21u);  // samples due at 0, 0.5 ms, ..., 10 ms
  for (size_t n = 0; n < got.size(); ++n) {
    const long reported = std::max(0L, static_cast<long>(n) - 3);
    EXPECT_EQ(got[n].sample, reported);
    EXPECT_NEAR(got[n].measured_at, reported * 5e-4, 1e-12);
    for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(got[n].value[ch], truth[reported * 5][ch]) << n;
  }
}

TEST(Sensors, QuantisationRoundsToTheResolution) {
  auto m = MakeModel(VibratingScene());
  f3r_sensors_scene c{};
  f3r_sensor_scene_defaults(&c.kind[F3R_SENSOR_ENCODERS]);
  c.kind[F3R_SENSOR_ENCODERS].resolution[0] = 1e-4;  // 0.1 mm
  c.kind[F3R_SENSOR_ENCODERS].resolution[1] = 2 * M_PI / 4096;
  std::vector<std::vector<double>> truth;
  const auto got = Record(m.get(), c, F3R_SENSOR_ENCODERS, 1, 0.005, &truth);
  ASSERT_EQ(got.size(), 6u);
  for (size_t n = 0; n < got.size(); ++n)
    for (int ch = 0; ch < 6; ++ch) {
      const double res = c.kind[F3R_SENSOR_ENCODERS].resolution[ch / 3], x = got[n].value[ch];
      EXPECT_LT(std::fabs(x / res - std::nearbyint(x / res)), 1e-9);
      EXPECT_LE(std::fabs(x - truth[n * 10][ch]), 0.5 * res * (1 + 1e-12));
    }
}

TEST(Sensors, BadFieldsAreRefusedWithTheFieldAndTheRange) {
  auto m = MakeModel(VibratingScene());
  f3r_sensors_scene c = AllOn();
  c.kind[F3R_SENSOR_STRAIN].delay = 65;
  f3r_sensors* raw = nullptr;
  f3r_error err{};
  EXPECT_EQ(f3r_sensors_create(m.get(), &c, &raw, &err), F3R_ERR_SCENE);
  EXPECT_EQ(raw, nullptr);
  EXPECT_STREQ(err.field, "sensors.strain_gauges.delay");
  EXPECT_NE(std::strstr(err.message, "0..64"), nullptr) << err.message;
  c = AllOn();
  c.kind[F3R_SENSOR_ACCELEROMETER].noise[1] = NAN;
  EXPECT_EQ(f3r_sensors_create(m.get(), &c, &raw, &err), F3R_ERR_SCENE);
  EXPECT_STREQ(err.field, "sensors.accelerometer.gyro_noise");
  c = AllOn();
  c.kind[F3R_SENSOR_ENCODERS].rate = 0;
  EXPECT_EQ(f3r_sensors_create(m.get(), &c, &raw, &err), F3R_ERR_SCENE);
  EXPECT_STREQ(err.field, "sensors.encoders.rate");
  c.kind[F3R_SENSOR_ENCODERS].enabled = 0;  // a sensor that is off is not checked
  EXPECT_EQ(f3r_sensors_create(m.get(), &c, &raw, &err), F3R_OK) << err.message;
  f3r_sensors_destroy(raw);
}

TEST(Sensors, TimeGoingBackIsAnErrorUntilReset) {
  auto m = MakeModel(VibratingScene());
  auto sim = MakeSim(m.get(), 1e-8);
  auto sensors = MakeSensors(m.get(), AllOn());
  f3r_error err{};
  ASSERT_EQ(f3r_sim_advance(sim.get(), 2e-3, &err), F3R_OK);
  ASSERT_EQ(f3r_sensors_update(sensors.get(), f3r_sim_outputs(sim.get()), &err), F3R_OK);
  ASSERT_EQ(f3r_sim_reset(sim.get(), &err), F3R_OK);
  EXPECT_EQ(f3r_sensors_update(sensors.get(), f3r_sim_outputs(sim.get()), &err), F3R_ERR_ARGUMENT);
  f3r_sensors_reset(sensors.get());
  EXPECT_EQ(f3r_sensors_update(sensors.get(), f3r_sim_outputs(sim.get()), &err), F3R_OK);
  EXPECT_EQ(f3r_sensors_reading(sensors.get(), F3R_SENSOR_STRAIN)->sample, 0);
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The CLI writes the sensors' columns after the others only when a sensor is on, and the other
// columns stay bit for bit.
TEST(Sensors, TheCliAddsColumnsOnlyWithSensors) {
  const std::string dir = ::testing::TempDir();
  const std::string base =
      std::string(F3R_CLI) + " " + ScenePath("mixed_links.yaml") + " --set run.duration=0.01";
  ASSERT_EQ(std::system((base + " --out " + dir + "plain.csv > /dev/null").c_str()), 0);
  ASSERT_EQ(std::system((base + " --out " + dir +
                         "sensed.csv --set sensors.strain_gauges.noise=1e-6"
                         " --set sensors.encoders.delay=2 > /dev/null")
                            .c_str()),
            0);
  std::istringstream plain(Slurp(dir + "plain.csv")), sensed(Slurp(dir + "sensed.csv"));
  std::string a, b;
  int rows = 0;
  while (std::getline(plain, a)) {
    ASSERT_TRUE(std::getline(sensed, b));
    ASSERT_EQ(b.compare(0, a.size(), a), 0) << rows;
    const std::string extra = b.substr(a.size());
    if (rows == 0)
      EXPECT_EQ(
          extra,
          ",enc_rho_1,enc_rho_2,enc_rho_3,enc_theta_1,enc_theta_2,enc_theta_3,strain_1,strain_2,"
          "strain_3");
    else
      EXPECT_EQ(std::count(extra.begin(), extra.end(), ','), 9) << extra;
    ++rows;
  }
  EXPECT_EQ(rows, 102);
  EXPECT_FALSE(std::getline(sensed, b));
}

}  // namespace
