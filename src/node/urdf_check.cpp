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

std::string CheckUrdf(const std::string& xml, const f3r_model& model, const FrameNames* given,
                      double tol) {
  urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(xml);
  if (!urdf) return "robot_description is not a valid URDF";
  const f3r_geometry g = f3r_model_geometry(&model);
  for (int i = 0; i < 3; ++i) {
    const std::string n = std::to_string(i + 1);
    const auto revolute = urdf->getJoint("leg_" + n + "_revolute");
    const auto prismatic = urdf->getJoint("leg_" + n + "_prismatic");
    const auto tip = urdf->getJoint("leg_" + n + "_tip_nominal_joint");
    const auto pc = urdf->getJoint("platform_c" + n + "_joint");
    if (!revolute || !prismatic || !tip || !pc)
      return "robot_description lacks joint leg_" + n + "_revolute, leg_" + n + "_prismatic, leg_" +
             n + "_tip_nominal_joint or platform_c" + n + "_joint (nodes/make_urdf.py writes them)";
    const auto& a = revolute->parent_to_joint_origin_transform.position;
    if (std::fabs(a.x - g.base_joint[i][0]) > tol)
      return Mismatch(revolute->name, "origin x (A_i)", a.x, g.base_joint[i][0]);
    if (std::fabs(a.y - g.base_joint[i][1]) > tol)
      return Mismatch(revolute->name, "origin y (A_i)", a.y, g.base_joint[i][1]);
    if (!prismatic->limits)
      return "robot_description: joint " + prismatic->name + " has no limit (the scene's stroke)";
    if (std::fabs(prismatic->limits->lower - g.stroke_min) > tol)
      return Mismatch(prismatic->name, "lower limit (geometry.stroke_min)",
                      prismatic->limits->lower, g.stroke_min);
    if (std::fabs(prismatic->limits->upper - g.stroke_max) > tol)
      return Mismatch(prismatic->name, "upper limit (geometry.stroke_max)",
                      prismatic->limits->upper, g.stroke_max);
    const double l = tip->parent_to_joint_origin_transform.position.x;
    if (std::fabs(l - g.link_length) > tol)
      return Mismatch(tip->name, "origin x (link length l)", l, g.link_length);
    const auto& c = pc->parent_to_joint_origin_transform.position;
    const double r = std::hypot(c.x, c.y);
    if (std::fabs(r - g.platform_radius) > tol)
      return Mismatch(pc->name, "distance from the platform centre (r_PC)", r, g.platform_radius);
  }
  // Every frame the node publishes is a link of the URDF, so that RobotModel shows all of it:
  // the names carry ~tf_prefix, and the beam stations ~beam_points.
  if (!given) return "";
  const FrameNames& frames = *given;
  std::vector<std::string> names = {frames.base, frames.platform};
  for (int i = 0; i < 3; ++i) {
    for (const auto* f :
         {&frames.cylinder[i], &frames.piston[i], &frames.tip_nominal[i], &frames.platform_c[i]})
      names.push_back(*f);
    for (const auto& b : frames.beam[i]) names.push_back(b);
  }
  for (const auto& name : names)
    if (!urdf->getLink(name))
      return "robot_description lacks link " + name +
             " (generate it for this node's ~tf_prefix and ~beam_points: nodes/make_urdf.py "
             "--prefix "
             "--beam-points, as sim.launch does)";
  const std::string points = std::to_string(frames.beam[0].size());
  const std::string extra =
      frames.beam[0][0].substr(0, frames.beam[0][0].size() - 1) + points;  // station N
  if (urdf->getLink(extra))
    return "robot_description has more beam stations than ~beam_points = " + points + " (link " +
           extra + ")";
  return "";
}

}  // namespace flex3rpr
