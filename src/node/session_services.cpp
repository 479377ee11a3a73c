// The services that act on the simulation itself: ~step_with_command (call and return),
// ~set_state and ~linearise. They run in the node's one thread, between periods.
#include <algorithm>
#include <cmath>
#include <memory>

#include "flex3rpr/linear.h"
#include "flex3rpr/session.h"
#include "sim_node.hpp"

namespace flex3rpr {

SimHandlers SimNode::Handlers() {
  SimHandlers h;
  h.step_with_command = [this](const StepWithCommand::Request& req,
                               StepWithCommand::Response* res) { StepWithCommandCall(req, res); };
  h.set_state = [this](const SetState::Request& req, SetState::Response* res) {
    SetStateCall(req, res);
  };
  h.linearise = [this](Linearise::Response* res) { LineariseCall(res); };
  return h;
}

void SimNode::StepWithCommandCall(const StepWithCommand::Request& req,
                                  StepWithCommand::Response* res) {
  res->success = false;
  // Deterministic only when nothing else advances the simulation meanwhile.
  if (!control_.paused && !params_.lockstep) {
    res->message = "the node runs freely: call ~pause first, or start it with ~lockstep";
    return;
  }
  if (params_.lockstep && inputs_->waiting() > 0) {
    res->message =
        "a command from a topic is waiting for the present period; mixing topics and "
        "~step_with_command in lockstep would make the order depend on timing";
    return;
  }
  const double period = 1.0 / params_.publish_rate;
  f3r_error err{};
  if (f3r_session_check_step(req.periods, period, &err) != F3R_OK) {
    res->message = err.message;
    return;
  }
  const std::string why = inputs_->HoldCommand(req.command);
  if (!why.empty()) {
    res->message = "command: " + why + "; nothing changed";
    return;
  }
  for (uint32_t k = 0; k < req.periods; ++k) {
    if (!AdvancePeriod(period)) {
      // the session's words, as Python's step says them: the failed period is undone; the
      // periods before it were published, and stand
      res->message = info_.last_error;
      if (k > 0)
        res->message += "; the first " + std::to_string(k) + " of " + std::to_string(req.periods) +
                        " periods stand";
      break;
    }
  }
  const f3r_outputs& out = *f3r_sim_outputs(sim_);
  res->success = res->message.empty();
  if (res->success) res->message = std::to_string(req.periods) + " periods";
  res->sim_time = out.t;
  res->joint_state = outputs_->joint_state();
  for (int k = 0; k < 3; ++k) {
    res->platform_pose[static_cast<size_t>(k)] = out.q[F3R_Q_X + k];
    res->platform_twist[static_cast<size_t>(k)] = out.v[F3R_Q_X + k];
  }
  res->modal.assign(out.q + F3R_Q_MODAL, out.q + f3r_model_nq(model_));
  res->modal_rate.assign(out.v + F3R_Q_MODAL, out.v + f3r_model_nq(model_));
}

void SimNode::SetStateCall(const SetState::Request& req, SetState::Response* res) {
  res->success = false;
  // the session's checks and set (flex3rpr/session.h), as flex3rpr.Sim.set_state's: the
  // modal count and the ranges of a scene's initial state, in the same words
  if (!req.modal.empty() && !req.modal_rate.empty() && req.modal.size() != req.modal_rate.size()) {
    res->message = "modal and modal_rate: " + std::to_string(req.modal.size()) + " and " +
                   std::to_string(req.modal_rate.size()) + " values; nothing changed";
    return;
  }
  const double* modal = req.modal.empty() ? nullptr : req.modal.data();
  const double* modal_rate = req.modal_rate.empty() ? nullptr : req.modal_rate.data();
  const int count = static_cast<int>(std::max(req.modal.size(), req.modal_rate.size()));
  f3r_error err{};
  if (f3r_session_set_state(session_, req.platform_pose.data(), req.platform_twist.data(), modal,
                            modal_rate, count, &err) != F3R_OK) {
    res->message = err.message;
    if (res->message.find("nothing changed") == std::string::npos)
      res->message += "; nothing changed";
    return;
  }
  verifier_->SetState(req.platform_pose.data(), req.platform_twist.data(), count != 0);
  const f3r_outputs& out = *f3r_sim_outputs(sim_);
  phi_p_ = out.q[F3R_Q_PHI];
  info_.last_error.clear();
  outputs_->RestartEnergy();
  CheckStroke(out);
  // The same time with a new state: /tf waits for the next period (a repeated stamp is
  // TF_REPEATED_DATA to every listener); the rest goes out now.
  outputs_->PublishPaused(out, info_);
  res->success = true;
  res->message = "state set at t = " + std::to_string(out.t) + " s";
}

namespace {

struct ModelDeleter {
  void operator()(f3r_model* m) const { f3r_model_destroy(m); }
};
struct StateSpaceDeleter {
  void operator()(f3r_state_space* ss) const { f3r_state_space_destroy(ss); }
};

// Column-major (the core's) to row-major (the message's).
std::vector<double> RowMajor(const double* a, int rows, int cols) {
  std::vector<double> out(static_cast<size_t>(rows * cols));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) out[static_cast<size_t>(r * cols + c)] = a[c * rows + r];
  return out;
}

}  // namespace

