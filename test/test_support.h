// Shared helpers of the C++ tests over the C core.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "residual.h"
#include "flex3rpr/sim.h"
#include "model_layout.h" /* the tests read the model's fields */

struct ModelDeleter {
  void operator()(f3r_model* m) const { f3r_model_destroy(m); }
};
struct SimDeleter {
  void operator()(f3r_sim* s) const { f3r_sim_destroy(s); }
};
struct WorkspaceDeleter {
  void operator()(f3r_workspace* w) const { f3r_workspace_destroy(w); }
};
using ModelPtr = std::unique_ptr<f3r_model, ModelDeleter>;
using SimPtr = std::unique_ptr<f3r_sim, SimDeleter>;
using WorkspacePtr = std::unique_ptr<f3r_workspace, WorkspaceDeleter>;

inline f3r_scene SceneWithLinks(f3r_link_model a, int ra, f3r_link_model b, int rb,
                                f3r_link_model c, int rc, bool exact = false) {
  f3r_scene s = f3r_default_scene();
  s.links[0].model = a;
  s.links[0].modes = ra;
  s.links[1].model = b;
  s.links[1].modes = rb;
  s.links[2].model = c;
  s.links[2].modes = rc;
  s.exact_kinematics = exact ? 1 : 0;
  return s;
}

// Frees a scene's input tables (scene.h: a loaded scene owns them) at the end of a scope.
struct SceneTables {
  f3r_scene* scene;
  ~SceneTables() { f3r_scene_free(scene); }
};

// Loads `path` with the overrides `sets` (as --set gives them); the status, the scene and the
// error.
inline f3r_status LoadWith(const std::string& path, std::vector<const char*> sets, f3r_scene* s,
                           f3r_error* err) {
  f3r_scene_options options{};
  options.overrides = sets.data();
  options.override_count = static_cast<int>(sets.size());
  return f3r_scene_load_with(path.c_str(), &options, s, err);
}

// Writes text to a file named name in the test temporary folder; its path.
inline std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

inline ModelPtr MakeModel(const f3r_scene& s) {
  f3r_model* m = nullptr;
  f3r_error err{};
  if (f3r_model_create(&s, &m, &err) != F3R_OK) throw std::runtime_error(err.message);
  return ModelPtr(m);
}

inline ModelPtr LoadModel(const std::string& path, f3r_scene* out = nullptr) {
  f3r_scene s;
  f3r_error err{};
  if (f3r_scene_load(path.c_str(), &s, &err) != F3R_OK) throw std::runtime_error(err.message);
  ModelPtr m = MakeModel(s);
  if (out)
    *out = s; /* the caller's, with its tables */
  else
    f3r_scene_free(&s);
  return m;
}

inline std::string ScenePath(const std::string& name) {
  return std::string(F3R_SOURCE_DIR) + "/config/scenes/" + name;
}

// A generic configuration near the home pose (not necessarily closing the loops), with rates
// and accelerations of realistic size.
struct RandomState {
  std::vector<double> q, v, a;
};

inline RandomState MakeRandomState(const f3r_model* m, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RandomState s;
  s.q.assign(F3R_MAX_Q, 0.0);
  s.v.assign(F3R_MAX_Q, 0.0);
  s.a.assign(F3R_MAX_Q, 0.0);
  const double theta0[3] = {5 * M_PI / 6, 9 * M_PI / 6, M_PI / 6};
  for (int i = 0; i < 3; ++i) {
    s.q[i] = 0.12 + 0.05 * u(rng);
    s.q[3 + i] = theta0[i] + 0.3 * u(rng);
    s.v[i] = u(rng);
    s.v[3 + i] = 5.0 * u(rng);
    s.a[i] = 50.0 * u(rng);
    s.a[3 + i] = 300.0 * u(rng);
  }
  for (int k = 6; k < 9; ++k) {
    s.q[k] = 0.02 * u(rng);
    s.v[k] = u(rng);
    s.a[k] = 50.0 * u(rng);
  }
  for (int k = 9; k < m->nq; ++k) {
    s.q[k] = 1e-3 * u(rng);
    s.v[k] = 0.1 * u(rng);
    s.a[k] = 100.0 * u(rng);
  }
  return s;
}

inline double MaxAbs(const std::vector<double>& x) {
  double r = 0.0;
  for (double v : x) r = std::max(r, std::fabs(v));
  return r;
}
