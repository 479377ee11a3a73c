#include "state_outputs.hpp"

#include "master_probe.hpp"

#include "flex3rpr/output_columns.h"

#include <tf2_eigen/tf2_eigen.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace flex3rpr {

namespace {

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
    : model_(model), params_(params), frames_(params.frames) {
  Advertise(nh, pnh);
  PrepareMessages();
  // ~state's outputs: the CSV's columns (flex3rpr/output_columns.h), named once by a parameter
  std::vector<std::string> columns(static_cast<size_t>(f3r_output_columns(&model)));
  for (size_t k = 0; k < columns.size(); ++k) {
    char name[F3R_OUTPUT_NAME];
    f3r_output_column_name(&model, static_cast<int>(k), name);
    columns[k] = name;
  }
  pnh.setParam("output_columns", columns);
  state_.outputs.assign(columns.size(), 0.0);
  SendStaticFrames();
  PrepareTransforms();
}

void StateOutputs::Advertise(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  // Each subscriber connection holds up to queue_size messages the node's network thread has not
  // sent yet; a recorder that must not lose any (record.launch) asks for a deep queue.
  const uint32_t q = static_cast<uint32_t>(params_.queue_size);
  // In lockstep the node waits for a controller that may connect later: the present state is
  // latched, so that it gets it on connection instead of waiting for a period that never comes.
  const bool latch = params_.lockstep;
  joints_pub_ = nh.advertise<sensor_msgs::JointState>("joint_states", q, latch);
  odom_pub_ = pnh.advertise<nav_msgs::Odometry>("odom", q, latch);
  status_pub_ = pnh.advertise<SimStatus>("status", q, latch);
  beam_pub_ = pnh.advertise<BeamState>("beam_state", q, latch);
  state_pub_ = pnh.advertise<FullState>("state", q, latch);
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("beams", q);
  diagnostics_pub_ = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  // A listener that connects while paused (rviz started later) gets the present frames at once.
  // Not while running: the next period brings them, and the connection may already have had
  // the last one (TF_REPEATED_DATA).
  tf_pub_ = nh.advertise<tf2_msgs::TFMessage>(
      "/tf", std::max(q, 100u),  // TransformBroadcaster's 100 at least
      [this](const ros::SingleSubscriberPublisher& subscriber) {
        if (have_transforms_ && still_) subscriber.publish(tf_);
      });
  if (params_.publish_clock) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", q);
}

void StateOutputs::PrepareMessages() {
  for (int i = 0; i < 3; ++i) {
    joints_.name.push_back(Leg(i, "_revolute"));
    joints_.name.push_back(Leg(i, "_prismatic"));
  }
  joints_.position.assign(6, 0.0);
  joints_.velocity.assign(6, 0.0);
  joints_.effort.assign(6, 0.0);
  odom_.header.frame_id = frames_.base;
  odom_.child_frame_id = frames_.platform;

  const int nmodal = f3r_model_nq(&model_) - F3R_Q_MODAL;
  for (int i = 0; i < 3; ++i) {
    beam_.model[i] = f3r_link_model_name(f3r_model_link(&model_, i)->model);
    beam_.modes[i] = static_cast<uint32_t>(f3r_model_link(&model_, i)->modes);
  }
  beam_.modal.assign(static_cast<size_t>(nmodal), 0.0);
  beam_.modal_rate.assign(static_cast<size_t>(nmodal), 0.0);
  state_.modal.assign(static_cast<size_t>(nmodal), 0.0);
  state_.modal_rate.assign(static_cast<size_t>(nmodal), 0.0);

  for (int i = 0; i < 3; ++i) {
    visualization_msgs::Marker m;
    m.header.frame_id = frames_.base;
    m.ns = "beams";
    m.id = i;
    m.type = visualization_msgs::Marker::LINE_STRIP;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = 0.008;
    m.color.r = 1.0f;
    m.color.g = 0.5f;
    m.color.a = 1.0f;
    m.points.resize(static_cast<size_t>(params_.beam_points));
    markers_.markers.push_back(m);
  }

  diagnostics_.status.resize(1);
  diagnostics_.status[0].name = ros::this_node::getName() + ": simulation";
  diagnostics_.status[0].hardware_id = "flex3rpr";
}

// Static frames, as the URDF's fixed joints (nodes/make_urdf.py): world -> base, the nominal
// beam tips, the beams' clamped roots (station 0 is the piston, whatever the deflection) and
// the platform joints.
void StateOutputs::SendStaticFrames() {
  const f3r_geometry g = f3r_model_geometry(&model_);
  std::vector<geometry_msgs::TransformStamped> statics;
  if (frames_.base != frames_.world) {
    auto base = Frame(frames_.world, frames_.base);  // ~base_pose
    SetPlanar(&base, params_.base_pose[0], params_.base_pose[1], params_.base_pose[2]);
    statics.push_back(base);
  }
  for (int i = 0; i < 3; ++i) {
    auto tip = Frame(frames_.piston[i], frames_.tip_nominal[i]);
    tip.transform.translation.x = g.link_length;
    statics.push_back(tip);
    statics.push_back(Frame(frames_.piston[i], frames_.beam[i][0]));
    auto c = Frame(frames_.platform, frames_.platform_c[i]);
    c.transform.translation.x = g.platform_radius * std::cos(g.platform_angle[i]);
    c.transform.translation.y = g.platform_radius * std::sin(g.platform_angle[i]);
    statics.push_back(c);
  }
  for (auto& s : statics) s.header.stamp = ros::Time(0.0);
  static_tf_.sendTransform(statics);
}

// Dynamic frames, all in the base frame but the legs' chain: 2 per leg, the platform, and the
// beam stations 1..N-1.
void StateOutputs::PrepareTransforms() {
  for (int i = 0; i < 3; ++i) {
    tf_.transforms.push_back(Frame(frames_.base, frames_.cylinder[i]));
    tf_.transforms.push_back(Frame(frames_.cylinder[i], frames_.piston[i]));
  }
  tf_.transforms.push_back(Frame(frames_.base, frames_.platform));
  for (int i = 0; i < 3; ++i)
    for (int k = 1; k < params_.beam_points; ++k)
      tf_.transforms.push_back(Frame(frames_.base, frames_.beam[i][k]));
}

void StateOutputs::FillTransforms(const f3r_outputs& out, const ros::Time& stamp) {
  const double* q = out.q;
  const f3r_geometry g = f3r_model_geometry(&model_);
  size_t n = 0;
  for (int i = 0; i < 3; ++i) {
    SetPlanar(&tf_.transforms[n++], g.base_joint[i][0], g.base_joint[i][1], q[F3R_Q_THETA + i]);
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
      if (k > 0) SetPlanar(&tf_.transforms[n++], pos[0], pos[1], angle);  // station 0 is static
      // The marker may exaggerate the deflection; the physics and TF never do.
      auto& pt = marker.points[static_cast<size_t>(k)];
      pt.x = pos[0] - (exaggeration - 1.0) * w * s;
      pt.y = pos[1] + (exaggeration - 1.0) * w * c;
      pt.z = 0.0;
    }
  }
  for (auto& t : tf_.transforms) t.header.stamp = stamp;
  have_transforms_ = true;
}

