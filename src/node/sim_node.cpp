#include "sim_node.hpp"

#include <algorithm>
#include <cmath>

#include <ros/callback_queue.h>
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

// ~initial_pose as ~set_state would check it, on a simulation of its own: a pose the legs
// reach only through the collapse guard, or beyond the end stops, would stop the first period.
bool SimNode::CheckInitialPose() {
  if (!params_.initial_pose_set) return true;
  f3r_sim* probe = nullptr;
  f3r_error err{};
  const double twist[3] = {0.0, 0.0, 0.0};
  f3r_status st = f3r_sim_create(model_, &params_.settings, &probe, &err);
  if (st == F3R_OK)
    st = f3r_sim_set_state(probe, params_.initial_pose.data(), twist, nullptr, nullptr, &err);
  f3r_sim_destroy(probe);
  if (st == F3R_OK) return true;
  ROS_ERROR("flex3rpr_node: parameter ~initial_pose: %s", err.message);
  return false;
}

bool SimNode::Init() {
  std::string error;
  if (!LoadParams(pnh_, &params_, &error)) {
    ROS_ERROR("flex3rpr_node: %s", error.c_str());
    return false;
  }
  session_ = params_.session;
  model_ = f3r_session_model(session_);
  sim_ = f3r_session_sim(session_);
  std::string urdf;
  const bool described = nh_.hasParam("robot_description");
  if (described && !nh_.getParam("robot_description", urdf)) {
    ROS_ERROR("flex3rpr_node: parameter robot_description: not a string (a URDF)");
    return false;
  }
  if (!described) {
    const std::string path = ros::package::getPath("flex3rpr") + "/urdf/flex3rpr.urdf";
    if (!ReadFile(path, &urdf)) {
      ROS_ERROR("flex3rpr_node: no robot_description parameter and cannot read %s", path.c_str());
      return false;
    }
    ROS_INFO("flex3rpr_node: no robot_description parameter; checking the geometry against %s",
             path.c_str());
  }
  // The package's URDF is for the default frames and 11 stations: only its geometry must match.
  const std::string mismatch = CheckUrdf(urdf, *model_, described ? &params_.frames : nullptr);
  if (!mismatch.empty()) {
    ROS_ERROR("flex3rpr_node: %s", mismatch.c_str());
    return false;
  }
  if (!CheckInitialPose()) return false;
  inputs_.reset(new CommandInputs(pnh_, *model_, params_, &phi_p_));
  outputs_.reset(new StateOutputs(nh_, pnh_, *model_, params_));
  StartSensors();
  services_.reset(new Services(pnh_, &control_, Handlers()));
  ROS_INFO(
      "flex3rpr_node: scene %s, nq %d, %s, rtol %g, publishing at %g Hz of simulated time, "
      "real-time factor %g, %s stamps%s, frames under %s",
      params_.scene_path.c_str(), f3r_model_nq(model_),
      f3r_formulation_name(params_.settings.formulation), params_.settings.rtol,
      params_.publish_rate, params_.realtime_factor,
      params_.sim_stamps ? "simulated" : "wall-clock", params_.publish_clock ? " with /clock" : "",
      params_.frames.base.c_str());
  if (params_.lockstep)
    ROS_INFO(
        "flex3rpr_node: lockstep: each publish period waits for its command, the next message on "
        "~command, ~effort_group/command or ~platform_wrench");
  if (params_.accuracy.summary[0]) ROS_INFO("flex3rpr_node: %s", params_.accuracy.summary);
  verifier_.reset(
      new ClosedLoopVerifier(f3r_session_closed_loop_check(session_), f3r_model_nq(model_)));
  info_.verifying = verifier_->active();
  if (verifier_->active())
    ROS_INFO(
        "flex3rpr_node: ~verify: the check configuration steps on the same commands on a thread "
        "of its own; ~status.measured_error_m is the largest end-effector distance so far");
  else if (params_.accuracy.request > 0.0)
    ROS_INFO(
        "flex3rpr_node: the accuracy is estimated, not measured (~verify is false, or the "
        "scene's accuracy.verify)");
  if (params_.accuracy.request > 0.0 && !params_.accuracy.request_met)
    ROS_WARN("flex3rpr_node: the accuracy request %g m is not met: estimated %.3g m (%s)",
             params_.accuracy.request, params_.accuracy.estimated_error, params_.accuracy.brief);
  return true;
}

