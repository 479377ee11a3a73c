#include "command_inputs.hpp"

namespace flex3rpr {

CommandInputs::CommandInputs(ros::NodeHandle& pnh, const f3r_model& model,
                             const NodeParams& params, const double* phi_p)
    : model_(model), params_(params), phi_p_(phi_p) {
  for (auto& h : held_) h.assign(static_cast<size_t>(model.nq), 0.0);
  scratch_.assign(static_cast<size_t>(model.nq), 0.0);
  total_.assign(static_cast<size_t>(model.nq), 0.0);
  // Deep queues (~command_queue_size, 1000 by default): a controller at 10 kHz must not lose
  // commands (a lost invalid one would also go uncounted) while the node is descheduled.
  const uint32_t kCommandQueue = static_cast<uint32_t>(params.command_queue_size);
  command_sub_ = pnh.subscribe<EffortCommand>("command", kCommandQueue, [this](const EffortCommand::ConstPtr& m) {
    Accept(kCommand, DecodeEffortCommand(*m, model_, params_.limits, &scratch_), scratch_, "~command");
  });
  group_sub_ = pnh.subscribe<std_msgs::Float64MultiArray>(
      "effort_group/command", kCommandQueue, [this](const std_msgs::Float64MultiArray::ConstPtr& m) {
        Accept(kEffortGroup, DecodeEffortGroup(*m, model_, params_.limits, &scratch_), scratch_,
               "~effort_group/command");
      });
  wrench_sub_ = pnh.subscribe<geometry_msgs::WrenchStamped>(
      "platform_wrench", kCommandQueue, [this](const geometry_msgs::WrenchStamped::ConstPtr& m) {
        Accept(kWrench,
               DecodeWrench(*m, params_.world_frame, "platform", *phi_p_, params_.limits, model_,
                            &scratch_),
               scratch_, "~platform_wrench");
      });
}

void CommandInputs::Accept(Source source, const std::string& why,
                           const std::vector<double>& forces, const char* topic) {
  if (!why.empty()) {
    ++rejected_;
    ROS_WARN_THROTTLE(1.0, "flex3rpr_node: rejected a command on %s: %s; the simulation runs on "
                           "unchanged", topic, why.c_str());
    return;
  }
  held_[source] = forces;
  fresh_[source] = true;
  active_[source] = true;
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
  for (auto& h : held_) std::fill(h.begin(), h.end(), 0.0);
  fresh_.fill(false);
  active_.fill(false);
}

}  // namespace flex3rpr
