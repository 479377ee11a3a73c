// The families' tables (flex3rpr/kinds.h): a dummy sensor and two dummy integrators added through
// the tables alone, at run time, then chosen by a scene file as a user would. Nothing else in the
// core learns of them: the loader checks their names and keys, the session samples the sensor
// and lists its columns (what the CLI's CSV and Python's Sim.sensors read), and the simulation
// steps with the registered stepper. docs/design/adding_a_kind.md walks through the same.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "flex3rpr/session.h"
#include "stepper.h"
#include "test_support.h"

namespace {

// leg_sum: the sum of the strokes (m) and of the leg angles (rad), its own noise keys.
void LegSums(const f3r_sensor_input* in, double* value) {
  value[0] = in->out->q[0] + in->out->q[1] + in->out->q[2] + in->constants[0];
  value[1] = in->out->q[3] + in->out->q[4] + in->out->q[5];
}
// A model constant, to see that prepare runs once and reaches measure: 0 m, computed.
void Prepare(const f3r_model*, double* constants) { constants[0] = 0.0 * std::sqrt(2.0); }

const f3r_sensor_kind kLegSum = {"leg_sum",
                                 "sensors/leg_sum",
                                 "the sum of the strokes and of the leg angles",
                                 2,
                                 {"rho_sum", "theta_sum"},
                                 {nullptr},
                                 {"rho_noise", "theta_noise"},
                                 {"rho_resolution", nullptr},
                                 {0, 1}};
const f3r_sensor_measure kLegSumMeasure = {0, Prepare, LegSums};

// Two integrators with the built-ins' steppers under new names: the tables' rows decide what a
// scene may ask of them.
const f3r_integrator_kind kIdaTwin = {"ida_twin",
                                      "IDA again, registered",
                                      (1u << F3R_FORMULATION_DAE) | (1u << F3R_FORMULATION_MINIMAL),
                                      0,
                                      nullptr,
                                      1};
const char* const kTwinTables[] = {"ARKODE_DORMAND_PRINCE_7_4_5", nullptr};
const f3r_integrator_kind kErkTwin = {
    "erk_twin", "ERKStep again, registered", 1u << F3R_FORMULATION_MINIMAL, 1, kTwinTables, 0};

int leg_sum = -1, ida_twin = -1, erk_twin = -1;

class Kinds : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    f3r_error err{};
    ASSERT_EQ(f3r_sensors_register(&kLegSum, &kLegSumMeasure, &leg_sum, &err), F3R_OK)
        << err.message;
    ASSERT_EQ(f3r_integrators_register(&kIdaTwin, &f3r_ida_stepper, &ida_twin, &err), F3R_OK)
        << err.message;
    ASSERT_EQ(f3r_integrators_register(&kErkTwin, &f3r_erk_stepper, &erk_twin, &err), F3R_OK)
        << err.message;
  }
};

// A scene of the repository with text appended (its sections are the file's last ones).
std::string SceneWith(const std::string& name, const std::string& more) {
  std::ifstream in(ScenePath("rest_turned.yaml"));
  std::stringstream text;
  text << in.rdbuf() << "\n" << more;
  return WriteTemp(name, text.str());
}

struct Session {
  f3r_session* s = nullptr;
  f3r_error err{};
  f3r_status st;
  Session(const std::string& path, std::vector<const char*> sets = {}) {
    f3r_session_options o{};
    o.overrides = sets.data();
    o.override_count = static_cast<int>(sets.size());
    st = f3r_session_open(path.c_str(), &o, &s, &err);
  }
  ~Session() { f3r_session_close(s); }
};

TEST_F(Kinds, RegisteredOnceAndRefusedTwice) {
  EXPECT_EQ(leg_sum, 3);
  EXPECT_EQ(f3r_sensor_kind_find("leg_sum"), leg_sum);
  EXPECT_EQ(ida_twin, 3);
  EXPECT_EQ(erk_twin, 4);
  f3r_integrator named;
  ASSERT_EQ(f3r_integrator_from_name("erk_twin", &named), 0);
  EXPECT_EQ(static_cast<int>(named), erk_twin);
  char names[256];
  EXPECT_STREQ(f3r_integrator_names(names, sizeof names), "ida, erk, dirk, ida_twin, erk_twin");
  f3r_error err{};
  int again = -1;
  EXPECT_EQ(f3r_sensors_register(&kLegSum, &kLegSumMeasure, &again, &err), F3R_ERR_ARGUMENT);
  EXPECT_EQ(f3r_integrators_register(&kIdaTwin, &f3r_ida_stepper, &again, &err), F3R_ERR_ARGUMENT);
  EXPECT_EQ(f3r_sensor_kind_count(), 4);
}

