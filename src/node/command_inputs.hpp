// The three input topics, each holding its last valid command; their sum is the held force.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <array>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "command_decoding.hpp"
#include "params.hpp"

namespace flex3rpr {

class CommandInputs {
 public:
  // phi_p is read when a wrench arrives in the platform frame. Commands arrive with TCP_NODELAY.
  CommandInputs(ros::NodeHandle& pnh, const f3r_model& model, const NodeParams& params,
                const double* phi_p);

  // Sum of the held commands at simulated time t; a command older than the timeout drops out.
  const std::vector<double>& Total(double t);
  void Clear();
  uint64_t rejected() const { return rejected_; }

  // Lockstep (~lockstep): a message on any command topic is queued instead of taking effect, and
  // TakeOne applies the oldest, one per period, so that which command meets which period depends
  // on the controller's order alone, never on when the messages arrived. An invalid message
  // (counted in rejected()) takes its period too, leaving the held commands as they were.
  // A command whose header stamp is set answers the state of that stamp: one stamped before
  // state_stamp (the first publication of the state the period waits for) answers an earlier
  // state, or repeats an answer already taken, and is discarded (counted in discarded()).
  // Unstamped commands (stamp 0, and ~effort_group/command, which has no header) keep the
  // order alone. False when no message is waiting.
  bool TakeOne(const ros::Time& state_stamp);
  size_t waiting() const { return queue_.size(); }
  uint64_t discarded() const { return discarded_; }
  // Whether the last command TakeOne applied carried a stamp (a controller that stamps its
  // answers cannot be confused by a state published twice).
  bool last_taken_stamped() const { return last_taken_stamped_; }
  // Publishers connected to the three command topics now.
  int publishers() const;
  // ~step_with_command: an EffortCommand held at once, as on ~command. Empty or the reason.
  std::string HoldCommand(const EffortCommand& command);

 private:
  enum Source { kCommand = 0, kEffortGroup = 1, kWrench = 2, kSources = 3 };
  struct Queued {
    Source source;
    bool valid;
    std::vector<double> forces;
    ros::Time stamp;  // zero: none
  };
  void Accept(Source source, const std::string& why, const std::vector<double>& forces,
              const char* topic, const ros::Time& stamp);
  void Hold(Source source, const std::vector<double>& forces);
  // The axes of a wrench's frame in the base frame: the node's own world, base and platform
  // frames directly; any other through tf2 (a listener started at the first such wrench).
  std::string ResolveFrame(const std::string& frame, Rotation* to_base);

  const f3r_model& model_;
  const NodeParams& params_;
  const double* phi_p_;
  std::array<std::vector<double>, kSources> held_;
  std::array<bool, kSources> fresh_{};    // received since the last Total()
  std::array<double, kSources> since_{};  // simulated time the command took effect
  std::array<bool, kSources> active_{};
  std::vector<double> scratch_, total_;
  std::deque<Queued> queue_;  // lockstep only
  uint64_t rejected_ = 0;
  uint64_t discarded_ = 0;
  bool last_taken_stamped_ = false;
  ros::Subscriber command_sub_, group_sub_, wrench_sub_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
};

}  // namespace flex3rpr
