#include "state_outputs.hpp"

#include <tf2_eigen/tf2_eigen.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

namespace flex3rpr {

namespace {

const char* ModelName(f3r_link_model m) {
  switch (m) {
    case F3R_LINK_RIGID: return "rigid";
    case F3R_LINK_FIXED_PINNED: return "fixed_pinned";
    case F3R_LINK_FIXED_FREE: return "fixed_free";
  }
  return "unknown";
}

// A planar pose (x, y, yaw about +Z) as a TF transform.
void SetPlanar(geometry_msgs::TransformStamped* t, double x, double y, double yaw) {
  const Eigen::Isometry3d pose =
      Eigen::Translation3d(x, y, 0.0) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  t->transform = tf2::eigenToTransform(pose).transform;
}

geometry_msgs::TransformStamped Frame(const std::string& parent, const std::string& child) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.rotation.w = 1.0;
  return t;
}

std::string Leg(int i, const char* suffix) { return "leg_" + std::to_string(i + 1) + suffix; }

}  // namespace

StateOutputs::StateOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, const f3r_model& model,
                           const NodeParams& params)
    : model_(model), params_(params) {
  // Each subscriber connection holds up to queue_size messages the node's network thread has not
  // sent yet; a recorder that must not lose any (record.launch) asks for a deep queue.
  const uint32_t q = static_cast<uint32_t>(params.queue_size);
  joints_pub_ = nh.advertise<sensor_msgs::JointState>("joint_states", q);
  status_pub_ = pnh.advertise<SimStatus>("status", q);
  beam_pub_ = pnh.advertise<BeamState>("beam_state", q);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("beams", q);
  tf_pub_ = nh.advertise<tf2_msgs::TFMessage>("/tf", std::max(q, 100u));  // TransformBroadcaster's 100 at least
  nh.param("/use_sim_time", publish_clock_, false);
  if (publish_clock_) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", q);

  for (int i = 0; i < 3; ++i) {
    joints_.name.push_back(Leg(i, "_revolute"));
    joints_.name.push_back(Leg(i, "_prismatic"));
  }
  joints_.position.assign(6, 0.0);
  joints_.velocity.assign(6, 0.0);
  joints_.effort.assign(6, 0.0);

  const int nmodal = model.nq - F3R_Q_MODAL;
  for (int i = 0; i < 3; ++i) {
    beam_.model[i] = ModelName(model.link[i].model);
    beam_.modes[i] = static_cast<uint32_t>(model.link[i].modes);
  }
  beam_.modal.assign(static_cast<size_t>(nmodal), 0.0);
  beam_.modal_rate.assign(static_cast<size_t>(nmodal), 0.0);

  const float colours[3][3] = {{1.0f, 0.5f, 0.0f}, {1.0f, 0.5f, 0.0f}, {1.0f, 0.5f, 0.0f}};
  for (int i = 0; i < 3; ++i) {
    visualization_msgs::Marker m;
    m.header.frame_id = params.world_frame;
    m.ns = "beams";
    m.id = i;
    m.type = visualization_msgs::Marker::LINE_STRIP;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = 0.008;
    m.color.r = colours[i][0];
    m.color.g = colours[i][1];
    m.color.b = colours[i][2];
    m.color.a = 1.0f;
    m.points.resize(static_cast<size_t>(params.beam_points));
    markers_.markers.push_back(m);
  }

  // Static frames: world -> base, the nominal beam tips and the platform joints.
  std::vector<geometry_msgs::TransformStamped> statics;
  if (params.base_frame != params.world_frame) statics.push_back(Frame(params.world_frame, params.base_frame));
  for (int i = 0; i < 3; ++i) {
    auto tip = Frame(Leg(i, "_piston"), Leg(i, "_tip_nominal"));
    tip.transform.translation.x = model.link_length;
    statics.push_back(tip);
    auto c = Frame("platform", "platform_c" + std::to_string(i + 1));
    c.transform.translation.x = model.platform_radius * std::cos(model.platform_angle[i]);
    c.transform.translation.y = model.platform_radius * std::sin(model.platform_angle[i]);
    statics.push_back(c);
  }
  for (auto& s : statics) s.header.stamp = ros::Time(0.0);
  static_tf_.sendTransform(statics);

  // Dynamic frames: 2 per leg of the tree, the platform, and the beam stations.
  for (int i = 0; i < 3; ++i) {
    tf_.transforms.push_back(Frame(params.base_frame, Leg(i, "_cylinder")));
    tf_.transforms.push_back(Frame(Leg(i, "_cylinder"), Leg(i, "_piston")));
  }
  tf_.transforms.push_back(Frame(params.world_frame, "platform"));
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < params.beam_points; ++k)
      tf_.transforms.push_back(Frame(params.world_frame, Leg(i, "_beam_") + std::to_string(k)));
}

