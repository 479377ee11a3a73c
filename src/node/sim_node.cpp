#include "sim_node.hpp"

#include <algorithm>
#include <cmath>

#include <ros/package.h>

#include <fstream>
#include <sstream>

#include "urdf_check.hpp"

namespace flex3rpr {

SimNode::SimNode(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh) {}

static bool ReadFile(const std::string& path, std::string* text) {
  std::ifstream in(path);
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  *text = ss.str();
  return true;
}

bool SimNode::Init() {
  std::string error;
  if (!LoadParams(pnh_, &params_, &error)) {
    ROS_ERROR("flex3rpr_node: %s", error.c_str());
    return false;
  }
  f3r_model* model = nullptr;
  f3r_error err{};
  if (f3r_model_create(&params_.scene, &model, &err) != F3R_OK) {
    ROS_ERROR("flex3rpr_node: %s: %s", params_.scene_path.c_str(), err.message);
    return false;
  }
  model_.reset(model);
  std::string urdf;
  if (!nh_.getParam("robot_description", urdf)) {
    const std::string path = ros::package::getPath("flex3rpr") + "/urdf/flex3rpr.urdf";
    if (!ReadFile(path, &urdf)) {
      ROS_ERROR("flex3rpr_node: no robot_description parameter and cannot read %s", path.c_str());
      return false;
    }
    ROS_INFO("flex3rpr_node: no robot_description parameter; checking the geometry against %s",
             path.c_str());
  }
  const std::string mismatch = CheckUrdfGeometry(urdf, *model_);
  if (!mismatch.empty()) {
    ROS_ERROR("flex3rpr_node: %s", mismatch.c_str());
    return false;
  }
  f3r_sim* sim = nullptr;
  if (f3r_sim_create(model_.get(), &params_.settings, &sim, &err) != F3R_OK) {
    ROS_ERROR("flex3rpr_node: %s", err.message);
    return false;
  }
  sim_.reset(sim);
  inputs_.reset(new CommandInputs(pnh_, *model_, params_, &phi_p_));
  outputs_.reset(new StateOutputs(nh_, pnh_, *model_, params_));
  services_.reset(new Services(pnh_, &control_));
  ROS_INFO("flex3rpr_node: scene %s, nq %d, %s, rtol %g, publishing at %g Hz of simulated time, "
           "real-time factor %g",
           params_.scene_path.c_str(), model_->nq,
           params_.settings.formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
           params_.settings.rtol, params_.publish_rate, params_.realtime_factor);
  return true;
}

// Paced runs only: how far the simulation lags its schedule (paced_sim simulated seconds since
// pace_wall), into ~status, and a throttled warning with the achieved factor while it is late.
void SimNode::ReportLag(const ros::WallTime& now, const ros::WallTime& pace_wall, double paced_sim) {
  info_.lag = 0.0;
  info_.behind = false;
  if (params_.realtime_factor <= 0.0 || control_.paused) return;
  const ros::WallTime due = pace_wall + ros::WallDuration(paced_sim / params_.realtime_factor);
  info_.lag = std::max(0.0, (now - due).toSec());
  info_.behind = info_.lag > kBehindSeconds;
  if (info_.behind)
    ROS_WARN_THROTTLE(5.0,
                      "flex3rpr_node: behind the wall clock by %.2f s: achieved real-time factor %.3g of "
                      "the requested %g (a looser solver.rtol, fewer modes or a lower ~realtime_factor "
                      "would keep up)",
                      info_.lag, info_.realtime_factor, params_.realtime_factor);
}

// Handles callbacks for `seconds` of wall time; returns the wall time that passed.
static ros::WallDuration SpinFor(double seconds) {
  const ros::WallTime from = ros::WallTime::now();
  while (ros::ok() && (ros::WallTime::now() - from).toSec() < seconds) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  return ros::WallTime::now() - from;
}

bool SimNode::Step(double period) {
  f3r_error err{};
  const double t = f3r_sim_time(sim_.get());
  const std::vector<double>& forces = inputs_->Total(t);
  if (f3r_sim_set_forces(sim_.get(), forces.data(), &err) != F3R_OK) {
    info_.last_error = err.message;
    ROS_WARN_THROTTLE(1.0, "flex3rpr_node: forces not applied: %s", err.message);
  }
  ++periods_;
  if (f3r_sim_advance(sim_.get(), periods_ * period, &err) != F3R_OK) {
    info_.last_error = err.message;
    ROS_ERROR("flex3rpr_node: integration stopped at t = %.6g s: %s; paused at the last good state "
              "(~reset starts over, ~resume tries again)",
              f3r_sim_time(sim_.get()), err.message);
    periods_ = static_cast<long>(std::floor(f3r_sim_time(sim_.get()) / period + 1e-9));  // stay on the grid
    return false;
  }
  return true;
}

int SimNode::Run() {
  const double period = 1.0 / params_.publish_rate;
  if (params_.wait_for_subscribers > 0) {  // e.g. a recorder: nothing may be published before it listens
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(params_.subscriber_timeout);
    while (ros::ok() && !outputs_->SubscribersConnected(params_.wait_for_subscribers)) {
      if (ros::WallTime::now() > until) {
        ROS_ERROR("flex3rpr_node: ~wait_for_subscribers: an output topic lacks subscribers (%d, or those the "
                  "master lists) after %g s",
                  params_.wait_for_subscribers, params_.subscriber_timeout);
        return 3;
      }
      ros::spinOnce();
      ros::WallDuration(0.02).sleep();
    }
    ROS_INFO("flex3rpr_node: every output topic has its subscribers (at least %d); starting",
             params_.wait_for_subscribers);
  }
  // A subscriber on simulated time, such as rosbag record, takes its first messages only once
  // /clock is past zero (ros::Time::waitForValid), and its subscription queues hold 100 each:
  // after the first period, and before it exits, the node holds ~subscriber_grace wall seconds.
  const bool grace = params_.wait_for_subscribers > 0 && params_.subscriber_grace > 0.0;
  bool grace_pending = grace;
  ros::WallTime start = ros::WallTime::now();
  ros::WallTime pace_wall = start;  // pacing restarts after a pause or a reset
  double pace_sim = 0.0;
  bool was_running = true;
  ros::WallTime window_wall = start;
  ros::WallTime last_status = start;
  double window_sim = 0.0;
  outputs_->Publish(*f3r_sim_outputs(sim_.get()), info_);
  int exit_code = 0;
  while (ros::ok()) {
    ros::spinOnce();
    if (control_.reset_requested) {
      f3r_error err{};
      control_.reset_requested = false;
      inputs_->Clear();
      if (f3r_sim_reset(sim_.get(), &err) != F3R_OK) ROS_ERROR("flex3rpr_node: reset failed: %s", err.message);
      periods_ = 0;
      was_running = false;
      window_sim = 0.0;
      info_.last_error.clear();
      outputs_->RestartCount();
      outputs_->Publish(*f3r_sim_outputs(sim_.get()), info_);
    }
    const bool run = !control_.paused || control_.pending_steps > 0;
    info_.paused = control_.paused;
    if (!run) {
      was_running = false;
      const ros::WallTime now = ros::WallTime::now();
      if ((now - last_status).toSec() >= 0.1) {
        info_.rejected_commands = inputs_->rejected();
        outputs_->PublishStatus(*f3r_sim_outputs(sim_.get()), info_);
        last_status = now;
      }
      ros::WallDuration(0.001).sleep();
      continue;
    }
    if (control_.pending_steps > 0) --control_.pending_steps;
    if (!was_running) {
      pace_wall = ros::WallTime::now();
      pace_sim = f3r_sim_time(sim_.get());
    }
    was_running = !control_.paused;
    if (!Step(period)) {  // the node outlives its physics: it pauses and keeps serving
      if (params_.duration > 0.0) {  // a scripted run (a recording) ends instead of waiting
        exit_code = 2;
        outputs_->Publish(*f3r_sim_outputs(sim_.get()), info_);
        break;
      }
      control_.paused = true;
      control_.pending_steps = 0;
      info_.paused = true;
      was_running = false;
      info_.rejected_commands = inputs_->rejected();
      outputs_->Publish(*f3r_sim_outputs(sim_.get()), info_);
      continue;
    }
    const f3r_outputs& out = *f3r_sim_outputs(sim_.get());
    phi_p_ = out.q[F3R_Q_PHI];
    ros::WallTime now = ros::WallTime::now();
    info_.wall_time = (now - start).toSec();
    const double window = (now - window_wall).toSec();
    if (window >= 0.5) {  // achieved real-time factor over the last half second of wall time
      info_.realtime_factor = (out.t - window_sim) / window;
      window_wall = now;
      window_sim = out.t;
    } else if (info_.realtime_factor == 0.0 && info_.wall_time > 0.0) {
      info_.realtime_factor = out.t / info_.wall_time;
    }
    info_.rejected_commands = inputs_->rejected();
    info_.requested_realtime_factor = params_.realtime_factor;
    ReportLag(now, pace_wall, out.t - pace_sim);
    outputs_->Publish(out, info_);
    if (grace_pending) {
      grace_pending = false;
      const ros::WallDuration held = SpinFor(params_.subscriber_grace);  // not the simulation's time
      start += held;
      window_wall += held;
      pace_wall += held;
      last_status += held;
      now += held;
    }
    if (params_.duration > 0.0 && out.t >= params_.duration - 0.5 * period) {
      ROS_INFO("flex3rpr_node: reached the duration %g s (real-time factor %.3g)", out.t,
               out.t / info_.wall_time);
      break;
    }
    if (params_.realtime_factor > 0.0 && !control_.paused) {  // pace to the wall clock
      const ros::WallTime due =
          pace_wall + ros::WallDuration((out.t - pace_sim) / params_.realtime_factor);
      if (due > now) (due - now).sleep();
    }
  }
  if (grace) SpinFor(params_.subscriber_grace);  // the subscribers take the last messages
  return exit_code;
}

}  // namespace flex3rpr
