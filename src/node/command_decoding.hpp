// Validation and decoding of the node's input messages into generalized forces (model.h
// layout). Pure functions: no ROS master, no simulation state, so they can be fuzzed.
#pragma once

#include <geometry_msgs/WrenchStamped.h>
#include <std_msgs/Float64MultiArray.h>

#include <array>
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

// The axes of a frame in the base frame, row-major: v_base = R v_frame.
using Rotation = std::array<double, 9>;
Rotation YawRotation(double yaw);

// A wrench acting on the platform at its centre P, its components given in a frame whose axes
// are turned into the base frame by to_base. In the base frame only force.x, force.y and
// torque.z may be nonzero (the plane); each component must be finite and within the limits,
// both as given and as turned into the base frame.
std::string DecodeWrench(const geometry_msgs::WrenchStamped& msg, const Rotation& to_base,
                         const CommandLimits& limits, const f3r_model& model,
                         std::vector<double>* forces);

}  // namespace flex3rpr
