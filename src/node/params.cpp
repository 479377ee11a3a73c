#include "params.hpp"

#include <cstdio>

#include <ros/package.h>

#include <cmath>
#include <sstream>
#include <type_traits>

namespace flex3rpr {

namespace {
const char* TypeName(double) { return "a number"; }
const char* TypeName(int) { return "an integer"; }
const char* TypeName(const std::string&) { return "a string"; }
}  // namespace

// A parameter, or fallback when it is not set. Set with the wrong type (roscpp's param() would
// silently take the default), it is an error naming it.
template <typename T>
static bool Read(const ros::NodeHandle& pnh, const char* name, const T& fallback, T* out,
                 std::string* error) {
  *out = fallback;
  if (!pnh.hasParam(name)) return true;
  XmlRpc::XmlRpcValue value;
  pnh.getParam(name, value);
  // roscpp would truncate 2.5 to an integer: an integer parameter must be one
  const bool integer_ok = !std::is_same<T, int>::value || value.getType() == XmlRpc::XmlRpcValue::TypeInt;
  if (integer_ok && pnh.getParam(name, *out)) return true;
  *error = std::string("parameter ~") + name + ": not " + TypeName(fallback);
  return false;
}

std::string DefaultScenePath() {
  return ros::package::getPath("flex3rpr") + "/config/scenes/paper_sim3_fixed_free.yaml";
}

namespace {

template <typename T>
bool Positive(const char* name, T value, std::string* error) {
  if (value > 0 && std::isfinite(static_cast<double>(value))) return true;
  std::ostringstream os;
  os << "parameter ~" << name << ": " << value << " must be positive";
  *error = os.str();
  return false;
}

bool NonNegative(const char* name, double value, std::string* error) {
  if (value >= 0 && std::isfinite(value)) return true;
  std::ostringstream os;
  os << "parameter ~" << name << ": " << value << " must be zero or positive";
  *error = os.str();
  return false;
}

}  // namespace

bool LoadParams(const ros::NodeHandle& pnh, NodeParams* p, std::string* error) {
  p->scene_path = pnh.param<std::string>("scene", DefaultScenePath());
  f3r_error err{};
  if (f3r_scene_load(p->scene_path.c_str(), &p->scene, &err) != F3R_OK) {
    *error = std::string("parameter ~scene: ") + err.message;
    return false;
  }
  // Single entries of the scene may be overridden by parameter.
  std::string formulation;
  if (pnh.getParam("formulation", formulation)) {
    if (formulation == "dae") p->scene.formulation = F3R_FORMULATION_DAE;
    else if (formulation == "minimal") p->scene.formulation = F3R_FORMULATION_MINIMAL;
    else {
      *error = "parameter ~formulation: '" + formulation + "' is not one of dae, minimal";
      return false;
    }
  }
  std::string integrator;
  if (pnh.getParam("integrator", integrator)) {
    if (integrator == "ida") p->scene.integrator = F3R_INTEGRATOR_IDA;
    else if (integrator == "erk") p->scene.integrator = F3R_INTEGRATOR_ERK;
    else if (integrator == "dirk") p->scene.integrator = F3R_INTEGRATOR_DIRK;
    else {
      *error = "parameter ~integrator: '" + integrator + "' is not one of ida, erk, dirk";
      return false;
    }
  }
  std::string table;
  if (pnh.getParam("table", table))  // checked with the scene below (solver.table)
    std::snprintf(p->scene.table, sizeof p->scene.table, "%s", table.c_str());
  if (!Read(pnh, "rtol", p->scene.rtol, &p->scene.rtol, error) ||
      !Read(pnh, "atol", p->scene.atol, &p->scene.atol, error))
    return false;
  if (f3r_scene_validate(&p->scene, &err) != F3R_OK) {
    *error = std::string("parameters override the scene badly: ") + err.message;
    return false;
  }
  p->settings = f3r_solver_settings_from_scene(&p->scene);
  p->settings.stop_at_outputs = 1;  // commands take effect exactly at publish times

  const bool read =
      Read(pnh, "publish_rate", 1000.0, &p->publish_rate, error) &&
      Read(pnh, "beam_points", p->scene.beam_points, &p->beam_points, error) &&
      Read(pnh, "realtime_factor", 1.0, &p->realtime_factor, error) &&
      Read(pnh, "world_frame", std::string("world"), &p->world_frame, error) &&
      Read(pnh, "base_frame", std::string("base"), &p->base_frame, error) &&
      Read(pnh, "command_timeout", 0.0, &p->command_timeout, error) &&
      Read(pnh, "duration", 0.0, &p->duration, error) &&
      Read(pnh, "wait_for_subscribers", 0, &p->wait_for_subscribers, error) &&
      Read(pnh, "subscriber_timeout", 30.0, &p->subscriber_timeout, error) &&
      Read(pnh, "subscriber_grace", 0.5, &p->subscriber_grace, error) &&
      Read(pnh, "queue_size", 10, &p->queue_size, error) &&
      Read(pnh, "command_queue_size", 1000, &p->command_queue_size, error) &&
      Read(pnh, "beam_marker_exaggeration", 1.0, &p->beam_marker_exaggeration, error) &&
      Read(pnh, "max_force", p->limits.force, &p->limits.force, error) &&
      Read(pnh, "max_torque", p->limits.torque, &p->limits.torque, error) &&
      Read(pnh, "max_modal_force", p->limits.modal, &p->limits.modal, error);
  if (!read) return false;
  if (p->duration < 0.0) p->duration = p->scene.duration;  // the scene's run.duration
  if (!Positive("publish_rate", p->publish_rate, error) ||
      !Positive("beam_points", p->beam_points, error) ||
      !NonNegative("realtime_factor", p->realtime_factor, error) ||
      !NonNegative("command_timeout", p->command_timeout, error) ||
      !NonNegative("duration", p->duration, error) ||
      !NonNegative("wait_for_subscribers", p->wait_for_subscribers, error) ||
      !Positive("subscriber_timeout", p->subscriber_timeout, error) ||
      !NonNegative("subscriber_grace", p->subscriber_grace, error) ||
      !Positive("queue_size", p->queue_size, error) ||
      !Positive("command_queue_size", p->command_queue_size, error) ||
      !Positive("beam_marker_exaggeration", p->beam_marker_exaggeration, error) ||
      !Positive("max_force", p->limits.force, error) ||
      !Positive("max_torque", p->limits.torque, error) ||
      !Positive("max_modal_force", p->limits.modal, error))
    return false;
  if (p->beam_points < 2 || p->beam_points > 101) {
    *error = "parameter ~beam_points: " + std::to_string(p->beam_points) + " is out of range 2..101";
    return false;
  }
  if (p->world_frame.empty() || p->base_frame.empty()) {
    *error = "parameter ~world_frame and ~base_frame must not be empty";
    return false;
  }
  return true;
}

}  // namespace flex3rpr