void SimNode::ReportPace() {
  const Pacer& p = *pacer_;
  info_.realtime_factor = p.achieved();
  info_.requested_realtime_factor = p.requested();
  info_.behind = p.behind();
  info_.lag = p.lag();
  info_.resyncs = p.resyncs();
  if (info_.behind)
    ROS_WARN_THROTTLE(
        5.0,
        "flex3rpr_node: behind the wall clock: achieved real-time factor %.3g of the requested %g "
        "(below %g of it; a looser solver.rtol, fewer modes or a lower ~realtime_factor would "
        "keep up)",
        p.achieved(), p.requested(), Pacer::kBehindFraction);
}

void SimNode::CheckStroke(const f3r_outputs& out) {
  const f3r_geometry g = f3r_model_geometry(model_);
  const double lo = g.stroke_min, hi = g.stroke_max;
  for (int i = 0; i < 3; ++i) {
    const double rho = out.q[F3R_Q_RHO + i];
    // End stops hold rho to the stroke up to the event location's tolerance.
    const double slack = g.end_stops ? 1e-6 : 0.0;
    const bool outside = rho < lo - slack || rho > hi + slack;
    bool& flag = info_.outside_stroke[static_cast<size_t>(i)];
    if (outside && !flag)
      ROS_WARN(
          "flex3rpr_node: leg %d left its stroke %g..%g m (the URDF's limits): rho_%d = %.6g m at "
          "t = "
          "%.6g s; reported once until it returns (end_stops:=true makes the stroke hard)",
          i + 1, lo, hi, i + 1, rho, out.t);
    flag = outside;
  }
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

// Publishes the state; a state whose time was published already (the last good state after an
// integration error is often the last output) goes out without /tf, which would otherwise repeat
// a stamp (TF_REPEATED_DATA).
void SimNode::PublishAt(const f3r_outputs& out) {
  ReadMeasurement();
  sensors_->Publish(out.t);
  if (out.t > last_published_t_) {
    outputs_->Publish(out, info_);
    last_published_t_ = out.t;
  } else {
    outputs_->PublishPaused(out, info_);
  }
}

bool SimNode::Step(double period) {
  f3r_error err{};
  const std::vector<double>& forces = inputs_->Total(f3r_sim_time(sim_));
  // Each topic's command was checked on arrival (command_decoding.hpp); their sum may reach the
  // sum of the limits, so the session checks only its count and finiteness here.
  if (f3r_session_advance(session_, forces.data(), static_cast<int>(forces.size()), period, &err) !=
      F3R_OK) {
    info_.last_error = err.message;
    ROS_ERROR(
        "flex3rpr_node: integration stopped in the period after t = %.6g s: %s; paused at the "
        "last good state, that period's start (~reset starts over, ~resume tries again)",
        f3r_sim_time(sim_), err.message);
    return false;
  }
  // the period's end on the session's grid: the time the session gives its own check
  verifier_->Period(forces.data(), static_cast<double>(f3r_session_periods(session_)) * period,
                    f3r_sim_outputs(sim_)->q + F3R_Q_X);
  return true;
}

bool SimNode::AdvancePeriod(double period) {
  if (!Step(period)) {  // the node outlives its physics: it pauses and keeps serving
    control_.paused = true;
    control_.pending_steps = 0;
    info_.paused = true;
    info_.rejected_commands = inputs_->rejected();
    PublishAt(*f3r_sim_outputs(sim_));
    return false;
  }
  PublishPeriod(*f3r_sim_outputs(sim_));
  return true;
}

void SimNode::PublishPeriod(const f3r_outputs& out) {
  phi_p_ = out.q[F3R_Q_PHI];
  CheckStroke(out);
  info_.rejected_commands = inputs_->rejected();
  PublishAt(out);
}

bool SimNode::ReadMeasurement() {
  if (!verifier_->active()) return false;
  const ClosedLoopVerifier::Result r = verifier_->Read();
  const bool was_met = info_.request_met;
  const bool changed = r.pending != info_.measurement_pending ||
                       !(r.measured == info_.measured_error) || r.note != info_.measurement_note;
  info_.measured_error = r.measured;
  info_.request_met = r.request_met;
  info_.measurement_note = r.note;
  info_.measurement_pending = r.pending;
  if (was_met && !r.request_met)
    ROS_WARN(
        "flex3rpr_node: ~verify: the accuracy request %g m is not met: %s (latched until "
        "~reset)",
        r.request,
        r.note.empty() ? ("measured " + std::to_string(r.measured) + " m").c_str()
                       : r.note.c_str());
  return changed;
}

void SimNode::AwaitCommand(double wall_now) {
  if (waiting_since_ < 0.0) {
    waiting_since_ = last_republish_ = wall_now;
    outputs_->HoldStill();  // a late /tf listener gets the present frames on connection
  }
  // An answer sent before the controller's publisher connected to this node is lost, and both
  // sides would wait for ever (a controller answering the latched first state at once): when a
  // command publisher connects while a period waits, and no command has come kConnectGraceSeconds
  // later (an answer sent just after the connection is on its way), the state goes out again.
  // So it does every kRepublishSeconds before the first command, or while the controller stamps
  // its answers (a duplicate answer is then discarded; unstamped, it would take the next period).
  const int publishers = inputs_->publishers();
  if (publishers > command_publishers_) republish_at_ = wall_now + kConnectGraceSeconds;
  command_publishers_ = publishers;
  const bool after_connection = republish_at_ > 0.0 && wall_now >= republish_at_;
  const bool retry = wall_now - last_republish_ >= kRepublishSeconds &&
                     (!commands_taken_ || inputs_->last_taken_stamped());
  if (after_connection || retry) {
    outputs_->Republish(*f3r_sim_outputs(sim_), info_);
    last_republish_ = wall_now;
    republish_at_ = -1.0;
  }
  const double waited = wall_now - waiting_since_;
  if (waited < params_.lockstep_warn_after) return;
  info_.waiting_for_command = waited;
  // throttled on the wall clock: simulated time stands still while the period waits
  if (wall_now - last_wait_warning_ < kWaitWarningSeconds) return;
  last_wait_warning_ = wall_now;
  ROS_WARN(
      "flex3rpr_node: lockstep: no command for the period at t = %.6g s for %.1f s; waiting (a "
      "controller answers every joint_states message with one message on ~command, "
      "~effort_group/command or ~platform_wrench)",
      f3r_sim_time(sim_), waited);
}

// e.g. a recorder: nothing may be published before it listens. False after ~subscriber_timeout.
bool SimNode::WaitForSubscribers() {
  if (params_.wait_for_subscribers <= 0) return true;
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(params_.subscriber_timeout);
  while (ros::ok() && !outputs_->SubscribersConnected(params_.wait_for_subscribers)) {
    if (ros::WallTime::now() > until) {
      ROS_ERROR(
          "flex3rpr_node: ~wait_for_subscribers: an output topic lacks subscribers (%d, or those "
          "the "
          "master lists) after %g s",
          params_.wait_for_subscribers, params_.subscriber_timeout);
      return false;
    }
    ros::spinOnce();
    ros::WallDuration(0.02).sleep();
  }
  ROS_INFO("flex3rpr_node: every output topic has its subscribers (at least %d); starting",
           params_.wait_for_subscribers);
  return true;
}

// ~reset: time, commands and the stroke warnings start over.
void SimNode::Restart(RunLoop* loop) {
  f3r_error err{};
  control_.reset_requested = false;
  inputs_->Clear();
  if (f3r_session_reset(session_, &err) != F3R_OK)
    ROS_ERROR("flex3rpr_node: reset failed: %s", err.message);
  verifier_->Reset();
  loop->was_running = false;
  info_.last_error.clear();
  info_.outside_stroke = {};
  outputs_->RestartCount();
  commands_taken_ = false;
  last_published_t_ = -1.0;  // time starts over
  sensors_->Reset();         // the session's sensors started over
  PublishAt(*f3r_sim_outputs(sim_));
}

void SimNode::PublishDiagnosticsWhenDue(double now, RunLoop* loop) {
  if (now - loop->last_diagnostics < kDiagnosticsSeconds) return;
  info_.rejected_commands = inputs_->rejected();
  ReadMeasurement();
  outputs_->PublishDiagnostics(*f3r_sim_outputs(sim_), info_);
  // A period that waits for its command publishes nothing else: say so on ~status too.
  if (info_.waiting_for_command > 0.0) outputs_->PublishStatusOnly(*f3r_sim_outputs(sim_), info_);
  loop->last_diagnostics = now;
}

void SimNode::IdlePaused(double now, RunLoop* loop) {
  loop->was_running = false;
  outputs_->HoldStill();  // in lockstep too, where nothing below is published
  info_.behind = false;
  info_.lag = 0.0;
  // Not in lockstep: a controller answers every state it receives, and the state is latched.
  const bool measured = ReadMeasurement();
  if (!params_.lockstep && now - loop->last_paused_output >= kPausedPublishSeconds) {
    info_.rejected_commands = inputs_->rejected();
    outputs_->PublishPaused(*f3r_sim_outputs(sim_), info_);
    loop->last_paused_output = now;
  } else if (inputs_->rejected() != info_.rejected_commands || measured) {
    // A command refused, or the check catching up, while paused shows on ~status at once, not
    // half a second later.
    info_.rejected_commands = inputs_->rejected();
    outputs_->PublishStatusOnly(*f3r_sim_outputs(sim_), info_);
  }
  ros::WallDuration(0.001).sleep();
}

// One period of a running simulation: advance, publish, pace. False when the run ends: the
// duration is reached, or (exit code 2) a scripted run's integration stopped.
bool SimNode::RunPeriod(double period, double now, RunLoop* loop, int* exit_code) {
  waiting_since_ = -1.0;
  republish_at_ = -1.0;  // a command came: what connected meanwhile has been heard
  command_publishers_ = inputs_->publishers();
  info_.waiting_for_command = 0.0;
  if (control_.pending_steps > 0) --control_.pending_steps;
  if (!loop->was_running) pacer_->Start(now, f3r_sim_time(sim_));
  loop->was_running = !control_.paused;
  if (!Step(period)) {
    if (params_.duration > 0.0) {  // a scripted run (a recording) ends instead of waiting
      *exit_code = 2;
      PublishAt(*f3r_sim_outputs(sim_));
      return false;
    }
    control_.paused = true;
    control_.pending_steps = 0;
    info_.paused = true;
    loop->was_running = false;
    info_.rejected_commands = inputs_->rejected();
    PublishAt(*f3r_sim_outputs(sim_));
    return true;
  }
  const f3r_outputs& out = *f3r_sim_outputs(sim_);
  const double after = loop->Wall();
  if (loop->first_period_wall < 0.0) {
    loop->first_period_wall = after;
    loop->first_period_t = out.t;
  }
  info_.wall_time = after - loop->start;
  const double due = pacer_->Due(after, out.t);
  ReportPace();
  PublishPeriod(out);
  if (loop->grace_pending) {
    loop->grace_pending = false;
    loop->held += SpinFor(params_.subscriber_grace).toSec();
  }
  if (params_.duration > 0.0 && out.t >= params_.duration - 0.5 * period) {
    // The second factor leaves out the start (a controller's or recorder's connection, the
    // first period's wait): what a closed loop sustains.
    ROS_INFO(
        "flex3rpr_node: reached the duration %g s (real-time factor %.3g; %.3g from the end of "
        "the first period)",
        out.t, out.t / info_.wall_time,
        (out.t - loop->first_period_t) / std::max(after - loop->first_period_wall, 1e-9));
    return false;
  }
  if (!control_.paused) {  // pace to the wall clock
    const double ahead = due - loop->Wall();
    if (ahead > 0.0) ros::WallDuration(ahead).sleep();
  }
  return true;
}

int SimNode::Run() {
  const double period = 1.0 / params_.publish_rate;
  if (!WaitForSubscribers()) return 3;
  // A subscriber on simulated time, such as rosbag record, takes its first messages only once
  // /clock is past zero (ros::Time::waitForValid), and its subscription queues hold 100 each:
  // after the first period, and before it exits, the node holds ~subscriber_grace wall seconds.
  RunLoop loop;
  const bool grace = params_.wait_for_subscribers > 0 && params_.subscriber_grace > 0.0;
  loop.grace_pending = grace;
  loop.start = ros::WallTime::now().toSec();
  pacer_.reset(new Pacer(params_.realtime_factor));
  control_.paused = params_.start_paused;
  info_.paused = control_.paused;
  info_.requested_realtime_factor = params_.realtime_factor;
  PublishAt(*f3r_sim_outputs(sim_));
  if (control_.paused)
    ROS_INFO("flex3rpr_node: paused at the start (~paused); ~resume or ~step runs it");
  int exit_code = 0;
  while (ros::ok()) {
    ros::spinOnce();
    const double now = loop.Wall();
    if (control_.reset_requested) Restart(&loop);
    PublishDiagnosticsWhenDue(now, &loop);
    const bool run = !control_.paused || control_.pending_steps > 0;
    info_.paused = control_.paused;
    if (!run) {
      IdlePaused(now, &loop);
      continue;
    }
    if (params_.lockstep && !inputs_->TakeOne(outputs_->state_stamp())) {  // not come yet
      AwaitCommand(now);
      // Wakes as soon as a message arrives, rather than at the next poll.
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.001));
      continue;
    }
    commands_taken_ = commands_taken_ || params_.lockstep;
    if (!RunPeriod(period, now, &loop, &exit_code)) break;
  }
  if (grace) SpinFor(params_.subscriber_grace);  // the subscribers take the last messages
  return exit_code;
}

}  // namespace flex3rpr
