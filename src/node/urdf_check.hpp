// The robot_description must describe what the node simulates and publishes: A_i, l, r_PC, the
// stroke (the prismatic limits), and a link for every frame the node publishes.
#pragma once

#include <string>

#include "flex3rpr/model.h"
#include "params.hpp"

namespace flex3rpr {

// Returns "" when the URDF matches the model within tolerance (m) and, given frames, has a link
// for each of them (but the world frame) and no more beam stations; else an error naming the
// joint or link and both values.
std::string CheckUrdf(const std::string& urdf_xml, const f3r_model& model, const FrameNames* frames,
                      double tolerance = 1e-9);

}  // namespace flex3rpr
