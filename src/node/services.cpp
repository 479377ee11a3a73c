#include "services.hpp"

namespace flex3rpr {

Services::Services(ros::NodeHandle& pnh, RunControl* control) : control_(control) {
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
}

}  // namespace flex3rpr
