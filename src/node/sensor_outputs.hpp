// The scene's simulated sensors (flex3rpr/sensors.h) on their own topics: ~sensors/encoders
// (sensor_msgs/JointState, positions only), ~sensors/strain and ~sensors/accelerometer
// (flex3rpr/SensorReading). The core samples, adds noise, quantises and delays; this only
// translates. Parameters ~sensors/<sensor>/<key> override the scene's sensors section.
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <memory>
#include <string>

#include "flex3rpr/SensorReading.h"
#include "flex3rpr/sensors.h"

namespace flex3rpr {

struct SensorsDeleter {
  void operator()(f3r_sensors* s) const { f3r_sensors_destroy(s); }
};

// The scene's sensors with the ~sensors/... parameters applied; false with a message naming
// the parameter (or the scene field out of range).
bool LoadSensorParams(const ros::NodeHandle& pnh, f3r_sensors_scene* sensors, std::string* error);

class SensorOutputs {
 public:
  // Nothing is advertised when no sensor is enabled. Throws std::runtime_error on a core error.
  SensorOutputs(ros::NodeHandle& pnh, const f3r_model& model, const f3r_sensors_scene& config,
                bool sim_stamps, int queue_size, bool latch);
  // Takes the samples due at out and publishes the readings that are new. Returns false with
  // error set when the core refuses (time went back without Reset).
  bool Update(const f3r_outputs& out, std::string* error);
  // Forgets the samples (~reset).
  void Reset() {
    if (sensors_) f3r_sensors_reset(sensors_.get());
  }

 private:
  ros::Time Stamp(double t) const {
    return sim_stamps_ ? ros::Time(t) : ros::Time(ros::WallTime::now().toSec());
  }
  std::unique_ptr<f3r_sensors, SensorsDeleter> sensors_;
  bool sim_stamps_;
  ros::Publisher pub_[F3R_SENSOR_KINDS];
  sensor_msgs::JointState encoders_;
  SensorReading reading_[F3R_SENSOR_KINDS];
};

}  // namespace flex3rpr
