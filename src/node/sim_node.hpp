// Owns the model and the simulation; runs the loop: apply commands, advance one publish period,
// publish, pace to the wall clock.
#pragma once

#include <ros/ros.h>

#include <memory>

#include "command_inputs.hpp"
#include "params.hpp"
#include "services.hpp"
#include "state_outputs.hpp"

namespace flex3rpr {

struct ModelDeleter {
  void operator()(f3r_model* m) const { f3r_model_destroy(m); }
};
struct SimDeleter {
  void operator()(f3r_sim* s) const { f3r_sim_destroy(s); }
};

class SimNode {
 public:
  SimNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  // Reads parameters, builds the model, checks the URDF. False with a ROS_ERROR on failure.
  bool Init();
  // Runs until shutdown or ~duration; returns the process exit code.
  int Run();

 private:
  // Late by more than this much wall time, a paced run says it is behind (~status, ROS_WARN).
  static constexpr double kBehindSeconds = 0.1;

  bool Step(double period);
  void ReportLag(const ros::WallTime& now, const ros::WallTime& pace_wall, double paced_sim);

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  std::unique_ptr<f3r_model, ModelDeleter> model_;
  std::unique_ptr<f3r_sim, SimDeleter> sim_;
  std::unique_ptr<CommandInputs> inputs_;
  std::unique_ptr<StateOutputs> outputs_;
  std::unique_ptr<Services> services_;
  RunControl control_;
  RunInfo info_;
  double phi_p_ = 0.0;
  long periods_ = 0;
};

}  // namespace flex3rpr
