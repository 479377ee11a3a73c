#include "urdf_check.hpp"

#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <sstream>

namespace flex3rpr {

namespace {

std::string Mismatch(const std::string& joint, const char* what, double urdf, double model) {
  std::ostringstream os;
  os.precision(12);
  os << "robot_description does not match the scene: joint " << joint << " " << what << " is "
     << urdf << " m in the URDF but " << model << " m in the model";
  return os.str();
}

}  // namespace

std::string CheckUrdfGeometry(const std::string& xml, const f3r_model& model, double tol) {
  urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(xml);
  if (!urdf) return "robot_description is not a valid URDF";
  for (int i = 0; i < 3; ++i) {
    const std::string n = std::to_string(i + 1);
    const auto revolute = urdf->getJoint("leg_" + n + "_revolute");
    const auto tip = urdf->getJoint("leg_" + n + "_tip_nominal");
    const auto pc = urdf->getJoint("platform_c" + n);
    if (!revolute || !tip || !pc)
      return "robot_description lacks joint leg_" + n + "_revolute, leg_" + n +
             "_tip_nominal or platform_c" + n;
    const auto& a = revolute->parent_to_joint_origin_transform.position;
    if (std::fabs(a.x - model.base_joint[i][0]) > tol)
      return Mismatch(revolute->name, "origin x (A_i)", a.x, model.base_joint[i][0]);
    if (std::fabs(a.y - model.base_joint[i][1]) > tol)
      return Mismatch(revolute->name, "origin y (A_i)", a.y, model.base_joint[i][1]);
    const double l = tip->parent_to_joint_origin_transform.position.x;
    if (std::fabs(l - model.link_length) > tol)
      return Mismatch(tip->name, "origin x (link length l)", l, model.link_length);
    const auto& c = pc->parent_to_joint_origin_transform.position;
    const double r = std::hypot(c.x, c.y);
    if (std::fabs(r - model.platform_radius) > tol)
      return Mismatch(pc->name, "distance from the platform centre (r_PC)", r, model.platform_radius);
  }
  return "";
}

}  // namespace flex3rpr
