// Shipped scenes load and run; bad scenes are refused with the file, line, field and range; the
// CLI writes the documented CSV.
#include <gtest/gtest.h>
#include <unistd.h>

#include <dirent.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "test_support.h"

namespace {

std::vector<std::string> ShippedScenes() {
  std::vector<std::string> names;
  const std::string dir = std::string(F3R_SOURCE_DIR) + "/config/scenes";
  DIR* d = opendir(dir.c_str());
  if (!d) return names;
  while (dirent* e = readdir(d)) {
    std::string n = e->d_name;
    if (n.size() > 5 && n.substr(n.size() - 5) == ".yaml") names.push_back(n);
  }
  closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

// Every scene runs to its end, but two long ones, shortened: free_vibration_long (60 s) to 1 s,
// and stiff_high_modes, which resolves its 20 modes at a real-time factor of 0.005
// (docs/scenes.md), to 5 ms.
TEST(SceneFiles, EveryShippedSceneLoadsAndRunsToItsEnd) {
  const auto names = ShippedScenes();
  ASSERT_GE(names.size(), 12u);
  for (const auto& name : names) {
    f3r_scene s = f3r_default_scene();
    SceneTables owned{&s};
    f3r_error err{};
    ASSERT_EQ(f3r_scene_load(ScenePath(name).c_str(), &s, &err), F3R_OK) << err.message;
    auto m = MakeModel(s);
    f3r_sim* raw = nullptr;
    ASSERT_EQ(f3r_sim_create(m.get(), nullptr, &raw, &err), F3R_OK) << name << ": " << err.message;
    SimPtr sim(raw);
    const double end = name == "free_vibration_long.yaml" ? 1.0
                       : name == "stiff_high_modes.yaml"  ? 0.005
                                                          : s.duration;
    const int chunks = static_cast<int>(std::ceil(end / 0.01 - 1e-9));
    for (int k = 1; k <= chunks; ++k)
      ASSERT_EQ(f3r_sim_advance(sim.get(), std::min(k * 0.01, end), &err), F3R_OK)
          << name << ": " << err.message;
    EXPECT_DOUBLE_EQ(f3r_sim_time(sim.get()), end) << name;
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    for (int n = 0; n < m->nq; ++n) ASSERT_TRUE(std::isfinite(o->q[n])) << name;
  }
}

TEST(SceneFiles, PaperScenesSayWhatMODELmdSays) {
  f3r_scene s;
  f3r_error err{};
  ASSERT_EQ(f3r_scene_load(ScenePath("paper_sim3_fixed_free.yaml").c_str(), &s, &err), F3R_OK);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s.links[i].model, F3R_LINK_FIXED_FREE);
    EXPECT_EQ(s.links[i].modes, 3);
    EXPECT_NEAR(f3r_input_value(&s.inputs[F3R_FORCE_RHO + i], 0.0125),
                50 * std::cos(40 * M_PI * 0.0125) - 50, 1e-12);
    EXPECT_NEAR(f3r_input_value(&s.inputs[F3R_FORCE_THETA + i], 0.0011),
                5 * std::cos(400 * M_PI * 0.0011), 1e-12);
  }
  EXPECT_NEAR(f3r_input_value(&s.inputs[F3R_FORCE_PLATFORM], 0.007),
              100 * std::cos(40 * M_PI * 0.007), 1e-12);
  EXPECT_EQ(s.inputs[F3R_FORCE_PLATFORM + 1].kind, F3R_INPUT_NONE);
  EXPECT_DOUBLE_EQ(s.duration, 0.5);
}

std::string WriteTemp(const std::string& body) {
  char path[] = "/tmp/f3r_scene_XXXXXX.yaml";
  const int fd = mkstemps(path, 5);
  EXPECT_GE(fd, 0);
  FILE* f = fdopen(fd, "w");
  fputs(body.c_str(), f);
  fclose(f);
  return path;
}

