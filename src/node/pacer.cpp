#include "pacer.hpp"

namespace flex3rpr {

void Pacer::Start(double wall, double sim) {
  anchor_wall_ = window_wall_ = wall;
  anchor_sim_ = window_sim_ = sim;
  lag_ = 0.0;
}

double Pacer::Due(double wall, double sim) {
  if (wall - window_wall_ >= kWindowSeconds) {
    achieved_ = (sim - window_sim_) / (wall - window_wall_);
    behind_ = requested_ > 0.0 && achieved_ < kBehindFraction * requested_;
    window_wall_ = wall;
    window_sim_ = sim;
    full_window_ = true;
  } else if (!full_window_ && wall > window_wall_) {  // an estimate until the first window is full
    achieved_ = (sim - window_sim_) / (wall - window_wall_);
  }
  if (requested_ <= 0.0) return wall;
  const double due = anchor_wall_ + (sim - anchor_sim_) / requested_;
  lag_ = wall > due ? wall - due : 0.0;
  if (lag_ > kResyncSeconds) {  // a stall: start the schedule again from here instead of racing
    anchor_wall_ = wall;
    anchor_sim_ = sim;
    ++resyncs_;
    return wall;
  }
  return due;
}

}  // namespace flex3rpr
