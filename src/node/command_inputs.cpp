#include "command_inputs.hpp"

#include <tf2_eigen/tf2_eigen.h>

#include <Eigen/Geometry>

namespace flex3rpr {

CommandInputs::CommandInputs(ros::NodeHandle& pnh, const f3r_model& model, const NodeParams& params,
                             const double* phi_p)
    : model_(model), params_(params), phi_p_(phi_p) {
  const size_t nq = static_cast<size_t>(f3r_model_nq(&model));
  for (auto& h : held_) h.assign(nq, 0.0);
  scratch_.assign(nq, 0.0);
  total_.assign(nq, 0.0);
  // Deep queues (~command_queue_size, 1000 by default): a controller at 10 kHz must not lose
  // commands (a lost invalid one would also go uncounted) while the node is descheduled.
  const uint32_t kCommandQueue = static_cast<uint32_t>(params.command_queue_size);
  // Control commands are small and frequent: Nagle's algorithm would hold them back.
  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  command_sub_ = pnh.subscribe<EffortCommand>(
      "command", kCommandQueue,
      [this](const EffortCommand::ConstPtr& m) {
        Accept(kCommand, DecodeEffortCommand(*m, model_, params_.scene, &scratch_), scratch_,
               "~command", m->header.stamp);
      },
      ros::VoidConstPtr(), hints);
  group_sub_ = pnh.subscribe<std_msgs::Float64MultiArray>(
      "effort_group/command", kCommandQueue,
      [this](const std_msgs::Float64MultiArray::ConstPtr& m) {
        Accept(kEffortGroup, DecodeEffortGroup(*m, model_, params_.scene, &scratch_), scratch_,
               "~effort_group/command", ros::Time());
      },
      ros::VoidConstPtr(), hints);
  wrench_sub_ = pnh.subscribe<geometry_msgs::WrenchStamped>(
      "platform_wrench", kCommandQueue,
      [this](const geometry_msgs::WrenchStamped::ConstPtr& m) {
        Rotation to_base;
        std::string why = ResolveFrame(m->header.frame_id, &to_base);
        if (why.empty()) why = DecodeWrench(*m, to_base, params_.scene, model_, &scratch_);
        Accept(kWrench, why, scratch_, "~platform_wrench", m->header.stamp);
      },
      ros::VoidConstPtr(), hints);
}

std::string CommandInputs::ResolveFrame(const std::string& frame, Rotation* to_base) {
  const FrameNames& f = params_.frames;
  if (frame.empty() || frame == f.base) {
    *to_base = YawRotation(0.0);
    return "";
  }
  if (frame == f.world) {  // world -> base is ~base_pose (state_outputs.cpp)
    *to_base = YawRotation(-params_.base_pose[2]);
    return "";
  }
  if (frame == f.platform) {
    *to_base = YawRotation(*phi_p_);
    return "";
  }
  if (!tf_buffer_) {  // the first wrench in another frame: listen to tf2 from now on
    tf_buffer_.reset(new tf2_ros::Buffer());
    tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_));  // its own spin thread
    // Give the listener a moment to hear /tf_static and /tf; in wall time, because simulated
    // time stands still while this loop waits. 0.5 s was too short on a loaded 2-core machine.
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(2.0);
    while (ros::WallTime::now() < until && !tf_buffer_->canTransform(f.base, frame, ros::Time(0)))
      ros::WallDuration(0.01).sleep();
  }
  std::string tf_error;
  if (!tf_buffer_->canTransform(f.base, frame, ros::Time(0), &tf_error))
    return "header.frame_id '" + frame + "' has no transform to '" + f.base + "' in tf2 (" +
           tf_error + ")";
  const Eigen::Matrix3d R =
      tf2::transformToEigen(tf_buffer_->lookupTransform(f.base, frame, ros::Time(0))).rotation();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) (*to_base)[static_cast<size_t>(3 * r + c)] = R(r, c);
  return "";
}

void CommandInputs::Accept(Source source, const std::string& why, const std::vector<double>& forces,
                           const char* topic, const ros::Time& stamp) {
  if (!why.empty()) {
    ++rejected_;
    ROS_WARN_THROTTLE(
        1.0,
        "flex3rpr_node: rejected a command on %s: %s; the simulation runs on "
        "unchanged%s",
        topic, why.c_str(),
        params_.lockstep ? " (in lockstep it takes its period with the commands held)" : "");
    if (params_.lockstep) queue_.push_back({source, false, {}, stamp});
    return;
  }
  if (params_.lockstep) {
    queue_.push_back({source, true, forces, stamp});
    return;
  }
  Hold(source, forces);
}

void CommandInputs::Hold(Source source, const std::vector<double>& forces) {
  held_[source] = forces;
  fresh_[source] = true;
  active_[source] = true;
}

bool CommandInputs::TakeOne(const ros::Time& state_stamp) {
  while (!queue_.empty()) {
    Queued next = std::move(queue_.front());
    queue_.pop_front();
    if (!next.stamp.isZero() && next.stamp < state_stamp) {
      ++discarded_;
      ROS_WARN_THROTTLE(1.0,
                        "flex3rpr_node: lockstep: discarded a command stamped %.9f, which answers "
                        "an earlier state than the one at %.9f (stale, or a duplicate answer)",
                        next.stamp.toSec(), state_stamp.toSec());
      continue;
    }
    if (next.valid) Hold(next.source, next.forces);
    last_taken_stamped_ = !next.stamp.isZero();
    return true;
  }
  return false;
}

int CommandInputs::publishers() const {
  return static_cast<int>(command_sub_.getNumPublishers() + group_sub_.getNumPublishers() +
                          wrench_sub_.getNumPublishers());
}

std::string CommandInputs::HoldCommand(const EffortCommand& command) {
  std::vector<double> forces(total_.size(), 0.0);
  const std::string why = DecodeEffortCommand(command, model_, params_.scene, &forces);
  if (why.empty()) Hold(kCommand, forces);
  return why;
}

const std::vector<double>& CommandInputs::Total(double t) {
  std::fill(total_.begin(), total_.end(), 0.0);
  for (int s = 0; s < kSources; ++s) {
    if (fresh_[s]) {
      since_[s] = t;
      fresh_[s] = false;
    }
    if (active_[s] && params_.command_timeout > 0.0 && t - since_[s] > params_.command_timeout) {
      active_[s] = false;
      ROS_WARN_THROTTLE(1.0, "flex3rpr_node: a command timed out after %g s; its forces are zero",
                        params_.command_timeout);
    }
    if (!active_[s]) continue;
    for (size_t n = 0; n < total_.size(); ++n) total_[n] += held_[s][n];
  }
  return total_;
}

void CommandInputs::Clear() {
  queue_.clear();
  last_taken_stamped_ = false;
  for (auto& h : held_) std::fill(h.begin(), h.end(), 0.0);
  fresh_.fill(false);
  active_.fill(false);
}

}  // namespace flex3rpr
