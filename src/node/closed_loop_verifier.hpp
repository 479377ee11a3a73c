// ~verify: the session's closed-loop check (flex3rpr/closed_loop_check.h) on a thread of its
// own, so that its cost (the check configuration is richer than the run) never slows the
// real-time loop. The loop hands over each period's command and end-effector position; the
// thread steps the check on them in order and keeps the measurement, which the loop reads for
// ~status and /diagnostics. The measurement itself is the core's; this only queues.
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

#include "flex3rpr/closed_loop_check.h"
#include "flex3rpr/model.h"

namespace flex3rpr {

class ClosedLoopVerifier {
 public:
  // check: the session's (NULL without an accuracy request or with ~verify false: inactive).
  ClosedLoopVerifier(f3r_closed_loop_check* check, int nq);
  ~ClosedLoopVerifier();
  ClosedLoopVerifier(const ClosedLoopVerifier&) = delete;
  ClosedLoopVerifier& operator=(const ClosedLoopVerifier&) = delete;

  bool active() const { return check_ != nullptr; }
  // The run held forces (nq) until t and its end-effector reached xy there.
  void Period(const double* forces, double t, const double xy[2]);
  // The run was set to a new state (a modal one ends the measurement).
  void SetState(const double pose[3], const double twist[3], bool has_modal);
  // The measurement ends here, with the reason.
  void Lose(const std::string& why);
  // A new measurement from t = 0.
  void Reset();

  struct Result {
    double measured = 0.0;  // m; NaN once lost
    bool request_met = true;
    std::string note;      // why the measurement was lost, or ""
    double request = 0.0;  // m
    size_t pending = 0;    // periods handed over and not yet checked
  };
  Result Read() const;
  // Blocks until every period handed over is checked (for ~step_with_command's answer and the
  // end of a run).
  void Drain() const;

  // Periods the check may fall behind before the measurement is given up: 60 s of a 1 kHz run
  // (each queued period holds nq forces; a 3-link r = 20 model's is 0.6 kB).
  static constexpr size_t kMaxPending = 60000;

 private:
  enum class Kind { kPeriod, kSetState, kLose, kReset };
  struct Record {
    explicit Record(Kind k) : kind(k) {}
    Kind kind;
    double t = 0.0;
    double values[F3R_MAX_Q] = {};  // forces, or pose and twist
    double xy[2] = {0.0, 0.0};
    bool has_modal = false;
    std::string why;
  };
  void Push(Record&& r);
  void Loop();
  void Apply(const Record& r);

  f3r_closed_loop_check* check_;
  int nq_;
  mutable std::mutex mutex_;
  mutable std::condition_variable wake_, idle_;
  std::deque<Record> queue_;
  bool busy_ = false, stop_ = false, overflowed_ = false;
  Result result_;
  std::thread thread_;
};

}  // namespace flex3rpr