std::string LoadError(const std::string& body, std::string* path_out = nullptr) {
  const std::string path = WriteTemp(body);
  if (path_out) *path_out = path;
  f3r_scene s;
  f3r_error err{};
  const f3r_status st = f3r_scene_load(path.c_str(), &s, &err);
  std::remove(path.c_str());
  return st == F3R_OK ? std::string("OK") : std::string(err.message);
}

TEST(SceneFiles, BadScenesNameFileLineFieldAndRange) {
  std::string path;
  std::string e = LoadError(
      "run: {duration: 0.1}\nlinks:\n  - {model: fixed_free, modes: 3}\n"
      "  - {model: fixed_free, modes: 25}\n  - {model: rigid}\n",
      &path);
  EXPECT_EQ(e, path + ":4: links[1].modes: 25 is out of range 1..20");
  e = LoadError("links: {model: rigid, modes: 3}\n", &path);
  EXPECT_EQ(e, path + ":1: links[0].modes: 3 given for a rigid link, which has no modes");
  e = LoadError("platform: {mass: -0.2}\n", &path);
  EXPECT_EQ(e, path + ":1: platform.mass: -0.2 must be positive and finite");
  e = LoadError("solver:\n  formulation: index3\n", &path);
  EXPECT_EQ(e, path + ":2: solver.formulation: 'index3' is not one of dae, minimal");
  e = LoadError("run:\n  duration: 0.1\n  speed: 3\n", &path);
  EXPECT_EQ(e, path + ":3: run.speed: unknown key (allowed: duration, output_step, beam_points)");
  e = LoadError("links: [\n", &path);
  EXPECT_NE(e.find(path + ":"), std::string::npos);
  EXPECT_NE(e.find("YAML syntax"), std::string::npos) << e;
}

TEST(Cli, WritesEveryDocumentedColumnAndASummary) {
  const std::string csv = "/tmp/f3r_cli_test.csv", log = "/tmp/f3r_cli_test.log";
  const std::string cmd = std::string(F3R_CLI) + " " + ScenePath("paper_sim3_fixed_free.yaml") +
                          " --duration 0.002 --out " + csv + " > " + log;
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(csv);
  std::string header;
  std::getline(in, header);
  for (const char* col : {"t,rho_1,rho_2,rho_3,theta_1,theta_2,theta_3,x_p,y_p,phi_p,eta_1_1",
                          "eta_3_3,w_tip_1,w_tip_2,w_tip_3,rho_1_dot", "eta_3_3_dot,w_tip_1_dot",
                          "kinetic_energy,potential_energy,external_work,constraint_residual"})
    EXPECT_NE(header.find(col), std::string::npos) << col << " in " << header;
  int rows = 0;
  for (std::string line; std::getline(in, line);) ++rows;
  EXPECT_EQ(rows, 21);  // t = 0 and 20 output steps of 1e-4 s
  std::ifstream summary(log);
  std::stringstream ss;
  ss << summary.rdbuf();
  for (const char* key : {"steps", "residual evals", "cpu time", "real-time factor",
                          "max constraint res", "energy balance err"})
    EXPECT_NE(ss.str().find(key), std::string::npos) << key;
  EXPECT_NE(std::system((std::string(F3R_CLI) + " /nonexistent.yaml 2>/dev/null").c_str()), 0);
}

// An accuracy request the scene's own solver cannot meet still runs, and warns on stderr.
// The CLI's stderr and exit code for a command line.
struct CliRun {
  int exit_code;
  std::string err;
};
CliRun RunCli(const std::string& args) {
  const std::string err = "/tmp/f3r_cli_err_" + std::to_string(getpid()) + ".txt";
  const int status =
      std::system((std::string(F3R_CLI) + " " + args + " > /dev/null 2> " + err).c_str());
  std::ifstream in(err);
  std::stringstream ss;
  ss << in.rdbuf();
  std::remove(err.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ss.str()};
}

