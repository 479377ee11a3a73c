// The session's simulated sensors on their topics (sensor_outputs.hpp).
#include "sensor_outputs.hpp"

#include "flex3rpr/kinds.h"

namespace flex3rpr {

SensorOutputs::SensorOutputs(ros::NodeHandle& pnh, const f3r_sensors* sensors, bool sim_stamps,
                             int queue_size, bool latch)
    : sensors_(sensors), sim_stamps_(sim_stamps) {
  const uint32_t q = static_cast<uint32_t>(queue_size);
  for (int k = 0; sensors && k < f3r_sensor_kind_count(); ++k) {
    const f3r_sensor_reading* r = f3r_sensors_reading(sensors, k);
    if (!r->enabled) continue;
    const f3r_sensor_kind* kind = f3r_sensor_kind_at(k);
    Topic t;
    t.kind = k;
    t.joints = true;
    for (int c = 0; c < kind->channels; ++c) t.joints = t.joints && kind->joint[c];
    if (t.joints) {
      t.pub = pnh.advertise<sensor_msgs::JointState>(kind->topic, q, latch);
      t.joint_state.name.assign(kind->joint, kind->joint + kind->channels);
    } else {
      t.pub = pnh.advertise<SensorReading>(kind->topic, q, latch);
      t.reading.names.assign(kind->column, kind->column + kind->channels);
    }
    topics_.push_back(t);
  }
}

void SensorOutputs::Publish(double t_now) {
  const ros::Time stamp = Stamp(t_now);
  for (Topic& t : topics_) {
    const f3r_sensor_reading* r = f3r_sensors_reading(sensors_, t.kind);
    if (r->updated_at_sample == t.published_sample) continue;
    t.published_sample = r->updated_at_sample;
    if (t.joints) {
      t.joint_state.header.stamp = stamp;
      t.joint_state.position.assign(r->value, r->value + r->channels);
      t.pub.publish(t.joint_state);
      continue;
    }
    t.reading.header.stamp = stamp;
    t.reading.measured_at = ros::Time(r->measured_at);
    t.reading.sample = r->sample;
    t.reading.values.assign(r->value, r->value + r->channels);
    t.pub.publish(t.reading);
  }
}

void SensorOutputs::Reset() {
  for (Topic& t : topics_) t.published_sample = -1;
}

}  // namespace flex3rpr

// SimNode's part (sim_node.hpp): here, beside the sensors it starts.
#include "sim_node.hpp"

namespace flex3rpr {

void SimNode::StartSensors() {
  const f3r_sensors* sensors = f3r_session_sensors(session_);
  sensors_.reset(
      new SensorOutputs(pnh_, sensors, params_.sim_stamps, params_.queue_size, params_.lockstep));
  if (!sensors) return;
  std::string on;
  for (int k = 0; k < f3r_sensor_kind_count(); ++k)
    if (f3r_sensors_reading(sensors, k)->enabled)
      on += (on.empty() ? "" : ", ") + std::string(f3r_sensor_kind_at(k)->name);
  ROS_INFO("flex3rpr_node: sensors: %s (~sensors/NAME/KEY)", on.c_str());
}

}  // namespace flex3rpr
