// ~pause, ~resume (std_srvs/Empty), ~reset and ~step (std_srvs/Trigger), as gazebo_ros users
// know them. They only set flags; the loop in sim_node.cpp acts on them between periods.
#pragma once

#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <std_srvs/Trigger.h>

namespace flex3rpr {

struct RunControl {
  bool paused = false;
  int pending_steps = 0;       // periods to run while paused
  bool reset_requested = false;
};

class Services {
 public:
  Services(ros::NodeHandle& pnh, RunControl* control);

 private:
  RunControl* control_;
  ros::ServiceServer pause_, resume_, reset_, step_;
};

}  // namespace flex3rpr
