// The session's simulated sensors (flex3rpr/sensors.h) on their own topics, one per enabled kind
// of the core's table (flex3rpr/kinds.h): ~TOPIC, a sensor_msgs/JointState (positions only) when
// every channel measures a URDF joint (encoders), else a flex3rpr/SensorReading. The core
// samples, adds noise, quantises and delays inside the session's step; the ~sensors/NAME/KEY
// parameters reach the scene as overrides (params.cpp). This only translates.
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <vector>

#include "flex3rpr/SensorReading.h"
#include "flex3rpr/sensors.h"

namespace flex3rpr {

class SensorOutputs {
 public:
  // Advertises a topic per enabled sensor of `sensors` (the session's; NULL: none).
  SensorOutputs(ros::NodeHandle& pnh, const f3r_sensors* sensors, bool sim_stamps, int queue_size,
                bool latch);
  // Publishes the readings that took a sample since the last call, stamped t (the state's).
  void Publish(double t);
  // After ~reset (the session's sensors start over): every reading is new again.
  void Reset();

 private:
  ros::Time Stamp(double t) const {
    return sim_stamps_ ? ros::Time(t) : ros::Time(ros::WallTime::now().toSec());
  }
  struct Topic {
    int kind;
    long published_sample = -1;  // updated_at_sample of the last reading published
    bool joints;                 // a JointState
    ros::Publisher pub;
    sensor_msgs::JointState joint_state;
    SensorReading reading;
  };
  const f3r_sensors* sensors_;
  bool sim_stamps_;
  std::vector<Topic> topics_;
};

}  // namespace flex3rpr