void StateOutputs::PublishState(const f3r_outputs& out, const ros::Time& stamp) {
  if (clock_pub_) {
    clock_.clock = ros::Time(out.t);
    clock_pub_.publish(clock_);
  }
  joints_.header.stamp = stamp;
  for (int i = 0; i < 3; ++i) {
    joints_.position[2 * i] = out.q[F3R_Q_THETA + i];
    joints_.velocity[2 * i] = out.v[F3R_Q_THETA + i];
    joints_.effort[2 * i] = out.actuator[3 + i];  // the actuators' efforts, as ros_control's
    joints_.position[2 * i + 1] = out.q[F3R_Q_RHO + i];
    joints_.velocity[2 * i + 1] = out.v[F3R_Q_RHO + i];
    joints_.effort[2 * i + 1] = out.actuator[i];
  }
  joints_pub_.publish(joints_);

  // nav_msgs convention: the pose in header.frame_id, the twist in child_frame_id (the platform).
  const double phi = out.q[F3R_Q_PHI], c = std::cos(phi), s = std::sin(phi);
  const double vx = out.v[F3R_Q_X], vy = out.v[F3R_Q_Y];
  odom_.header.stamp = stamp;
  odom_.pose.pose.position.x = out.q[F3R_Q_X];
  odom_.pose.pose.position.y = out.q[F3R_Q_Y];
  odom_.pose.pose.orientation.z = std::sin(phi / 2);
  odom_.pose.pose.orientation.w = std::cos(phi / 2);
  odom_.twist.twist.linear.x = c * vx + s * vy;
  odom_.twist.twist.linear.y = -s * vx + c * vy;
  odom_.twist.twist.angular.z = out.v[F3R_Q_PHI];
  odom_pub_.publish(odom_);

  for (auto& marker : markers_.markers) marker.header.stamp = stamp;
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

  // ~state: the same numbers, one message
  state_.header.stamp = stamp;
  state_.sim_time = out.t;
  state_.joint_state = joints_;
  for (size_t k = 0; k < 3; ++k) {
    state_.platform_pose[k] = out.q[F3R_Q_X + k];
    state_.platform_twist[k] = out.v[F3R_Q_X + k];
    state_.tip_deflection[k] = out.tip_deflection[k];
    state_.tip_deflection_rate[k] = out.tip_deflection_rate[k];
  }
  state_.modal = beam_.modal;
  state_.modal_rate = beam_.modal_rate;
  for (size_t c = 0; c < 6; ++c) state_.loop_force[c] = out.lambda[c];
  for (size_t i = 0; i < 3; ++i) state_.stop_force[i] = out.stop_force[i];
  f3r_output_row(&model_, &out, state_.outputs.data());
  state_pub_.publish(state_);
}

