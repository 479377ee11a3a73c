// ~pause, ~resume (std_srvs/Empty), ~reset and ~step (std_srvs/Trigger), as gazebo_ros users
// know them. They only set flags; the loop in sim_node.cpp acts on them between periods.
// ~step_with_command, ~set_state and ~linearise act on the simulation itself, through the
// handlers the node gives (session_services.cpp); callbacks run between periods (one thread).
#pragma once

#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <std_srvs/Trigger.h>

#include <functional>

#include "flex3rpr/Linearise.h"
#include "flex3rpr/SetState.h"
#include "flex3rpr/StepWithCommand.h"

namespace flex3rpr {

struct RunControl {
  bool paused = false;
  int pending_steps = 0;  // periods to run while paused
  bool reset_requested = false;
};

struct SimHandlers {
  std::function<void(const StepWithCommand::Request&, StepWithCommand::Response*)>
      step_with_command;
  std::function<void(const SetState::Request&, SetState::Response*)> set_state;
  std::function<void(Linearise::Response*)> linearise;
};

class Services {
 public:
  Services(ros::NodeHandle& pnh, RunControl* control, SimHandlers handlers);

 private:
  RunControl* control_;
  SimHandlers handlers_;
  ros::ServiceServer pause_, resume_, reset_, step_, step_with_command_, set_state_, linearise_;
};

}  // namespace flex3rpr
