// Parameters of flex3rpr_node (private namespace ~) and the scene they select.
#pragma once

#include <ros/ros.h>

#include <array>
#include <string>
#include <vector>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/session.h"
#include "flex3rpr/sim.h"

namespace flex3rpr {

// Every frame the node publishes: ~tf_prefix + name, except the world frame, which robots share.
struct FrameNames {
  std::string world, base, platform;
  std::array<std::string, 3> cylinder, piston, tip_nominal, platform_c;
  std::array<std::vector<std::string>, 3> beam;  // stations 0..beam_points-1
};
FrameNames MakeFrameNames(const std::string& prefix, const std::string& world,
                          const std::string& base, int beam_points);
// "robot1" and "robot1/" give "robot1/"; "" gives "".
std::string NormalisePrefix(const std::string& prefix);

struct NodeParams {
  NodeParams() = default;
  NodeParams(const NodeParams&) = delete;  // the scene owns its input tables
  NodeParams& operator=(const NodeParams&) = delete;
  ~NodeParams() {
    f3r_session_close(session);
    f3r_scene_free(&scene);
  }

  std::string scene_path;                 // ~scene, default: the package's rest.yaml
  f3r_scene scene = f3r_default_scene();  // loaded, overridden and resolved (the session's)
  // The scene opened for the run (flex3rpr/session.h): the knob's choice, the model, the
  // simulation, the limits and the closed-loop check, as in every shell.
  f3r_session* session = nullptr;
  f3r_solver_settings settings;    // ~formulation, ~integrator, ~rtol, ~atol
  f3r_accuracy_choice accuracy{};  // ~accuracy or the scene's: what the knob chose, and why
  double publish_rate = 1000.0;    // Hz of simulated time
  int beam_points = 11;            // stations per link
  double realtime_factor = 1.0;    // 1 paces to the wall clock, 0 runs as fast as possible
  std::string tf_prefix;           // prepended to every frame but the world frame ("robot1/")
  std::string world_frame = "world";
  std::string base_frame = "base";  // default: tf_prefix + "base"
  FrameNames frames;
  bool sim_stamps = false;       // ~stamps (sim, wall); default: /use_sim_time
  bool publish_clock = false;    // ~publish_clock, default: /use_sim_time
  bool start_paused = false;     // ~paused
  bool end_stops = false;        // ~end_stops: the scene's stroke as hard stops
  double command_timeout = 0.0;  // s of simulated time; 0 holds commands forever
  double duration =
      0.0;  // s; > 0 stops the node at that simulated time; < 0 the scene's run.duration
  int wait_for_subscribers =
      0;  // before the first output, wait until every output topic has this many
  double subscriber_timeout = 30.0;  // wall s to wait for them; then the node exits with an error
  double subscriber_grace = 0.5;     // wall s the node holds after the first period when it waited
  int queue_size = 10;               // outgoing messages held per subscriber and output topic
  int command_queue_size =
      1000;  // incoming commands held per input topic while the loop integrates
  double beam_marker_exaggeration = 1.0;  // visual only: scales the deflection in ~beams
  bool lockstep = false;              // ~lockstep: each period waits for its command (sim_node.cpp)
  double lockstep_warn_after = 2.0;   // wall s without the period's command before a warning
  std::array<double, 3> base_pose{};  // ~base_pose: x (m), y (m), yaw (rad) of base in world
  bool initial_pose_set = false;      // ~initial_pose given: the scene's initial.platform_pose
  std::array<double, 3> initial_pose{};  // what it says: x (m), y (m), phi (rad)
};

// The default scene shipped with the package.
std::string DefaultScenePath();

// Reads every parameter; on a missing or invalid one returns false with a message naming it.
bool LoadParams(const ros::NodeHandle& pnh, NodeParams* params, std::string* error);

}  // namespace flex3rpr
