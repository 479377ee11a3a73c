#include "run_control_services.hpp"

namespace flex3rpr {

Services::Services(ros::NodeHandle& pnh, RunControl* control, SimHandlers handlers)
    : control_(control), handlers_(std::move(handlers)) {
  pause_ = pnh.advertiseService<std_srvs::Empty::Request, std_srvs::Empty::Response>(
      "pause", [this](std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
        control_->paused = true;
        return true;
      });
  resume_ = pnh.advertiseService<std_srvs::Empty::Request, std_srvs::Empty::Response>(
      "resume", [this](std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
        control_->paused = false;
        control_->pending_steps = 0;
        return true;
      });
  reset_ = pnh.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
      "reset", [this](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
        control_->reset_requested = true;
        res.success = true;
        res.message = "back to the scene's initial state at the next period";
        return true;
      });
  step_ = pnh.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
      "step", [this](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
        if (!control_->paused) {
          res.success = false;
          res.message = "not paused: call ~pause first";
          return true;
        }
        ++control_->pending_steps;
        res.success = true;
        res.message = "one publish period";
        return true;
      });
  step_with_command_ = pnh.advertiseService<StepWithCommand::Request, StepWithCommand::Response>(
      "step_with_command", [this](StepWithCommand::Request& req, StepWithCommand::Response& res) {
        handlers_.step_with_command(req, &res);
        return true;
      });
  set_state_ = pnh.advertiseService<SetState::Request, SetState::Response>(
      "set_state", [this](SetState::Request& req, SetState::Response& res) {
        handlers_.set_state(req, &res);
        return true;
      });
  linearise_ = pnh.advertiseService<Linearise::Request, Linearise::Response>(
      "linearise", [this](Linearise::Request&, Linearise::Response& res) {
        handlers_.linearise(&res);
        return true;
      });
}

}  // namespace flex3rpr