// A request that the scene's own basis and solver cannot reach (one mode a fixed-free link, no
// static shapes: 8.4e-5 m off over 0.05 s): measured, it exits 3 and names the request, the
// measured error and the configurations tried; with --no-verify it warns of the estimate and exits
// 0. A request within reach exits 0 without a warning either way.
TEST(Cli, SaysWhenTheAccuracyRequestIsNotMet) {
  const std::string base =
      ScenePath("paper_sim3_fixed_free.yaml") +
      " --set links.modes=1 --set links.static_correction=false --duration 0.05"
      " --ida --rtol 1e-3 --formulation minimal --accuracy ";
  const CliRun measured = RunCli(base + "1e-6");
  EXPECT_EQ(measured.exit_code, 3) << measured.err;
  EXPECT_NE(measured.err.find("the accuracy request 1e-06 m is not met: measured "),
            std::string::npos)
      << measured.err;
  EXPECT_NE(measured.err.find("after 2 runs (1/1/1 exact, ida rtol 0.001: measured "),
            std::string::npos)
      << measured.err;
  const CliRun estimated = RunCli(base + "1e-6 --no-verify");
  EXPECT_EQ(estimated.exit_code, 0) << estimated.err;
  EXPECT_NE(estimated.err.find(" m is not met: estimated "), std::string::npos) << estimated.err;
  for (const char* flag : {"", " --no-verify"}) {
    const CliRun met = RunCli(base + "1e-3" + flag);
    EXPECT_EQ(met.exit_code, 0) << flag << met.err;
    EXPECT_EQ(met.err.find("warning"), std::string::npos) << flag << met.err;
  }
}

}  // namespace

namespace {

// test/invalid_scenes/NN_name.yaml holds a bad scene and NN_name.expected the error after
// "path:": the line, the field and the allowed range or values.
// f3r_scene_copy is a deep copy: the copy's tables are its own, of their real sizes, and
// outlive the original's; a model built from the copy runs the same path as one built from the
// original (end_stop_impact drives a leg by a table).
TEST(SceneFiles, ACopyOwnsItsTables) {
  f3r_scene s;
  f3r_error err{};
  ASSERT_EQ(f3r_scene_load(ScenePath("end_stop_impact.yaml").c_str(), &s, &err), F3R_OK)
      << err.message;
  int table = -1;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k)
    if (s.inputs[k].kind == F3R_INPUT_TABLE) table = k;
  ASSERT_GE(table, 0);
  const int used = s.inputs[table].table_size;
  EXPECT_EQ(f3r_scene_table_doubles(&s), 2u * used);
  f3r_scene copy_room, *copy = &copy_room;
  ASSERT_EQ(f3r_scene_copy(copy, &s, &err), F3R_OK);
  const f3r_input &from = s.inputs[table], &to = copy->inputs[table];
  EXPECT_NE(to.table_time, from.table_time);
  for (int k = 0; k < used; ++k) {
    EXPECT_EQ(to.table_time[k], from.table_time[k]);
    EXPECT_EQ(to.table_value[k], from.table_value[k]);
  }
  f3r_scene fields = *copy, expected = s; /* all but the table pointers alike */
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) {
    fields.inputs[k].table_time = fields.inputs[k].table_value = nullptr;
    expected.inputs[k].table_time = expected.inputs[k].table_value = nullptr;
  }
  EXPECT_EQ(std::memcmp(&fields, &expected, sizeof expected), 0);
  s.duration = copy->duration = 0.05;
  s.end_stops = copy->end_stops = 0;
  auto final_state = [](const f3r_scene& scene) {
    ModelPtr m = MakeModel(scene);
    const f3r_solver_settings settings = f3r_solver_settings_from_scene(&scene);
    f3r_sim* sim = nullptr;
    f3r_error e{};
    std::vector<double> y;
    if (f3r_sim_create(m.get(), &settings, &sim, &e) == F3R_OK &&
        f3r_sim_advance(sim, scene.duration, &e) == F3R_OK) {
      const double* state = f3r_sim_state(sim);
      y.assign(state, state + f3r_state_size(m.get(), settings.formulation));
    }
    f3r_sim_destroy(sim);
    return y;
  };
  const std::vector<double> original = final_state(s);
  ASSERT_FALSE(original.empty());
  f3r_scene_free(&s); /* the copy's tables outlive the original's */
  EXPECT_EQ(s.inputs[table].table_time, nullptr);
  EXPECT_EQ(original, final_state(*copy));
  f3r_scene_free(copy);
}

