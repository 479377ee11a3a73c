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
#include "flex3rpr/scene.h"

namespace flex3rpr {

// Each returns "" and fills forces (nq values) when the message is valid, or a reason naming
// what was wrong and leaves forces alone: its shape ("data has 5 values, expected 6") or, from
// the session's check (flex3rpr/session.h), the value as every shell names it ("leg_force_2 is
// nan, not finite", "cylinder_torque_3 is 150, out of range -100..100 (the scene's
// limits.torque)"), against the scene's limits.
std::string DecodeEffortCommand(const EffortCommand& msg, const f3r_model& model,
                                const f3r_scene& scene, std::vector<double>* forces);

// ros_control JointGroupEffortController order: leg_force_1..3, then cylinder_torque_1..3.
std::string DecodeEffortGroup(const std_msgs::Float64MultiArray& msg, const f3r_model& model,
                              const f3r_scene& scene, std::vector<double>* forces);

// The axes of a frame in the base frame, row-major: v_base = R v_frame.
using Rotation = std::array<double, 9>;
Rotation YawRotation(double yaw);

// A wrench acting on the platform at its centre P, its components given in a frame whose axes
// are turned into the base frame by to_base. In the base frame only force.x, force.y and
// torque.z may be nonzero (the plane); each component must be finite and within the limits,
// both as given and as turned into the base frame.
std::string DecodeWrench(const geometry_msgs::WrenchStamped& msg, const Rotation& to_base,
                         const f3r_scene& scene, const f3r_model& model,
                         std::vector<double>* forces);

}  // namespace flex3rpr