void StateOutputs::Publish(const f3r_outputs& out, const RunInfo& info) {
  still_ = info.paused;
  const ros::Time stamp = Stamp(out.t);
  state_stamp_ = stamp;
  FillTransforms(out, stamp);
  PublishState(out, stamp);
  tf_pub_.publish(tf_);
  ++published_states_;
  largest_energy_ = std::max(largest_energy_, out.kinetic_energy + out.potential_energy);
  energy_guard_ =
      energy_guard_ || f3r_energy_guard_tripped(out.energy_balance_error, largest_energy_);
  PublishStatus(out, info);
}

void StateOutputs::PublishPaused(const f3r_outputs& out, const RunInfo& info) {
  still_ = true;
  const ros::Time stamp = Stamp(out.t);
  if (!params_.sim_stamps) {
    FillTransforms(out, stamp);
    tf_pub_.publish(tf_);
  }
  PublishState(out, stamp);
  PublishStatus(out, info);
}

void StateOutputs::Republish(const f3r_outputs& out, const RunInfo& info) {
  const ros::Time stamp = Stamp(out.t);
  if (!params_.sim_stamps) {  // a simulated stamp repeated on /tf is TF_REPEATED_DATA
    FillTransforms(out, stamp);
    tf_pub_.publish(tf_);
  }
  PublishState(out, stamp);
  PublishStatus(out, info);
}

void StateOutputs::PublishDiagnostics(const f3r_outputs& out, const RunInfo& info) {
  diagnostic_msgs::DiagnosticStatus& d = diagnostics_.status[0];
  std::string outside;
  for (int i = 0; i < 3; ++i)
    if (info.outside_stroke[static_cast<size_t>(i)])
      outside += (outside.empty() ? "" : ", ") + Leg(i, "");
  if (!info.last_error.empty()) {
    d.level = diagnostic_msgs::DiagnosticStatus::ERROR;
    d.message = "integration stopped: " + info.last_error;
  } else if (info.waiting_for_command > 0.0) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    char text[160];
    std::snprintf(text, sizeof text, "lockstep: no command for the period at t = %.6g s for %.1f s",
                  out.t, info.waiting_for_command);
    d.message = text;
  } else if (energy_guard_) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    char text[200];
    std::snprintf(text, sizeof text,
                  "energy balance error past %g of the largest T + V (now %.3g J of %.3g J): the "
                  "integrator has likely gone unstable; the path is suspect",
                  F3R_ENERGY_GUARD, out.energy_balance_error, largest_energy_);
    d.message = text;
  } else if (info.verifying && !info.request_met) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    char text[400];
    if (info.measurement_note.empty())
      std::snprintf(text, sizeof text,
                    "accuracy request %g m not met: measured %.3g m (latched until ~reset)",
                    params_.accuracy.request, info.measured_error);
    else
      std::snprintf(text, sizeof text, "accuracy not measured: %s", info.measurement_note.c_str());
    d.message = text;
  } else if (info.behind || !outside.empty()) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    d.message =
        info.behind ? "behind the requested real-time factor" : outside + " outside the stroke";
  } else {
    d.level = diagnostic_msgs::DiagnosticStatus::OK;
    d.message = info.paused ? "paused" : "running";
  }
  auto value = [](const char* key, double v) {
    diagnostic_msgs::KeyValue kv;
    kv.key = key;
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);
    kv.value = text;
    return kv;
  };
  diagnostic_msgs::KeyValue choice;
  choice.key = "accuracy_choice";
  choice.value = params_.accuracy.brief;
  d.values = {value("sim_time", out.t),
              value("realtime_factor", info.realtime_factor),
              value("requested_realtime_factor", info.requested_realtime_factor),
              value("steps", static_cast<double>(out.stats.steps)),
              value("constraint_residual", out.constraint_residual),
              value("energy_balance_error", out.energy_balance_error),
              value("rejected_commands", static_cast<double>(info.rejected_commands))};
  if (!choice.value.empty()) {
    d.values.push_back(choice);
    d.values.push_back(value("estimated_error", params_.accuracy.estimated_error));
    diagnostic_msgs::KeyValue basis;
    basis.key = "error_basis";
    basis.value = params_.accuracy.request <= 0.0 ? "" : info.verifying ? "measured" : "estimated";
    d.values.push_back(basis);
    if (info.verifying) {
      d.values.push_back(value("measured_error_m", info.measured_error));
      diagnostic_msgs::KeyValue met;
      met.key = "request_met";
      met.value = info.request_met ? "true" : "false";
      d.values.push_back(met);
    }
  }
  diagnostics_.header.stamp = Stamp(out.t);
  diagnostics_pub_.publish(diagnostics_);
}

