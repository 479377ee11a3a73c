// Everything the node publishes: joint_states, TF (tree, platform, beam points), ~status,
// ~beam_state, ~beams and /clock. Messages are preallocated; Publish only fills them.
#pragma once

#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <vector>

#include "flex3rpr/BeamState.h"
#include "flex3rpr/SimStatus.h"
#include "flex3rpr/sim.h"
#include "params.hpp"

namespace flex3rpr {

struct RunInfo {
  double wall_time = 0.0;
  double realtime_factor = 0.0;
  double requested_realtime_factor = 0.0;  // ~realtime_factor
  bool behind = false;                     // paced and more than kBehindSeconds late
  double lag = 0.0;                        // wall s behind the paced schedule
  bool paused = false;
  uint64_t rejected_commands = 0;
  std::string last_error;
};

class StateOutputs {
 public:
  StateOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, const f3r_model& model,
               const NodeParams& params);
  void Publish(const f3r_outputs& out, const RunInfo& info);
  // Only ~status: while paused the state does not change, but the status (paused, rejected
  // commands) still does.
  void PublishStatus(const f3r_outputs& out, const RunInfo& info);
  // Restarts ~status.published_states (a reset starts the count again at its initial state).
  void RestartCount() { published_states_ = 0; }
  // True when every output topic (joint_states, /tf, ~status, ~beam_state, ~beams, and /clock
  // when it is published) has at least n subscribers connected, and each subscriber the master
  // lists for it: on /clock, rosout and other nodes on simulated time count too, so a count alone
  // could pass before a recorder's own /clock connection is up.
  bool SubscribersConnected(int n) const;

 private:
  void FillTransforms(const f3r_outputs& out, const ros::Time& stamp);

  const f3r_model& model_;
  const NodeParams& params_;
  bool publish_clock_ = false;
  uint64_t published_states_ = 0;  // ~status.published_states
  ros::Publisher joints_pub_, status_pub_, beam_pub_, markers_pub_, clock_pub_, tf_pub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  sensor_msgs::JointState joints_;
  SimStatus status_;
  BeamState beam_;
  visualization_msgs::MarkerArray markers_;
  rosgraph_msgs::Clock clock_;
  tf2_msgs::TFMessage tf_;  // tf_.transforms: the dynamic frames
};

}  // namespace flex3rpr
