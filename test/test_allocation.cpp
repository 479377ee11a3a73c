// No heap allocation inside the integration loop: malloc, calloc and realloc are counted (by
// interposing them in this executable) while a simulation advances, changes its held forces and
// reads its outputs. Counts, not times.
#include <gtest/gtest.h>

#include <atomic>

#include "flex3rpr/sensors.h"
#include "test_support.h"

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);

static std::atomic<bool> counting{false};
static std::atomic<long> allocations{0};

void* malloc(size_t n) {
  if (counting) ++allocations;
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t size) {
  if (counting) ++allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, size_t n) {
  if (counting) ++allocations;
  return __libc_realloc(p, n);
}
}

namespace {

long AllocationsWhileStepping(const std::string& scene, f3r_formulation form,
                              f3r_integrator integrator, long* steps) {
  f3r_scene s;
  f3r_error err{};
  if (f3r_scene_load(ScenePath(scene).c_str(), &s, &err) != F3R_OK)
    throw std::runtime_error(err.message);
  s.formulation = form;
  s.integrator = integrator;
  auto m = MakeModel(s);
  f3r_sim* raw = nullptr;
  if (f3r_sim_create(m.get(), nullptr, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  SimPtr sim(raw);
  std::vector<double> held(m->nq, 0.0);
  if (f3r_sim_advance(sim.get(), 1e-3, &err) != F3R_OK) throw std::runtime_error(err.message);
  allocations = 0;
  counting = true;
  for (int k = 2; k <= 40; ++k) {
    held[0] = (k % 5) * 0.5;  // a new held force every period: restarts too
    f3r_sim_set_forces(sim.get(), held.data(), &err);
    f3r_sim_advance(sim.get(), k * 1e-3, &err);
    f3r_sim_outputs(sim.get());
  }
  counting = false;
  *steps = f3r_sim_outputs(sim.get())->stats.steps;
  return allocations;
}

TEST(Allocation, NoHeapAllocationWhileStepping) {
  struct Case {
    const char* scene;
    f3r_formulation form;
    f3r_integrator integrator;
  } cases[] = {{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_DAE, F3R_INTEGRATOR_IDA},
               {"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_IDA},
               {"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_ERK},
               {"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_DIRK},
               {"end_stop_impact.yaml", F3R_FORMULATION_MINIMAL, F3R_INTEGRATOR_IDA}};
  for (const auto& c : cases) {
    long steps = 0;
    EXPECT_EQ(AllocationsWhileStepping(c.scene, c.form, c.integrator, &steps), 0)
        << c.scene << " formulation " << c.form << " integrator " << c.integrator;
    EXPECT_GT(steps, 100) << "the counted window must contain real steps";
  }
}

// The sensors (sensors.h) sample, add noise, quantise and delay without allocating.
TEST(Allocation, NoHeapAllocationWhileSensing) {
  f3r_scene s;
  f3r_error err{};
  ASSERT_EQ(f3r_scene_load(ScenePath("paper_sim3_fixed_free.yaml").c_str(), &s, &err), F3R_OK);
  auto m = MakeModel(s);
  f3r_sensors_scene c{};
  for (f3r_sensor_scene* k : {&c.kind[F3R_SENSOR_ENCODERS], &c.kind[F3R_SENSOR_STRAIN],
                              &c.kind[F3R_SENSOR_ACCELEROMETER]}) {
    f3r_sensor_scene_defaults(k);
    k->delay = 3;
    k->noise[0] = k->noise[1] = 1e-3;
    k->resolution[0] = 1e-6;
  }
  f3r_sim* raw = nullptr;
  ASSERT_EQ(f3r_sim_create(m.get(), nullptr, &raw, &err), F3R_OK) << err.message;
  SimPtr sim(raw);
  f3r_sensors* sensors = nullptr;
  ASSERT_EQ(f3r_sensors_create(m.get(), &c, &sensors, &err), F3R_OK) << err.message;
  allocations = 0;
  counting = true;
  long taken = 0;
  for (int k = 1; k <= 20; ++k) {
    f3r_sim_advance(sim.get(), k * 1e-3, &err);
    f3r_sensors_update(sensors, f3r_sim_outputs(sim.get()), &err);
    taken += f3r_sensors_reading(sensors, F3R_SENSOR_ACCELEROMETER)->fresh;
  }
  counting = false;
  f3r_sensors_destroy(sensors);
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(taken, 20);
}

TEST(Allocation, TheCounterSeesAllocations) {
  allocations = 0;
  counting = true;
  f3r_scene s = f3r_default_scene();
  f3r_model* m = nullptr;
  f3r_model_create(&s, &m, nullptr);
  counting = false;
  f3r_model_destroy(m);
  EXPECT_GE(allocations, 1) << "creating a model allocates, so the hook works";
}

}  // namespace
