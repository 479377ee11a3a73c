// Paces the simulation to the wall clock at a requested real-time factor and measures what it
// achieves. Pure arithmetic on times passed in, so that stalls can be tested without waiting.
//
// After a stall (the process descheduled, stopped, or a slow stretch), the pacer does not race
// to catch up: once the run is more than kResyncSeconds behind its schedule, the schedule is
// re-anchored at the present, and the lost wall time is simply lost, as Gazebo does when its
// real-time update falls behind.
#pragma once

#include <cstdint>

namespace flex3rpr {

class Pacer {
 public:
  static constexpr double kResyncSeconds = 0.05;  // wall s late that count as a stall
  static constexpr double kWindowSeconds =
      0.5;  // wall s over which the achieved factor is measured
  static constexpr double kBehindFraction =
      0.95;  // achieved below this share of the request: behind

  // requested: simulated seconds per wall second; 0 runs as fast as it can.
  explicit Pacer(double requested) : requested_(requested) {}

  // (Re)anchors the schedule at wall time `wall` and simulated time `sim`: at the start, after a
  // pause or a reset. The achieved factor's window starts again too.
  void Start(double wall, double sim);
  // A period ended at simulated time `sim`, at wall time `wall`. Returns the wall time the loop
  // should sleep until (no later than `wall` when it is late or unpaced).
  double Due(double wall, double sim);

  double requested() const { return requested_; }
  double achieved() const { return achieved_; }  // over the last full window (before one: so far)
  // Paced and the achieved factor of the last window below kBehindFraction of the request.
  bool behind() const { return behind_; }
  double lag() const { return lag_; }            // wall s late at the last period (before a resync)
  uint64_t resyncs() const { return resyncs_; }  // stalls after which the schedule was re-anchored

 private:
  double requested_;
  double anchor_wall_ = 0.0, anchor_sim_ = 0.0;
  double window_wall_ = 0.0, window_sim_ = 0.0;
  double achieved_ = 0.0, lag_ = 0.0;
  bool behind_ = false;
  bool full_window_ = false;
  uint64_t resyncs_ = 0;
};

}  // namespace flex3rpr
