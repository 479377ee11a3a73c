#include "closed_loop_verifier.hpp"

#include <cmath>
#include <cstring>

namespace flex3rpr {

ClosedLoopVerifier::ClosedLoopVerifier(f3r_closed_loop_check* check, int nq)
    : check_(check), nq_(nq) {
  if (!check_) return;
  result_.request = f3r_closed_loop_check_request(check_);
  thread_ = std::thread(&ClosedLoopVerifier::Loop, this);
}

ClosedLoopVerifier::~ClosedLoopVerifier() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void ClosedLoopVerifier::Push(Record&& r) {
  if (!check_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (r.kind == Kind::kReset) overflowed_ = false;
    if (r.kind == Kind::kPeriod && overflowed_) return;  // lost already: nothing to check
    if (r.kind == Kind::kPeriod && queue_.size() >= kMaxPending) {
      // the check cannot keep up with the run: give the measurement up rather than grow
      overflowed_ = true;
      queue_.clear();
      r = Record(Kind::kLose);
      r.why = "the check fell " + std::to_string(kMaxPending) +
              " periods behind the run (a richer configuration than the machine can follow "
              "beside it; ~reset starts a new measurement)";
    }
    queue_.push_back(std::move(r));
  }
  wake_.notify_one();
}

void ClosedLoopVerifier::Period(const double* forces, double t, const double xy[2]) {
  Record r(Kind::kPeriod);
  std::memcpy(r.values, forces, static_cast<size_t>(nq_) * sizeof(double));
  r.t = t;
  r.xy[0] = xy[0];
  r.xy[1] = xy[1];
  Push(std::move(r));
}

void ClosedLoopVerifier::SetState(const double pose[3], const double twist[3], bool has_modal) {
  Record r(Kind::kSetState);
  std::memcpy(r.values, pose, 3 * sizeof(double));
  std::memcpy(r.values + 3, twist, 3 * sizeof(double));
  r.has_modal = has_modal;
  Push(std::move(r));
}

void ClosedLoopVerifier::Lose(const std::string& why) {
  Record r(Kind::kLose);
  r.why = why;
  Push(std::move(r));
}

void ClosedLoopVerifier::Reset() { Push(Record(Kind::kReset)); }

void ClosedLoopVerifier::Apply(const Record& r) {
  switch (r.kind) {
    case Kind::kPeriod: f3r_closed_loop_check_period(check_, r.values, r.t, r.xy); break;
    case Kind::kSetState:
      f3r_closed_loop_check_set_state(check_, r.values, r.values + 3, r.has_modal);
      break;
    case Kind::kLose: f3r_closed_loop_check_lose(check_, r.why.c_str()); break;
    case Kind::kReset: {
      f3r_error err{};
      if (f3r_closed_loop_check_reset(check_, &err) != F3R_OK)
        f3r_closed_loop_check_lose(check_, err.message);
      break;
    }
  }
}

void ClosedLoopVerifier::Loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (stop_) return;
    Record r = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    Apply(r);  // the check alone: the loop never touches it
    int met = 0;
    const char* lost = nullptr;
    const double measured = f3r_closed_loop_check_measured(check_, &met, &lost);
    lock.lock();
    result_.measured = measured;
    result_.request_met = met != 0;
    result_.note = lost ? lost : "";
    busy_ = false;
    if (queue_.empty()) idle_.notify_all();
  }
}

ClosedLoopVerifier::Result ClosedLoopVerifier::Read() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Result r = result_;
  r.pending = queue_.size() + (busy_ ? 1 : 0);
  return r;
}

void ClosedLoopVerifier::Drain() const {
  if (!check_) return;
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return stop_ || (queue_.empty() && !busy_); });
}

}  // namespace flex3rpr