bool StateOutputs::SubscribersConnected(int n) const {
  // Subscribers the master knows of and that answer, per topic (master_probe.hpp): one left by
  // a killed process would never connect.
  std::map<std::string, int> registered = AnsweringSubscribers();
  for (const ros::Publisher* p :
       {&joints_pub_, &odom_pub_, &status_pub_, &beam_pub_, &markers_pub_, &tf_pub_, &clock_pub_}) {
    if (!*p) continue;  // no /clock without simulated time
    const int need = std::max(n, registered[p->getTopic()]);
    if (static_cast<int>(p->getNumSubscribers()) < need) return false;
  }
  return true;
}

void StateOutputs::PublishStatus(const f3r_outputs& out, const RunInfo& info) {
  status_.accuracy_choice = params_.accuracy.brief;
  status_.estimated_error = params_.accuracy.estimated_error;
  // the node runs what the knob chose and cannot run a richer check ahead of itself
  status_.error_basis = params_.accuracy.request <= 0.0 ? ""
                        : info.verifying                ? "measured"
                                                        : "estimated";
  status_.measured_error_m = info.verifying ? info.measured_error : 0.0;
  status_.request_met = info.verifying ? info.request_met : params_.accuracy.request_met != 0;
  status_.measurement_note = info.measurement_note;
  status_.measurement_pending = info.measurement_pending;
  status_.energy_guard = energy_guard_;
  status_.header.stamp = Stamp(out.t);
  status_.sim_time = out.t;
  status_.wall_time = info.wall_time;
  status_.realtime_factor = info.realtime_factor;
  status_.requested_realtime_factor = info.requested_realtime_factor;
  status_.behind = info.behind;
  status_.lag = info.lag;
  status_.resyncs = info.resyncs;
  for (int i = 0; i < 3; ++i)
    status_.outside_stroke[static_cast<size_t>(i)] = info.outside_stroke[static_cast<size_t>(i)];
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
  for (size_t i = 0; i < 3; ++i) {
    status_.stop_locked[i] = static_cast<int8_t>(out.stop_locked[i]);
    status_.stop_force[i] = out.stop_force[i];
  }
  status_.impacts = static_cast<uint64_t>(out.impacts);
  status_.waiting_for_command = info.waiting_for_command;
  for (int i = 0; i < 3; ++i) {  // joint_states' order: revolute, prismatic per leg
    status_.joint_passive_effort[static_cast<size_t>(2 * i)] = out.passive[3 + i];
    status_.joint_passive_effort[static_cast<size_t>(2 * i + 1)] = out.passive[i];
  }
  status_.published_states = published_states_;
  status_.last_error = info.last_error;
  status_pub_.publish(status_);
}

}  // namespace flex3rpr