TEST_F(Kinds, ASceneSamplesTheDummySensorAndListsItsColumns) {
  Session a(SceneWith("leg_sum.yaml",
                      "sensors:\n  leg_sum: {rate: 500, rho_resolution: 1e-6}\n"
                      "  encoders: {}\n"));
  ASSERT_EQ(a.st, F3R_OK) << a.err.message;
  const f3r_sensors* sensors = f3r_session_sensors(a.s);
  ASSERT_NE(sensors, nullptr);
  // encoders first, then the dummy, in the table's order: the CLI's and Python's columns
  ASSERT_EQ(f3r_sensors_columns(sensors), 8);
  EXPECT_STREQ(f3r_sensors_column_name(sensors, 6), "rho_sum");
  EXPECT_STREQ(f3r_sensors_column_name(sensors, 7), "theta_sum");
  const f3r_model* m = f3r_session_model(a.s);
  std::vector<double> push(f3r_model_nq(m), 0.0);
  push[0] = 50.0;  // leg 1's force moves every joint
  f3r_error err{};
  ASSERT_EQ(f3r_session_step(a.s, push.data(), static_cast<int>(push.size()), 10, 1e-3, &err),
            F3R_OK)
      << err.message;
  const f3r_sensor_reading* r = f3r_sensors_reading(sensors, leg_sum);
  EXPECT_EQ(r->sample, 5);  // 500 Hz over 10 ms
  const f3r_outputs* out = f3r_sim_outputs(f3r_session_sim(a.s));
  const double rho = out->q[0] + out->q[1] + out->q[2], theta = out->q[3] + out->q[4] + out->q[5];
  EXPECT_NEAR(r->value[0], rho, 0.5e-6 + 1e-15);  // rounded to the resolution
  EXPECT_DOUBLE_EQ(r->value[1], theta);
  EXPECT_EQ(std::fmod(std::fabs(r->value[0]) + 1e-12, 1e-6) < 1e-9, true);
  double row[16];
  ASSERT_EQ(f3r_sensors_row(sensors, row), 8);
  EXPECT_EQ(row[6], r->value[0]);
  EXPECT_EQ(row[0], f3r_sensors_reading(sensors, F3R_SENSOR_ENCODERS)->value[0]);
}

TEST_F(Kinds, TheLoaderChecksTheDummysKeysAndRanges) {
  Session bad_key(SceneWith("leg_sum_key.yaml", "sensors:\n  leg_sum: {gyro_noise: 1}\n"));
  EXPECT_EQ(bad_key.st, F3R_ERR_SCENE);
  EXPECT_NE(std::string(bad_key.err.message)
                .find("sensors.leg_sum.gyro_noise: unknown key (allowed: enabled, rate, delay, "
                      "seed, rho_noise, theta_noise, rho_resolution)"),
            std::string::npos)
      << bad_key.err.message;
  Session negative(SceneWith("leg_sum_range.yaml", "sensors:\n  leg_sum: {}\n"),
                   {"sensors.leg_sum.theta_noise=-1"});
  EXPECT_NE(std::string(negative.err.message)
                .find("sensors.leg_sum.theta_noise: -1 must be finite and at least 0"),
            std::string::npos)
      << negative.err.message;
  Session unknown(SceneWith("leg_sum_unknown.yaml", "sensors:\n  leg_sums: {}\n"));
  EXPECT_NE(std::string(unknown.err.message)
                .find("unknown sensor (allowed: encoders, strain_gauges, accelerometer, leg_sum)"),
            std::string::npos)
      << unknown.err.message;
}

// The run of a scene with an integrator by name: the end-effector path at 1 ms outputs.
std::vector<double> Path(const std::vector<const char*>& sets) {
  Session a(ScenePath("paper_sim3_fixed_free.yaml"), sets);
  EXPECT_EQ(a.st, F3R_OK) << a.err.message;
  if (a.st != F3R_OK) return {};
  f3r_sim* sim = f3r_session_sim(a.s);
  std::vector<double> path;
  f3r_error err{};
  for (int k = 1; k <= 20; ++k) {
    EXPECT_EQ(f3r_sim_advance(sim, 1e-3 * k, &err), F3R_OK) << err.message;
    const f3r_outputs* out = f3r_sim_outputs(sim);
    path.insert(path.end(), out->q + F3R_Q_X, out->q + F3R_Q_X + 3);
  }
  return path;
}

TEST_F(Kinds, ASceneStepsWithTheDummyIntegrators) {
  // the same stepper under another name gives the same numbers, bit for bit
  EXPECT_EQ(Path({"solver.integrator=ida_twin"}), Path({"solver.integrator=ida"}));
  EXPECT_EQ(Path({"solver.integrator=erk_twin", "solver.table=ARKODE_DORMAND_PRINCE_7_4_5"}),
            Path({"solver.integrator=erk", "solver.table=ARKODE_DORMAND_PRINCE_7_4_5"}));
  // the dummies' rows say what they take
  Session dae(ScenePath("paper_sim3_fixed_free.yaml"),
              {"solver.integrator=erk_twin", "solver.formulation=dae"});
  EXPECT_NE(std::string(dae.err.message).find("erk_twin integrates the minimal formulation only"),
            std::string::npos)
      << dae.err.message;
  Session table(ScenePath("paper_sim3_fixed_free.yaml"),
                {"solver.integrator=erk_twin", "solver.table=ARKODE_FEHLBERG_13_7_8"});
  EXPECT_NE(std::string(table.err.message).find("ARKODE_DORMAND_PRINCE_7_4_5"), std::string::npos)
      << table.err.message;
  Session no_table(ScenePath("paper_sim3_fixed_free.yaml"),
                   {"solver.integrator=ida_twin", "solver.table=ARKODE_FEHLBERG_13_7_8"});
  EXPECT_NE(std::string(no_table.err.message)
                .find("a Butcher table needs integrator erk or dirk or erk_twin"),
            std::string::npos)
      << no_table.err.message;
}

}  // namespace
