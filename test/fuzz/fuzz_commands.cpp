// libFuzzer harness for the node's command decoding (src/node/command_decoding.cpp), without a
// ROS master: the fuzzer bytes choose a decoder, a model size (nq), the limits and a message
// (EffortCommand with any modal[] length, Float64MultiArray with any data length,
// WrenchStamped with any frame_id), whose values may be any double: NaN, Inf, -0, denormals,
// values at and just beyond the limits.
//
// Invariants, checked on every input (abort() on a violation, which libFuzzer reports):
//  - accepted ("" returned): forces has nq values, every one finite and within its limit
//    (leg and platform forces max_force, torques max_torque, modal forces max_modal_force),
//    at the indices of model.h's layout, zero elsewhere;
//  - rejected (a reason returned): the reason is not empty and forces is unchanged (size and
//    every bit);
//  - the decision agrees with an independent statement of the rules (docs/ros.md, "Inputs"): a
//    message is accepted exactly when its lengths, frame and values are allowed.
//
//   scripts/ci/fuzz [SECONDS]   builds this with clang++ -fsanitize=fuzzer,address,undefined
#include <fuzzer/FuzzedDataProvider.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "command_decoding.hpp"

namespace {

// The scene's limits section (limits.force, .torque, .modal_force), as the harness draws them.
struct CommandLimits {
  double force = 1000.0, torque = 100.0, modal = 1000.0;
};

f3r_scene SceneWith(const CommandLimits& l) {
  f3r_scene scene = f3r_default_scene();
  scene.limit_force = l.force;
  scene.limit_torque = l.torque;
  scene.limit_modal_force = l.modal;
  return scene;
}

[[noreturn]] void Fail(const char* what, const std::string& reason = "") {
  std::fprintf(stderr, "fuzz_commands: invariant broken: %s%s%s\n", what,
               reason.empty() ? "" : ": ", reason.c_str());
  std::abort();
}

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// Any double, with the values that matter for the checks made likely.
double AnyValue(FuzzedDataProvider& p, double limit) {
  switch (p.ConsumeIntegralInRange<int>(0, 4)) {
    case 0: {  // any bit pattern: NaN payloads, infinities, denormals
      uint64_t bits = p.ConsumeIntegral<uint64_t>();
      double v;
      std::memcpy(&v, &bits, sizeof v);
      return v;
    }
    case 1: {
      const double special[] = {0.0,
                                -0.0,
                                kNaN,
                                -kNaN,
                                kInf,
                                -kInf,
                                limit,
                                -limit,
                                std::nextafter(limit, kInf),
                                -std::nextafter(limit, kInf),
                                std::nextafter(limit, 0.0),
                                DBL_MAX,
                                -DBL_MAX,
                                DBL_MIN,
                                std::numeric_limits<double>::denorm_min(),
                                1.0,
                                -1.0,
                                std::numeric_limits<double>::signaling_NaN()};
      return special[p.ConsumeIntegralInRange<size_t>(0, sizeof special / sizeof special[0] - 1)];
    }
    case 2: return p.ConsumeFloatingPointInRange<double>(-limit, limit);
    case 3: return p.ConsumeFloatingPoint<double>();
    default: return static_cast<double>(p.ConsumeIntegralInRange<int>(-3, 3));
  }
}

// A limit as LoadParams allows it: positive and finite (default when the bytes say nothing).
double AnyLimit(FuzzedDataProvider& p, double fallback) {
  switch (p.ConsumeIntegralInRange<int>(0, 3)) {
    case 0: return fallback;
    case 1: {
      const double special[] = {DBL_MAX, DBL_MIN, std::numeric_limits<double>::denorm_min(),
                                1.0,     1e300,   0.5};
      return special[p.ConsumeIntegralInRange<size_t>(0, sizeof special / sizeof special[0] - 1)];
    }
    default: {
      const double v = std::fabs(p.ConsumeFloatingPoint<double>());
      return v > 0.0 && std::isfinite(v) ? v : fallback;
    }
  }
}

std::string AnyFrame(FuzzedDataProvider& p) {
  switch (p.ConsumeIntegralInRange<int>(0, 3)) {
    case 0: return "world";
    case 1: return "platform";
    case 2: return "";
    default: return p.ConsumeRandomLengthString(40);
  }
}

bool Allowed(double v, double limit) { return std::isfinite(v) && std::fabs(v) <= limit; }

double LimitAt(size_t index, const CommandLimits& l) {
  if (index < 3) return l.force;    // rho_i
  if (index < 6) return l.torque;   // theta_i
  if (index < 8) return l.force;    // platform F_x, F_y
  if (index == 8) return l.torque;  // platform torque
  return l.modal;                   // modal forces
}

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

void CheckAccepted(const std::vector<double>& forces, const f3r_model& model,
                   const CommandLimits& limits) {
  if (forces.size() != static_cast<size_t>(f3r_model_nq(&model)))
    Fail("accepted, but forces is not nq long");
  for (size_t n = 0; n < forces.size(); ++n) {
    if (!std::isfinite(forces[n])) Fail("accepted, but a force is not finite");
    if (std::fabs(forces[n]) > LimitAt(n, limits)) {
      char what[160];
      std::snprintf(what, sizeof what, "accepted, but force[%zu] = %.17g exceeds its limit %.17g",
                    n, forces[n], LimitAt(n, limits));
      Fail(what);
    }
  }
}

// The default scene with fixed-free links carrying n_modal modes in all (up to 20 a link; a
// link left with none is rigid), built once per count and kept.
f3r_model* ModelWithModalCoordinates(int n_modal) {
  static f3r_model* models[F3R_MAX_Q] = {};
  if (models[n_modal]) return models[n_modal];
  f3r_scene scene = f3r_default_scene();
  int left = n_modal;
  for (int i = 0; i < 3; ++i) {
    const int r = left < F3R_MAX_MODES ? left : F3R_MAX_MODES;
    scene.links[i].model = r ? F3R_LINK_FIXED_FREE : F3R_LINK_RIGID;
    scene.links[i].modes = r;
    left -= r;
  }
  f3r_error err;
  if (f3r_model_create(&scene, &models[n_modal], &err) != F3R_OK) Fail(err.message);
  if (f3r_model_nq(models[n_modal]) != 9 + n_modal) Fail("the model has the wrong nq");
  return models[n_modal];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider p(data, size);
  // A real model with any nq: 9 + the modes of links flexible or rigid, at most F3R_MAX_Q.
  f3r_model* model = ModelWithModalCoordinates(p.ConsumeIntegralInRange<int>(0, F3R_MAX_Q - 9));
  CommandLimits limits;
  limits.force = AnyLimit(p, limits.force);
  limits.torque = AnyLimit(p, limits.torque);
  limits.modal = AnyLimit(p, limits.modal);
  const f3r_scene scene = SceneWith(limits);

  // What forces holds before the call: any length, any bits; it must survive a rejection.
  std::vector<double> forces(p.ConsumeIntegralInRange<size_t>(0, 80));
  for (double& f : forces) f = AnyValue(p, 1.0);
  const std::vector<double> before = forces;

  const int which = p.ConsumeIntegralInRange<int>(0, 2);
  std::string why;
  bool expect_ok = true;
  std::vector<double> expected;  // the accepted forces, where the harness can state them exactly
  double turned_in = -1.0, turned_torque = 0.0;  // a platform-frame wrench: |(f.x, f.y)|, torque.z
  if (which == 0) {
    flex3rpr::EffortCommand msg;
    for (size_t i = 0; i < 3; ++i) {
      msg.leg_force[i] = AnyValue(p, limits.force);
      msg.cylinder_torque[i] = AnyValue(p, limits.torque);
      msg.platform[i] = AnyValue(p, i < 2 ? limits.force : limits.torque);
      expect_ok = expect_ok && Allowed(msg.leg_force[i], limits.force) &&
                  Allowed(msg.cylinder_torque[i], limits.torque) &&
                  Allowed(msg.platform[i], i < 2 ? limits.force : limits.torque);
    }
    const size_t n_modal = static_cast<size_t>(f3r_model_nq(model) - 9);
    size_t len;
    switch (p.ConsumeIntegralInRange<int>(0, 3)) {
      case 0: len = 0; break;
      case 1: len = n_modal; break;
      default: len = p.ConsumeIntegralInRange<size_t>(0, 100); break;
    }
    msg.modal.resize(len);
    for (double& m : msg.modal) {
      m = AnyValue(p, limits.modal);
      expect_ok = expect_ok && Allowed(m, limits.modal);
    }
    expect_ok = expect_ok && (len == 0 || len == n_modal);
    why = flex3rpr::DecodeEffortCommand(msg, *model, scene, &forces);
    expected.assign(static_cast<size_t>(f3r_model_nq(model)), 0.0);
    for (size_t i = 0; i < 3; ++i) {
      expected[i] = msg.leg_force[i];
      expected[3 + i] = msg.cylinder_torque[i];
      expected[6 + i] = msg.platform[i];
    }
    for (size_t k = 0; k < msg.modal.size() && 9 + k < expected.size(); ++k)
      expected[9 + k] = msg.modal[k];
  } else if (which == 1) {
    std_msgs::Float64MultiArray msg;
    size_t len = p.ConsumeBool() ? 6 : p.ConsumeIntegralInRange<size_t>(0, 100);
    msg.data.resize(len);
    for (size_t k = 0; k < len; ++k) {
      msg.data[k] = AnyValue(p, k < 3 ? limits.force : limits.torque);
      expect_ok = expect_ok && Allowed(msg.data[k], k < 3 ? limits.force : limits.torque);
    }
    // The layout is ignored; fill it anyway, as a publisher may.
    if (p.ConsumeBool()) {
      msg.layout.dim.resize(1);
      msg.layout.dim[0].label = p.ConsumeRandomLengthString(16);
      msg.layout.dim[0].size = p.ConsumeIntegral<uint32_t>();
      msg.layout.dim[0].stride = p.ConsumeIntegral<uint32_t>();
      msg.layout.data_offset = p.ConsumeIntegral<uint32_t>();
    }
    expect_ok = expect_ok && len == 6;
    why = flex3rpr::DecodeEffortGroup(msg, *model, scene, &forces);
    expected.assign(static_cast<size_t>(f3r_model_nq(model)), 0.0);
    for (size_t k = 0; k < 6 && k < len; ++k) expected[k] = msg.data[k];
  } else {
    geometry_msgs::WrenchStamped msg;
    msg.header.frame_id = AnyFrame(p);  // resolved by the node (tf2); here only the axes matter
    msg.header.seq = p.ConsumeIntegral<uint32_t>();
    const bool in_world = p.ConsumeBool();  // the base's axes, or a frame turned by phi_p
    // phi_p is the platform angle of the simulation's state, which the core keeps finite.
    double phi_p = AnyValue(p, 10.0);
    if (!std::isfinite(phi_p)) phi_p = 0.0;
    auto& w = msg.wrench;
    w.force.x = AnyValue(p, limits.force);
    w.force.y = AnyValue(p, limits.force);
    w.force.z = p.ConsumeBool() ? 0.0 : AnyValue(p, limits.force);
    w.torque.x = p.ConsumeBool() ? 0.0 : AnyValue(p, limits.torque);
    w.torque.y = p.ConsumeBool() ? 0.0 : AnyValue(p, limits.torque);
    w.torque.z = AnyValue(p, limits.torque);
    // The limit holds for the force applied, in the world frame: a platform-frame force is
    // turned by phi_p first (which can raise a component by up to sqrt(2)).
    double fx = w.force.x, fy = w.force.y;
    if (!in_world) {
      const double c = std::cos(phi_p), s = std::sin(phi_p);
      fx = c * w.force.x - s * w.force.y;
      fy = s * w.force.x + c * w.force.y;
    }
    expect_ok = Allowed(fx, limits.force) && Allowed(fy, limits.force) &&
                Allowed(w.force.x, limits.force) && Allowed(w.force.y, limits.force) &&
                Allowed(w.force.z, limits.force) && Allowed(w.torque.x, limits.torque) &&
                Allowed(w.torque.y, limits.torque) && Allowed(w.torque.z, limits.torque) &&
                w.force.z == 0.0 && w.torque.x == 0.0 && w.torque.y == 0.0;
    why = flex3rpr::DecodeWrench(msg, flex3rpr::YawRotation(in_world ? 0.0 : phi_p), scene, *model,
                                 &forces);
    if (why.empty() && forces.size() == static_cast<size_t>(f3r_model_nq(model))) {
      if (in_world) {
        expected.assign(static_cast<size_t>(f3r_model_nq(model)), 0.0);
        expected[6] = w.force.x;
        expected[7] = w.force.y;
        expected[8] = w.torque.z;
      } else {  // turned by phi_p: checked below for what a turn keeps
        expected = forces;
        // at half scale: a magnitude near DBL_MAX would overflow on one side of the comparison
        turned_in = std::hypot(0.5 * w.force.x, 0.5 * w.force.y);
        turned_torque = w.torque.z;
      }
    }
  }

  static const bool verbose = std::getenv("FUZZ_COMMANDS_VERBOSE") != nullptr;
  if (verbose) {  // FUZZ_COMMANDS_VERBOSE=1 build/fuzz/fuzz_commands FILE...: what each input is
    static const char* names[] = {"~command", "~effort_group/command", "~platform_wrench"};
    std::fprintf(stderr, "%s, nq %d, limits %g %g %g: %s\n", names[which], f3r_model_nq(model),
                 limits.force, limits.torque, limits.modal, why.empty() ? "accepted" : why.c_str());
    if (why.empty()) {
      std::fprintf(stderr, "  forces");
      for (double f : forces) std::fprintf(stderr, " %.17g", f);
      std::fprintf(stderr, "\n");
    }
  }
  if (why.empty()) {
    if (!expect_ok) Fail("a command the rules forbid was accepted");
    CheckAccepted(forces, *model, limits);
    for (size_t n = 0; n < forces.size(); ++n)
      if (!(forces[n] == expected[n])) Fail("an accepted force is not the command's value");
    if (turned_in >= 0.0) {  // the turn keeps the in-plane magnitude (to rounding; absolute near
                             // the denormals, where it loses digits) and leaves the torque alone
      const double out = std::hypot(0.5 * forces[6], 0.5 * forces[7]);
      if (std::fabs(turned_in - out) > 1e-12 * turned_in + 1e-300)
        Fail("a platform-frame force changed magnitude");
      if (forces[8] != turned_torque) Fail("the platform torque was changed");
      for (size_t n = 0; n < forces.size(); ++n)
        if ((n < 6 || n > 8) && forces[n] != 0.0)
          Fail("a force outside the platform's is not zero");
    }
  } else {
    if (expect_ok) Fail("a command the rules allow was rejected", why);
    if (!SameBits(forces, before)) Fail("a rejected command changed forces", why);
  }
  return 0;
}
