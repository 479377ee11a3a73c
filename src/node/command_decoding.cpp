#include "command_decoding.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "flex3rpr/session.h"

namespace flex3rpr {

namespace {

// "" if value is finite and within limit, else the reason, naming field.
std::string Check(const std::string& field, double value, double limit) {
  std::ostringstream os;
  os << std::setprecision(17);
  if (std::isnan(value))
    os << field << " is NaN";
  else if (std::isinf(value))
    os << field << " is infinite";
  else if (std::fabs(value) > limit)
    os << field << " = " << value << " exceeds the limit " << limit;
  return os.str();
}

// "" when forces pass the session's command check (flex3rpr/session.h), else its reason, which
// names the value as every shell does ("leg_force_2", "platform_torque", "modal_force[3]").
std::string CoreCheck(const std::vector<double>& forces, const f3r_model& model,
                      const f3r_scene& scene) {
  f3r_error err{};
  return f3r_command_check(&scene, &model, forces.data(), static_cast<int>(forces.size()), &err) ==
                 F3R_OK
             ? std::string()
             : std::string(err.message);
}

}  // namespace

std::string DecodeEffortCommand(const EffortCommand& msg, const f3r_model& model,
                                const f3r_scene& scene, std::vector<double>* forces) {
  const size_t n_modal = static_cast<size_t>(f3r_model_nq(&model) - F3R_Q_MODAL);
  if (!msg.modal.empty() && msg.modal.size() != n_modal)
    return "modal has " + std::to_string(msg.modal.size()) + " values, expected 0 or " +
           std::to_string(n_modal);
  std::vector<double> decoded(static_cast<size_t>(f3r_model_nq(&model)), 0.0);
  for (size_t i = 0; i < 3; ++i) {
    decoded[F3R_FORCE_RHO + i] = msg.leg_force[i];
    decoded[F3R_FORCE_THETA + i] = msg.cylinder_torque[i];
    decoded[F3R_FORCE_PLATFORM + i] = msg.platform[i];
  }
  for (size_t k = 0; k < msg.modal.size(); ++k) decoded[F3R_Q_MODAL + k] = msg.modal[k];
  const std::string why = CoreCheck(decoded, model, scene);
  if (why.empty()) forces->swap(decoded);
  return why;
}

std::string DecodeEffortGroup(const std_msgs::Float64MultiArray& msg, const f3r_model& model,
                              const f3r_scene& scene, std::vector<double>* forces) {
  if (msg.data.size() != F3R_Q_LEG_JOINTS)
    return "data has " + std::to_string(msg.data.size()) +
           " values, expected 6 (leg_force_1..3, cylinder_torque_1..3)";
  std::vector<double> decoded(static_cast<size_t>(f3r_model_nq(&model)), 0.0);
  for (size_t k = 0; k < F3R_Q_LEG_JOINTS; ++k)
    decoded[F3R_Q_RHO + k] = msg.data[k];  // ros_control order is q's
  const std::string why = CoreCheck(decoded, model, scene);
  if (why.empty()) forces->swap(decoded);
  return why;
}

Rotation YawRotation(double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0};
}

std::string DecodeWrench(const geometry_msgs::WrenchStamped& msg, const Rotation& R,
                         const f3r_scene& scene, const f3r_model& model,
                         std::vector<double>* forces) {
  const auto& f = msg.wrench.force;
  const auto& m = msg.wrench.torque;
  const std::pair<const char*, double> all[] = {{"force.x", f.x},  {"force.y", f.y},
                                                {"force.z", f.z},  {"torque.x", m.x},
                                                {"torque.y", m.y}, {"torque.z", m.z}};
  for (const auto& c : all) {
    const bool torque = c.first[0] == 't';
    const std::string why =
        Check(c.first, c.second, torque ? scene.limit_torque : scene.limit_force);
    if (!why.empty()) return why;
  }
  const double fb[3] = {R[0] * f.x + R[1] * f.y + R[2] * f.z, R[3] * f.x + R[4] * f.y + R[5] * f.z,
                        R[6] * f.x + R[7] * f.y + R[8] * f.z};
  const double mb[3] = {R[0] * m.x + R[1] * m.y + R[2] * m.z, R[3] * m.x + R[4] * m.y + R[5] * m.z,
                        R[6] * m.x + R[7] * m.y + R[8] * m.z};
  // In the plane: exactly for a frame turned about z only (R's third row is (0, 0, 1)); to
  // rounding for a frame whose z axis tf2 gives as the base's up to rounding.
  const bool about_z = R[6] == 0.0 && R[7] == 0.0 && R[8] == 1.0;
  const double size = std::fabs(f.x) + std::fabs(f.y) + std::fabs(f.z) + std::fabs(m.x) +
                      std::fabs(m.y) + std::fabs(m.z);
  const double tolerance = about_z ? 0.0 : 1e-12 * size;
  const bool planar = about_z ? f.z == 0.0 && m.x == 0.0 && m.y == 0.0
                              : std::fabs(fb[2]) <= tolerance && std::fabs(mb[0]) <= tolerance &&
                                    std::fabs(mb[1]) <= tolerance;
  if (!planar)
    return "out-of-plane components (force.z, torque.x, torque.y in the base frame) must be zero";
  // The limit holds for the force applied, in the base frame: turning can raise a component by
  // up to sqrt(2) (and overflow to Inf near DBL_MAX). Found by test/fuzz/fuzz_commands.
  std::vector<double> decoded(static_cast<size_t>(f3r_model_nq(&model)), 0.0);
  decoded[F3R_FORCE_PLATFORM] = fb[0];
  decoded[F3R_FORCE_PLATFORM + 1] = fb[1];
  decoded[F3R_FORCE_PLATFORM + 2] = mb[2];
  const std::string why = CoreCheck(decoded, model, scene);
  if (!why.empty()) return why + " (the wrench turned into the base frame)";
  forces->swap(decoded);
  return "";
}

}  // namespace flex3rpr
