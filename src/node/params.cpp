#include "params.hpp"

#include <cstdio>

#include <ros/package.h>

#include <cmath>
#include <sstream>

namespace flex3rpr {

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
  pnh.getParam("rtol", p->scene.rtol);
  pnh.getParam("atol", p->scene.atol);
  if (f3r_scene_validate(&p->scene, &err) != F3R_OK) {
    *error = std::string("parameters override the scene badly: ") + err.message;
    return false;
  }
  p->settings = f3r_solver_settings_from_scene(&p->scene);
  p->settings.stop_at_outputs = 1;  // commands take effect exactly at publish times

  p->publish_rate = pnh.param("publish_rate", 1000.0);
  p->beam_points = pnh.param("beam_points", p->scene.beam_points);
  p->realtime_factor = pnh.param("realtime_factor", 1.0);
  p->world_frame = pnh.param<std::string>("world_frame", "world");
  p->base_frame = pnh.param<std::string>("base_frame", "base");
  p->command_timeout = pnh.param("command_timeout", 0.0);
  p->duration = pnh.param("duration", 0.0);
  if (p->duration < 0.0) p->duration = p->scene.duration;  // the scene's run.duration
  p->wait_for_subscribers = pnh.param("wait_for_subscribers", 0);
  p->subscriber_timeout = pnh.param("subscriber_timeout", 30.0);
  p->subscriber_grace = pnh.param("subscriber_grace", 0.5);
  p->queue_size = pnh.param("queue_size", 10);
  p->command_queue_size = pnh.param("command_queue_size", 1000);
  p->beam_marker_exaggeration = pnh.param("beam_marker_exaggeration", 1.0);
  p->limits.force = pnh.param("max_force", p->limits.force);
  p->limits.torque = pnh.param("max_torque", p->limits.torque);
  p->limits.modal = pnh.param("max_modal_force", p->limits.modal);
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