void StateOutputs::FillTransforms(const f3r_outputs& out, const ros::Time& stamp) {
  const double* q = out.q;
  size_t n = 0;
  for (int i = 0; i < 3; ++i) {
    SetPlanar(&tf_.transforms[n++], model_.base_joint[i][0], model_.base_joint[i][1], q[F3R_Q_THETA + i]);
    SetPlanar(&tf_.transforms[n++], q[F3R_Q_RHO + i], 0.0, 0.0);
  }
  SetPlanar(&tf_.transforms[n++], q[F3R_Q_X], q[F3R_Q_Y], q[F3R_Q_PHI]);
  const int points = params_.beam_points;
  const double exaggeration = params_.beam_marker_exaggeration;
  for (int i = 0; i < 3; ++i) {
    auto& marker = markers_.markers[static_cast<size_t>(i)];
    marker.header.stamp = stamp;
    const double c = std::cos(q[F3R_Q_THETA + i]), s = std::sin(q[F3R_Q_THETA + i]);
    for (int k = 0; k < points; ++k) {
      const double xi = static_cast<double>(k) / (points - 1);
      double pos[2], angle, w;
      f3r_model_beam_point(&model_, q, i, xi, pos, &angle, &w);
      SetPlanar(&tf_.transforms[n++], pos[0], pos[1], angle);
      // The marker may exaggerate the deflection; the physics and TF never do.
      auto& pt = marker.points[static_cast<size_t>(k)];
      pt.x = pos[0] - (exaggeration - 1.0) * w * s;
      pt.y = pos[1] + (exaggeration - 1.0) * w * c;
      pt.z = 0.0;
    }
  }
  for (auto& t : tf_.transforms) t.header.stamp = stamp;
}

void StateOutputs::Publish(const f3r_outputs& out, const RunInfo& info) {
  const ros::Time stamp(out.t);
  if (publish_clock_) {
    clock_.clock = stamp;
    clock_pub_.publish(clock_);
  }
  joints_.header.stamp = stamp;
  for (int i = 0; i < 3; ++i) {
    joints_.position[2 * i] = out.q[F3R_Q_THETA + i];
    joints_.velocity[2 * i] = out.v[F3R_Q_THETA + i];
    joints_.effort[2 * i] = out.forces[F3R_Q_THETA + i];
    joints_.position[2 * i + 1] = out.q[F3R_Q_RHO + i];
    joints_.velocity[2 * i + 1] = out.v[F3R_Q_RHO + i];
    joints_.effort[2 * i + 1] = out.forces[F3R_Q_RHO + i];
  }
  joints_pub_.publish(joints_);

  FillTransforms(out, stamp);
  tf_pub_.publish(tf_);
  markers_pub_.publish(markers_);

  beam_.header.stamp = stamp;
  for (size_t k = 0; k < beam_.modal.size(); ++k) {
    beam_.modal[k] = out.q[F3R_Q_MODAL + k];
    beam_.modal_rate[k] = out.v[F3R_Q_MODAL + k];
  }
  for (int i = 0; i < 3; ++i) {
    beam_.tip_deflection[i] = out.tip_deflection[i];
    beam_.tip_deflection_rate[i] = out.tip_deflection_rate[i];
  }
  beam_pub_.publish(beam_);
  ++published_states_;
  PublishStatus(out, info);
}

bool StateOutputs::SubscribersConnected(int n) const {
  // Subscribers the master knows of, per topic (getSystemState: [publishers, subscribers, services]).
  std::map<std::string, int> registered;
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (ros::master::execute("getSystemState", request, response, payload, false) && payload.size() > 1) {
    for (int i = 0; i < payload[1].size(); ++i)
      registered[static_cast<std::string>(payload[1][i][0])] = payload[1][i][1].size();
  }
  for (const ros::Publisher* p : {&joints_pub_, &status_pub_, &beam_pub_, &markers_pub_, &tf_pub_, &clock_pub_}) {
    if (!*p) continue;  // no /clock without simulated time
    const int need = std::max(n, registered[p->getTopic()]);
    if (static_cast<int>(p->getNumSubscribers()) < need) return false;
  }
  return true;
}

void StateOutputs::PublishStatus(const f3r_outputs& out, const RunInfo& info) {
  status_.header.stamp = ros::Time(out.t);
  status_.sim_time = out.t;
  status_.wall_time = info.wall_time;
  status_.realtime_factor = info.realtime_factor;
  status_.requested_realtime_factor = info.requested_realtime_factor;
  status_.behind = info.behind;
  status_.lag = info.lag;
  status_.paused = info.paused;
  status_.steps = static_cast<uint64_t>(out.stats.steps);
  status_.residual_evals = static_cast<uint64_t>(out.stats.residual_evals);
  status_.last_step = out.stats.last_step;
  status_.last_order = out.stats.last_order;
  status_.constraint_residual = out.constraint_residual;
  status_.actuation_condition = out.actuation_condition;
  status_.recoverable_errors = static_cast<uint64_t>(out.stats.recoverable_errors);
  status_.kinetic_energy = out.kinetic_energy;
  status_.potential_energy = out.potential_energy;
  status_.external_work = out.external_work;
  status_.energy_balance_error = out.energy_balance_error;
  status_.rejected_commands = info.rejected_commands;
  status_.published_states = published_states_;
  status_.last_error = info.last_error;
  status_pub_.publish(status_);
}

}  // namespace flex3rpr
