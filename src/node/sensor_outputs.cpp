// The scene's simulated sensors on their topics (sensor_outputs.hpp).
#include "sensor_outputs.hpp"

#include <stdexcept>

namespace flex3rpr {

namespace {

const char* const kSensorNames[F3R_SENSOR_KINDS] = {"encoders", "strain_gauges", "accelerometer"};
const char* const kTopics[F3R_SENSOR_KINDS] = {"sensors/encoders", "sensors/strain",
                                               "sensors/accelerometer"};
// The parameters of noise[0], noise[1], resolution[0], resolution[1] (as the scene names them).
const char* const kKeys[F3R_SENSOR_KINDS][4] = {
    {"stroke_noise", "angle_noise", "stroke_resolution", "angle_resolution"},
    {"noise", nullptr, "resolution", nullptr},
    {"noise", "gyro_noise", "resolution", "gyro_resolution"}};
const char* const kChannelNames[F3R_SENSOR_KINDS][F3R_SENSOR_MAX_CHANNELS] = {
    {"leg_1_prismatic", "leg_2_prismatic", "leg_3_prismatic", "leg_1_revolute", "leg_2_revolute",
     "leg_3_revolute"},
    {"strain_1", "strain_2", "strain_3"},
    {"accel_x", "accel_y", "gyro_z"}};

f3r_sensor_scene* SensorOf(f3r_sensors_scene* s, int k) {
  return k == 0 ? &s->encoders : k == 1 ? &s->strain_gauges : &s->accelerometer;
}

// A number parameter (int or double) into *out; false when it is set but not a number.
bool ReadNumber(const ros::NodeHandle& pnh, const std::string& name, double* out, bool* given) {
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(name, v)) return true;
  *given = true;
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) {
    *out = static_cast<int>(v);
    return true;
  }
  if (v.getType() != XmlRpc::XmlRpcValue::TypeDouble) return false;
  *out = static_cast<double>(v);
  return true;
}

bool ReadSensor(const ros::NodeHandle& pnh, int k, f3r_sensor_scene* s, std::string* error) {
  const std::string base = std::string("sensors/") + kSensorNames[k] + "/";
  if (!pnh.hasParam(std::string("sensors/") + kSensorNames[k])) return true;
  if (!s->enabled) f3r_sensor_scene_defaults(s);  // named: on, from the defaults
  const char* ints[2] = {"delay", "seed"};
  int* int_targets[2] = {&s->delay, &s->seed};
  for (int j = 0; j < 2; ++j) {
    XmlRpc::XmlRpcValue v;
    if (!pnh.getParam(base + ints[j], v)) continue;
    if (v.getType() != XmlRpc::XmlRpcValue::TypeInt) {
      *error = "parameter ~" + base + ints[j] + ": not an integer";
      return false;
    }
    *int_targets[j] = static_cast<int>(v);
  }
  bool given = false;
  if (!ReadNumber(pnh, base + "rate", &s->rate, &given)) {
    *error = "parameter ~" + base + "rate: not a number";
    return false;
  }
  for (int j = 0; j < 4; ++j) {
    if (!kKeys[k][j]) continue;
    double* target = j < 2 ? &s->noise[j] : &s->resolution[j - 2];
    if (!ReadNumber(pnh, base + kKeys[k][j], target, &given)) {
      *error = "parameter ~" + base + kKeys[k][j] + ": not a number";
      return false;
    }
  }
  XmlRpc::XmlRpcValue v;
  if (pnh.getParam(base + "enabled", v)) {
    if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean) {
      *error = "parameter ~" + base + "enabled: not a boolean";
      return false;
    }
    s->enabled = static_cast<bool>(v) ? 1 : 0;
  }
  return true;
}

}  // namespace