// A table set by hand is the input's own copy; the model keeps a copy of its own in its buffer.
TEST(SceneFiles, AHandMadeTableIsCopiedIntoTheModel) {
  f3r_scene s = f3r_default_scene();
  const double time[] = {0.0, 0.1, 0.2}, value[] = {1.0, 2.0, 0.5};
  f3r_error err{};
  ASSERT_EQ(f3r_input_set_table(&s.inputs[F3R_FORCE_RHO], time, value, 1, 0, &err),
            F3R_ERR_ARGUMENT);
  ASSERT_EQ(f3r_input_set_table(&s.inputs[F3R_FORCE_RHO], time, value, 3, 1, &err), F3R_OK);
  EXPECT_EQ(s.inputs[F3R_FORCE_RHO].kind, F3R_INPUT_TABLE);
  EXPECT_EQ(f3r_input_value(&s.inputs[F3R_FORCE_RHO], 0.15), 2.0);
  ModelPtr m = MakeModel(s);
  const f3r_input& kept = f3r_model_scene(m.get())->inputs[F3R_FORCE_RHO];
  EXPECT_NE(kept.table_time, s.inputs[F3R_FORCE_RHO].table_time);
  f3r_scene_free(&s);
  f3r_scene_free(&s); /* twice is safe */
  EXPECT_EQ(f3r_input_value(&kept, 0.15), 2.0);
  EXPECT_EQ(m->n_breakpoints, 2); /* 0.1 and 0.2: breakpoints are after t = 0 */
}

TEST(SceneFiles, InvalidSceneCorpusGivesTheExpectedErrors) {
  const std::string dir = std::string(F3R_SOURCE_DIR) + "/test/invalid_scenes";
  DIR* d = opendir(dir.c_str());
  ASSERT_NE(d, nullptr);
  std::vector<std::string> names;
  while (dirent* e = readdir(d)) {
    std::string n = e->d_name;
    if (n.size() > 5 && n.substr(n.size() - 5) == ".yaml")
      names.push_back(n.substr(0, n.size() - 5));
  }
  closedir(d);
  std::sort(names.begin(), names.end());
  EXPECT_GE(names.size(), 50u);
  for (const auto& n : names) {
    std::ifstream in(dir + "/" + n + ".expected");
    std::string expected;
    std::getline(in, expected);
    ASSERT_FALSE(expected.empty()) << n << ".expected is missing";
    const std::string path = dir + "/" + n + ".yaml";
    f3r_scene s;
    f3r_error err{};
    const f3r_status st = f3r_scene_load(path.c_str(), &s, &err);
    EXPECT_EQ(st, F3R_ERR_SCENE) << n;
    EXPECT_EQ(std::string(err.message), path + ":" + expected) << n;
  }
}

}  // namespace

// An override gives the scene the same file with the field edited by hand would give (the
// independent computation here is the edited file), whether the field is in the file or not.
TEST(SceneOverrides, EqualTheFileEditedByHand) {
  const std::string base =
      "links:\n  - {model: fixed_free, modes: 3}\n  - {model: fixed_free, modes: 3}\n"
      "  - {model: rigid}\nrun: {duration: 0.2}\n";
  const std::string edited =
      "links:\n  - {model: fixed_free, modes: 4}\n  - {model: fixed_pinned, modes: 3}\n"
      "  - {model: rigid}\neffects:\n  payload: {mass: 0.1}\n  gravity: [0, -9.81, 0]\n"
      "run: {duration: 0.3}\n";
  f3r_scene a, b;
  f3r_error err{};
  ASSERT_EQ(LoadWith(WriteTemp("edited.yaml", edited), {}, &b, &err), F3R_OK) << err.message;
  ASSERT_EQ(LoadWith(WriteTemp("base.yaml", base),
                     {"links[0].modes=4", "links[1].model=fixed_pinned", "effects.payload.mass=0.1",
                      "effects.gravity=[0, -9.81, 0]", "run.duration=0.25", "run.duration=0.3"},
                     &a, &err),
            F3R_OK)
      << err.message;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.links[i].model, b.links[i].model) << i;
    EXPECT_EQ(a.links[i].modes, b.links[i].modes) << i;
  }
  EXPECT_EQ(a.payload_mass, b.payload_mass);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(a.gravity[k], b.gravity[k]) << k;
  EXPECT_EQ(a.duration, b.duration);
  EXPECT_EQ(a.explicit_settings, b.explicit_settings);
  EXPECT_EQ(a.links[0].modes, 4);  // and the edit did happen
  EXPECT_EQ(a.duration, 0.3);
}