void SimNode::LineariseCall(Linearise::Response* res) {
  res->success = false;
  // The model of the present pose at rest: the node's scene (its mode counts as the model chose
  // them) with the present platform pose as its initial one, no velocity, no deflection.
  const f3r_outputs& out = *f3r_sim_outputs(sim_);
  // A view of the model's scene (its tables stay the model's, scene.h), which the new model copies.
  std::unique_ptr<f3r_scene> scene(new f3r_scene(*f3r_model_scene(model_)));
  for (int k = 0; k < 3; ++k) {
    scene->platform_pose0[k] = out.q[F3R_Q_X + k];
    scene->platform_velocity0[k] = 0.0;
  }
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = f3r_model_link(model_, i);
    scene->links[i].modes = lp->modes - lp->static_shapes;  // the shapes follow static_correction
    for (int j = 0; j < F3R_MAX_MODES; ++j)
      scene->links[i].eta0[j] = scene->links[i].eta_rate0[j] = 0.0;
  }
  f3r_error err{};
  f3r_model* raw = nullptr;
  if (f3r_model_create(scene.get(), &raw, &err) != F3R_OK) {
    res->message = std::string("no model at the present pose: ") + err.message;
    return;
  }
  std::unique_ptr<f3r_model, ModelDeleter> model(raw);
  f3r_state_space* ss_raw = nullptr;
  if (f3r_state_space_create(model.get(), &ss_raw, &err) != F3R_OK) {
    res->message = std::string("no linearisation at the present pose: ") + err.message;
    return;
  }
  std::unique_ptr<f3r_state_space, StateSpaceDeleter> ss(ss_raw);
  res->nx = static_cast<uint32_t>(ss->nx);
  res->nu = static_cast<uint32_t>(ss->nu);
  res->ny = static_cast<uint32_t>(ss->ny);
  for (int k = 0; k < ss->nx; ++k) res->state_names.push_back(ss->state_names[k]);
  for (int k = 0; k < ss->nu; ++k) res->input_names.push_back(ss->input_names[k]);
  for (int k = 0; k < ss->ny; ++k) res->output_names.push_back(ss->output_names[k]);
  res->A = RowMajor(ss->A, ss->nx, ss->nx);
  res->B = RowMajor(ss->B, ss->nx, ss->nu);
  res->C = RowMajor(ss->C, ss->ny, ss->nx);
  res->D = RowMajor(ss->D, ss->ny, ss->nu);
  res->x0.assign(ss->x0, ss->x0 + ss->nx);
  res->y0.assign(ss->y0, ss->y0 + ss->ny);
  res->success = true;
  res->message = "about the platform pose at t = " + std::to_string(out.t) + " s, at rest";
}

}  // namespace flex3rpr