bool LoadSensorParams(const ros::NodeHandle& pnh, f3r_sensors_scene* sensors, std::string* error) {
  // rosrun's _sensors:="{...}" arrives as a string: roscpp parses no YAML mappings
  XmlRpc::XmlRpcValue all;
  if (pnh.getParam("sensors", all) && all.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    *error =
        "parameter ~sensors: not a mapping (set it with rosparam or a launch file's <rosparam>)";
    return false;
  }
  for (int k = 0; k < F3R_SENSOR_KINDS; ++k)
    if (!ReadSensor(pnh, k, SensorOf(sensors, k), error)) return false;
  f3r_error err{};
  if (f3r_sensors_scene_validate(sensors, &err) != F3R_OK) {
    *error = std::string("parameter ~") + err.message;
    return false;
  }
  return true;
}

SensorOutputs::SensorOutputs(ros::NodeHandle& pnh, const f3r_model& model,
                             const f3r_sensors_scene& config, bool sim_stamps, int queue_size,
                             bool latch)
    : sim_stamps_(sim_stamps) {
  if (!f3r_sensors_any(&config)) return;
  f3r_sensors* raw = nullptr;
  f3r_error err{};
  if (f3r_sensors_create(&model, &config, &raw, &err) != F3R_OK)
    throw std::runtime_error(err.message);
  sensors_.reset(raw);
  const uint32_t q = static_cast<uint32_t>(queue_size);
  for (int k = 0; k < F3R_SENSOR_KINDS; ++k) {
    const f3r_sensor_reading* r = f3r_sensors_reading(raw, k);
    if (!r->enabled) continue;
    if (k == F3R_SENSOR_ENCODERS) {
      pub_[k] = pnh.advertise<sensor_msgs::JointState>(kTopics[k], q, latch);
      encoders_.name.assign(kChannelNames[k], kChannelNames[k] + r->channels);
      encoders_.position.assign(static_cast<size_t>(r->channels), 0.0);
    } else {
      pub_[k] = pnh.advertise<SensorReading>(kTopics[k], q, latch);
      reading_[k].names.assign(kChannelNames[k], kChannelNames[k] + r->channels);
      reading_[k].values.assign(static_cast<size_t>(r->channels), 0.0);
    }
  }
}

bool SensorOutputs::Update(const f3r_outputs& out, std::string* error) {
  if (!sensors_) return true;
  f3r_error err{};
  if (f3r_sensors_update(sensors_.get(), &out, &err) != F3R_OK) {
    *error = err.message;
    return false;
  }
  const ros::Time stamp = Stamp(out.t);
  for (int k = 0; k < F3R_SENSOR_KINDS; ++k) {
    const f3r_sensor_reading* r = f3r_sensors_reading(sensors_.get(), k);
    if (!r->enabled || !r->fresh) continue;
    if (k == F3R_SENSOR_ENCODERS) {
      encoders_.header.stamp = stamp;
      encoders_.position.assign(r->value, r->value + r->channels);
      pub_[k].publish(encoders_);
      continue;
    }
    SensorReading& m = reading_[k];
    m.header.stamp = stamp;
    m.measured_at = ros::Time(r->measured_at);
    m.sample = r->sample;
    m.values.assign(r->value, r->value + r->channels);
    pub_[k].publish(m);
  }
  return true;
}

}  // namespace flex3rpr

// SimNode's part (sim_node.hpp): here, beside the sensors it starts.
#include "sim_node.hpp"

namespace flex3rpr {

bool SimNode::StartSensors() {
  f3r_sensors_scene config = params_.scene.sensors;
  std::string error;
  if (!LoadSensorParams(pnh_, &config, &error)) {
    ROS_ERROR("flex3rpr_node: %s", error.c_str());
    return false;
  }
  try {
    sensors_.reset(new SensorOutputs(pnh_, *model_, config, params_.sim_stamps, params_.queue_size,
                                     params_.lockstep));
  } catch (const std::exception& e) {
    ROS_ERROR("flex3rpr_node: sensors: %s", e.what());
    return false;
  }
  if (f3r_sensors_any(&config))
    ROS_INFO(
        "flex3rpr_node: sensors: encoders %s, strain gauges %s, accelerometer %s (~sensors/...)",
        config.encoders.enabled ? "on" : "off", config.strain_gauges.enabled ? "on" : "off",
        config.accelerometer.enabled ? "on" : "off");
  return true;
}

}  // namespace flex3rpr
