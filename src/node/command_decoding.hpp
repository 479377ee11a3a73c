// Validation and decoding of the node's input messages into generalized forces (model.h
// layout). Pure functions: no ROS master, no simulation state, so they can be fuzzed.
#pragma once

#include <geometry_msgs/WrenchStamped.h>
#include <std_msgs/Float64MultiArray.h>

#include <string>
#include <vector>

#include "flex3rpr/EffortCommand.h"
#include "flex3rpr/model.h"
#include "params.hpp"

namespace flex3rpr {

// Each returns "" and fills forces (nq values) when the message is valid, or a reason naming
// the field ("leg_force[1] is NaN", "data has 5 values, expected 6", ...) and leaves forces alone.
std::string DecodeEffortCommand(const EffortCommand& msg, const f3r_model& model,
                                const CommandLimits& limits, std::vector<double>* forces);

// ros_control JointGroupEffortController order: leg_force_1..3, then cylinder_torque_1..3.
std::string DecodeEffortGroup(const std_msgs::Float64MultiArray& msg, const f3r_model& model,
                              const CommandLimits& limits, std::vector<double>* forces);

// force.x, force.y, torque.z in world_frame (or an empty frame_id) or platform_frame, which is
// turned by the platform angle phi_p; any other nonzero component is out of the plane.
std::string DecodeWrench(const geometry_msgs::WrenchStamped& msg, const std::string& world_frame,
                         const std::string& platform_frame, double phi_p,
                         const CommandLimits& limits, const f3r_model& model,
                         std::vector<double>* forces);

}  // namespace flex3rpr