// "links[i]" on one mapping for all three links sets that link only; "links.field" sets all.
TEST(SceneOverrides, AddressOneLinkOrAll) {
  const std::string shared = WriteTemp("shared.yaml", "links: {model: fixed_free, modes: 2}\n");
  f3r_scene s;
  f3r_error err{};
  ASSERT_EQ(LoadWith(shared, {"links[1].modes=5"}, &s, &err), F3R_OK) << err.message;
  EXPECT_EQ(s.links[0].modes, 2);
  EXPECT_EQ(s.links[1].modes, 5);
  EXPECT_EQ(s.links[2].modes, 2);
  EXPECT_EQ(s.links[2].model, F3R_LINK_FIXED_FREE);
  const std::string list = WriteTemp("list.yaml",
                                     "links:\n  - {model: fixed_free, modes: 2}\n"
                                     "  - {model: rigid}\n  - {model: fixed_free}\n");
  ASSERT_EQ(LoadWith(list, {"links.model=fixed_pinned", "links.modes=6"}, &s, &err), F3R_OK)
      << err.message;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s.links[i].model, F3R_LINK_FIXED_PINNED) << i;
    EXPECT_EQ(s.links[i].modes, 6) << i;
  }
}

// A bad override is refused by the file's own checks, with the override named where a file error
// names path:line; the file's own errors still name the file.
TEST(SceneOverrides, ErrorsNameTheOverride) {
  const std::string path = ScenePath("paper_sim3_fixed_free.yaml");
  const struct {
    const char* set;
    const char* message;
  } cases[] = {
      {"links[0].modes=40", "--set links[0].modes=40: links[0].modes: 40 is out of range 1..20"},
      {"effects.payload.mass=-1",
       "--set effects.payload.mass=-1: effects.payload.mass: -1 is out of range"},
      {"links[0].modez=3", "--set links[0].modez=3: links[0].modez: unknown key"},
      {"foo.bar=1", "--set foo.bar=1: foo: unknown section"},
      {"links[5].modes=2", "--set links[5].modes=2: links has 3 entries"},
      {"effects.gravity=[0, 1]",
       "--set effects.gravity=[0, 1]: effects.gravity: has 2 values, expected 3"},
      {"run.duration=[1", "--set run.duration=[1: the value is not YAML"},
      {"links[0].modes=", "--set links[0].modes=: no value"},
      {"links..modes=1", "--set links..modes=1: expected FIELD=VALUE"},
      {"run.duration.x=1", "--set run.duration.x=1: run.duration is not a mapping"},
  };
  for (const auto& c : cases) {
    f3r_scene s;
    f3r_error err{};
    EXPECT_EQ(LoadWith(path, {c.set}, &s, &err), F3R_ERR_SCENE) << c.set;
    EXPECT_EQ(std::string(err.message).rfind(c.message, 0), 0u)
        << c.set << " gave: " << err.message;
  }
  f3r_scene s;
  f3r_error err{};
  const std::string bad =
      WriteTemp("bad.yaml", "links: {model: fixed_free, modes: 2}\nrun: {duration: -1}\n");
  EXPECT_EQ(LoadWith(bad, {"links[0].modes=3"}, &s, &err), F3R_ERR_SCENE);
  EXPECT_EQ(std::string(err.message).rfind(bad + ":2: run.duration", 0), 0u) << err.message;
}
