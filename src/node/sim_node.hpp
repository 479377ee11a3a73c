// Owns the model and the simulation; runs the loop: apply commands, advance one publish period,
// publish, pace to the wall clock.
#pragma once

#include <ros/ros.h>

#include <memory>

#include "closed_loop_verifier.hpp"
#include "command_inputs.hpp"
#include "pacer.hpp"
#include "sensor_outputs.hpp"
#include "params.hpp"
#include "run_control_services.hpp"
#include "state_outputs.hpp"

namespace flex3rpr {

class SimNode {
 public:
  SimNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  // Reads parameters, builds the model, checks the URDF. False with a ROS_ERROR on failure.
  bool Init();
  // Runs until shutdown or ~duration; returns the process exit code.
  int Run();

 private:
  static constexpr double kPausedPublishSeconds = 0.5;  // wall s between outputs while paused
  static constexpr double kDiagnosticsSeconds = 1.0;    // wall s between /diagnostics
  static constexpr double kRepublishSeconds = 2.0;      // lockstep: wall s before a waiting state
                                                        // is sent again (see AwaitCommand)
  static constexpr double kConnectGraceSeconds = 1.0;   // lockstep: wall s after a command
                                                        // publisher connects before that
  static constexpr double kWaitWarningSeconds = 5.0;    // wall s between the wait's warnings

  // What Run keeps from one pass of its loop to the next.
  struct RunLoop {
    bool grace_pending = false;  // the ~subscriber_grace hold after the first period is to come
    double start = 0.0;          // wall s when the loop began
    double held = 0.0;           // wall s spent in the grace holds, not the simulation's
    double first_period_wall = -1.0, first_period_t = 0.0;
    bool was_running = false;  // the pacer is anchored when a run starts
    double last_paused_output = -1e9, last_diagnostics = -1e9;
    // Wall s without the grace holds: what the pacer and the intervals measure.
    double Wall() const { return ros::WallTime::now().toSec() - held; }
  };

  // ~initial_pose, if given, checked as ~set_state checks a pose; false with a ROS_ERROR.
  bool CheckInitialPose();
  // Run's parts: waiting for ~wait_for_subscribers (false when they do not come), ~reset, the
  // periodic /diagnostics, a pass while paused, and one period of a running simulation (false
  // when the run ends).
  bool WaitForSubscribers();
  void Restart(RunLoop* loop);
  void PublishDiagnosticsWhenDue(double now, RunLoop* loop);
  void IdlePaused(double now, RunLoop* loop);
  bool RunPeriod(double period, double now, RunLoop* loop, int* exit_code);
  bool Step(double period);
  // One period: Step, then what follows every period (stroke check, publishing). False when the
  // integration stopped (the node then pauses, or ends a scripted run).
  bool AdvancePeriod(double period);
  void PublishAt(const f3r_outputs& out);
  // After each period: the stroke check and the outputs.
  void PublishPeriod(const f3r_outputs& out);
  // ~verify's measurement into info_, with a warning when the request is first missed; true when
  // it changed since the last read.
  bool ReadMeasurement();
  // Lockstep: the present period has no command yet. Warns (throttled) and reports on ~status and
  // /diagnostics once it has waited ~lockstep_warn_after wall seconds.
  void AwaitCommand(double wall_now);
  // The services that act on the simulation (session_services.cpp).
  SimHandlers Handlers();
  void StepWithCommandCall(const StepWithCommand::Request& req, StepWithCommand::Response* res);
  void SetStateCall(const SetState::Request& req, SetState::Response* res);
  void LineariseCall(Linearise::Response* res);
  // The scene's sensors with the ~sensors parameters (sensor_outputs.cpp); false with a
  // ROS_ERROR.
  void StartSensors();
  // Into ~status and a throttled warning while the achieved factor is short of the request.
  void ReportPace();
  // rho_i outside the scene's stroke: into ~status, and a warning once per excursion.
  void CheckStroke(const f3r_outputs& out);

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  f3r_session* session_ = nullptr;  // params_.session: the model, the simulation, the check
  const f3r_model* model_ = nullptr;
  f3r_sim* sim_ = nullptr;
  std::unique_ptr<CommandInputs> inputs_;
  std::unique_ptr<StateOutputs> outputs_;
  std::unique_ptr<SensorOutputs> sensors_;  // the scene's sensors (sensor_outputs.hpp)
  std::unique_ptr<Services> services_;
  RunControl control_;
  RunInfo info_;
  std::unique_ptr<Pacer> pacer_;
  // ~verify's thread; destroyed before params_ closes the session whose check it steps
  std::unique_ptr<ClosedLoopVerifier> verifier_;
  double phi_p_ = 0.0;
  double last_published_t_ = -1.0;   // simulated time of the last full Publish (with /tf)
  double waiting_since_ = -1.0;      // lockstep: wall s when the present period began to wait
  double last_republish_ = -1.0;     // lockstep: wall s the waiting state was last sent
  double last_wait_warning_ = -1e9;  // wall s of the last "waiting for command" warning
  int command_publishers_ = 0;       // lockstep: publishers on the command topics at the last look
  double republish_at_ = -1.0;       // lockstep: wall s to send the waiting state again (a
                                     // publisher connected meanwhile), or < 0
  bool commands_taken_ = false;      // lockstep: a command has taken a period since the start
  bool stopped_ = false;             // the last AdvancePeriod failed
};

}  // namespace flex3rpr
