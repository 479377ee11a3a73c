// The robot_description must describe the simulated geometry: A_i, l and r_PC.
#pragma once

#include <string>

#include "flex3rpr/model.h"

namespace flex3rpr {

// Returns "" when the URDF matches the model within tolerance (m), else an error naming the
// joint and both values.
std::string CheckUrdfGeometry(const std::string& urdf_xml, const f3r_model& model,
                              double tolerance = 1e-9);

}  // namespace flex3rpr
