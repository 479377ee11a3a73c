// Everything the node publishes: joint_states, TF (tree, platform, beam points), ~odom, ~status,
// ~beam_state, ~beams, /clock and /diagnostics. Messages are preallocated; Publish only fills them.
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <array>
#include <vector>

#include "flex3rpr/BeamState.h"
#include "flex3rpr/FullState.h"
#include "flex3rpr/SimStatus.h"
#include "flex3rpr/sim.h"
#include "params.hpp"

namespace flex3rpr {

struct RunInfo {
  double wall_time = 0.0;
  double realtime_factor = 0.0;
  double requested_realtime_factor = 0.0;  // ~realtime_factor
  bool behind = false;                     // paced and achieving less than 0.95 of the request
  double lag = 0.0;                        // wall s behind the paced schedule
  uint64_t resyncs = 0;                    // stalls after which pacing started again
  std::array<bool, 3> outside_stroke{};    // rho_i outside the scene's stroke
  bool paused = false;
  uint64_t rejected_commands = 0;
  double waiting_for_command = 0.0;  // lockstep: wall s the present period has waited for
                                     // its command, once past ~lockstep_warn_after; else 0
  std::string last_error;
  // ~verify (closed_loop_verifier.hpp): the closed-loop measurement of the accuracy request
  bool verifying = false;
  double measured_error = 0.0;       // m, the largest end-effector distance so far; NaN once lost
  bool request_met = true;           // measured within 0.7 of the request: false stays until ~reset
  std::string measurement_note;      // why the measurement was lost, or ""
  uint64_t measurement_pending = 0;  // periods handed to the check and not yet checked
};

class StateOutputs {
 public:
  StateOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, const f3r_model& model,
               const NodeParams& params);
  void Publish(const f3r_outputs& out, const RunInfo& info);
  // While paused, at a low rate: /clock, joint_states, ~odom, ~beam_state, ~beams and ~status
  // again (the state has not changed; the status may have). /tf only with wall stamps: a
  // simulated stamp repeated is TF_REPEATED_DATA to every listener, so with simulated time a
  // listener that connects later gets the frames once, on connection.
  void PublishPaused(const f3r_outputs& out, const RunInfo& info);
  // ~status alone (lockstep: while a period waits for its command, joint_states must not repeat,
  // since a controller answers each one).
  void PublishStatusOnly(const f3r_outputs& out, const RunInfo& info) { PublishStatus(out, info); }
  // Lockstep: the state a period waits for, again (joint_states, ~odom, ~beam_state, ~status; /tf
  // only with wall stamps), when its first answer may have been lost: a command publisher that
  // connected after the state went out could not have delivered it.
  void Republish(const f3r_outputs& out, const RunInfo& info);
  // Lockstep: the present period waits for its command, so the state stands still as when
  // paused: a /tf subscriber that connects from now until the next period gets the present
  // frames once, on connection (a late tf2 listener resolves them while simulated time stands).
  void HoldStill() { still_ = true; }
  // The stamp of the last state Publish sent (its first publication).
  const ros::Time& state_stamp() const { return state_stamp_; }
  // /diagnostics: one status for the simulation (OK, WARN when behind or outside the stroke,
  // ERROR when the integration stopped).
  void PublishDiagnostics(const f3r_outputs& out, const RunInfo& info);
  // Restarts ~status.published_states (a reset starts the count again at its initial state) and
  // the energy guard's largest T + V (the energy balance starts anew there too).
  void RestartCount() {
    published_states_ = 0;
    RestartEnergy();
  }
  // A new energy balance (~set_state): the guard starts again.
  void RestartEnergy() {
    largest_energy_ = 0.0;
    energy_guard_ = false;
  }
  // The last joint_states message filled (for ~step_with_command's answer).
  const sensor_msgs::JointState& joint_state() const { return joints_; }
  // True when every output topic (joint_states, /tf, ~odom, ~status, ~beam_state, ~beams, and /clock
  // when it is published) has at least n subscribers connected, and each live subscriber the
  // master lists for it: on /clock, rosout and other nodes on simulated time count too, so a
  // count alone could pass before a recorder's own /clock connection is up. A listed node that
  // does not answer at its URI (a killed process's stale entry) is not waited for.
  bool SubscribersConnected(int n) const;

 private:
  // The constructor's parts: the topics, the preallocated messages, the static frames (sent
  // once) and the dynamic frames' transforms.
  void Advertise(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  void PrepareMessages();
  void SendStaticFrames();
  void PrepareTransforms();
  void FillTransforms(const f3r_outputs& out, const ros::Time& stamp);
  void PublishStatus(const f3r_outputs& out, const RunInfo& info);
  void PublishState(const f3r_outputs& out, const ros::Time& stamp);  // all but /tf and ~status
  // Simulated time, or the wall clock (~stamps).
  ros::Time Stamp(double t) const {
    return params_.sim_stamps ? ros::Time(t) : ros::Time(ros::WallTime::now().toSec());
  }

  const f3r_model& model_;
  const NodeParams& params_;
  const FrameNames& frames_;
  uint64_t published_states_ = 0;  // ~status.published_states
  ros::Time state_stamp_;          // the last Publish's stamp
  double largest_energy_ = 0.0;    // J: the largest T + V published, for the energy guard
  bool energy_guard_ = false;      // tripped once since the balance began: it stays (a blow-up's
                                   // own T + V can bring the ratio back under the guard)
  bool have_transforms_ = false;   // tf_ holds a published state
  bool still_ = false;  // the state stands (paused, or a lockstep period waits): a /tf subscriber
                        // that connects gets the present frames once
  ros::Publisher joints_pub_, status_pub_, beam_pub_, state_pub_, markers_pub_, clock_pub_, tf_pub_,
      odom_pub_, diagnostics_pub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  sensor_msgs::JointState joints_;
  SimStatus status_;
  FullState state_;
  BeamState beam_;
  visualization_msgs::MarkerArray markers_;
  rosgraph_msgs::Clock clock_;
  nav_msgs::Odometry odom_;
  diagnostic_msgs::DiagnosticArray diagnostics_;
  tf2_msgs::TFMessage tf_;  // tf_.transforms: the dynamic frames
};

}  // namespace flex3rpr
