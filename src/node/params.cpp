#include "params.hpp"

#include <cstdio>
#include <cstdlib>

#include <ros/package.h>

#include <cmath>
#include <sstream>
#include <type_traits>
#include <vector>

namespace flex3rpr {

namespace {
const char* TypeName(bool) { return "a boolean"; }
const char* TypeName(double) { return "a number"; }
const char* TypeName(int) { return "an integer"; }
const char* TypeName(const std::string&) { return "a string"; }
}  // namespace

// A parameter, or fallback when it is not set. Set with the wrong type (roscpp's param() would
// silently take the default), it is an error naming it.
template <typename T>
static bool Read(const ros::NodeHandle& pnh, const char* name, const T& fallback, T* out,
                 std::string* error) {
  *out = fallback;
  if (!pnh.hasParam(name)) return true;
  XmlRpc::XmlRpcValue value;
  pnh.getParam(name, value);
  // roscpp would truncate 2.5 to an integer, and take 0 and 1 for booleans: the type must match
  const auto type = value.getType();
  const bool type_ok = (!std::is_same<T, int>::value || type == XmlRpc::XmlRpcValue::TypeInt) &&
                       (!std::is_same<T, bool>::value || type == XmlRpc::XmlRpcValue::TypeBoolean);
  if (type_ok && pnh.getParam(name, *out)) return true;
  *error = std::string("parameter ~") + name + ": not " + TypeName(fallback);
  return false;
}

std::string DefaultScenePath() {
  return ros::package::getPath("flex3rpr") + "/config/scenes/rest.yaml";
}

std::string NormalisePrefix(const std::string& prefix) {
  size_t a = 0, b = prefix.size();
  while (a < b && prefix[a] == '/') ++a;
  while (b > a && prefix[b - 1] == '/') --b;
  return a == b ? "" : prefix.substr(a, b - a) + "/";
}

FrameNames MakeFrameNames(const std::string& prefix, const std::string& world,
                          const std::string& base, int beam_points) {
  FrameNames f;
  f.world = world;
  f.base = base;
  f.platform = prefix + "platform";
  for (int i = 0; i < 3; ++i) {
    const std::string leg = prefix + "leg_" + std::to_string(i + 1) + "_";
    f.cylinder[i] = leg + "cylinder";
    f.piston[i] = leg + "piston";
    f.tip_nominal[i] = leg + "tip_nominal";
    f.platform_c[i] = prefix + "platform_c" + std::to_string(i + 1);
    for (int k = 0; k < beam_points; ++k) f.beam[i].push_back(leg + "beam_" + std::to_string(k));
  }
  return f;
}

namespace {

template <typename T>
bool Positive(const char* name, T value, std::string* error) {
  if (value > 0 && std::isfinite(static_cast<double>(value))) return true;
  std::ostringstream os;
  os << "parameter ~" << name << ": " << value << " must be positive";
  *error = os.str();
  return false;
}

// A tf2 frame id (or, with prefix, a tf_prefix, whose slashes are trimmed): tf2 rejects ids
// that start with '/', and a space or a control character would only fail later, in a lookup.
bool FrameName(const char* name, const std::string& value, std::string* error,
               bool prefix = false) {
  std::string why;
  if (value.empty() && !prefix)
    why = "must not be empty";
  else if (!prefix && value[0] == '/')
    why = "must not start with '/' (tf2 frame ids are relative)";
  for (unsigned char c : value)
    if (c <= ' ' || c == 0x7f) why = "must not contain spaces or control characters";
  if (why.empty()) return true;
  *error = "parameter ~" + std::string(name) + ": '" + value + "' " + why;
  return false;
}

bool NonNegative(const char* name, double value, std::string* error) {
  if (value >= 0 && std::isfinite(value)) return true;
  std::ostringstream os;
  os << "parameter ~" << name << ": " << value << " must be zero or positive";
  *error = os.str();
  return false;
}

// ~base_pose: [x, y, yaw], numbers (integers too), finite; absent: the identity.
bool ReadBasePose(const ros::NodeHandle& pnh, std::array<double, 3>* pose, std::string* error) {
  pose->fill(0.0);
  if (!pnh.hasParam("base_pose")) return true;
  XmlRpc::XmlRpcValue value;
  pnh.getParam("base_pose", value);
  const char* why = nullptr;
  if (value.getType() != XmlRpc::XmlRpcValue::TypeArray || value.size() != 3)
    why = "not a list of 3 numbers";
  for (int k = 0; !why && k < 3; ++k) {
    XmlRpc::XmlRpcValue& v = value[k];
    if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble)
      (*pose)[static_cast<size_t>(k)] = static_cast<double>(v);
    else if (v.getType() == XmlRpc::XmlRpcValue::TypeInt)
      (*pose)[static_cast<size_t>(k)] = static_cast<int>(v);
    else
      why = "not a list of 3 numbers";
    if (!why && !std::isfinite((*pose)[static_cast<size_t>(k)]))
      why = "holds a value that is not finite";
  }
  if (!why) return true;
  *error =
      std::string("parameter ~base_pose: ") + why + " [x (m), y (m), yaw (rad)] of base in world";
  return false;
}

// A parameter that sets a scene field, as an override "FIELD=VALUE" for the scene loader.
struct SceneOverride {
  std::string param;
  std::string text;
};

// A string as a YAML single-quoted scalar, so that the loader reads it as it is.
std::string Quoted(const std::string& value) {
  std::string out = "'";
  for (char c : value) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

// A number that round-trips.
std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// "x,y,phi" (brackets and spaces allowed) as three finite numbers; false on anything else.
bool ParsePose(std::string text, std::array<double, 3>* pose) {
  for (char& c : text)
    if (c == '[' || c == ']') c = ' ';
  const char* at = text.c_str();
  for (int k = 0; k < 3; ++k) {
    char* end = nullptr;
    const double v = std::strtod(at, &end);
    if (end == at || !std::isfinite(v)) return false;
    (*pose)[static_cast<size_t>(k)] = v;
    at = end;
    while (*at == ' ') ++at;
    if (k < 2 && *at++ != ',') return false;
  }
  return *at == '\0';
}

// ~initial_pose: the platform's pose at t = 0, "x,y,phi" (m, m, rad; a string, as roslaunch's
// initial_pose:=x,y,phi gives it) or a list of three numbers: the scene's initial.platform_pose,
// whose range the loader checks. Absent or "": the scene's own.
bool ReadInitialPose(const ros::NodeHandle& pnh, NodeParams* p, std::vector<SceneOverride>* out,
                     std::string* error) {
  p->initial_pose_set = false;
  if (!pnh.hasParam("initial_pose")) return true;
  XmlRpc::XmlRpcValue value;
  pnh.getParam("initial_pose", value);
  std::string text;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeString) {
    text = static_cast<std::string>(value);
  } else if (value.getType() == XmlRpc::XmlRpcValue::TypeArray) {
    for (int k = 0; k < value.size(); ++k) {
      const auto type = value[k].getType();
      if (type != XmlRpc::XmlRpcValue::TypeDouble && type != XmlRpc::XmlRpcValue::TypeInt) {
        text = "?";
        break;
      }
      const double v = type == XmlRpc::XmlRpcValue::TypeInt ? static_cast<int>(value[k])
                                                            : static_cast<double>(value[k]);
      text += (k ? "," : "") + Number(v);
    }
  } else {
    text = "?";
  }
  if (text.find_first_not_of(' ') == std::string::npos) return true;  // "": the scene's
  if (!ParsePose(text, &p->initial_pose)) {
    *error = "parameter ~initial_pose: '" + text +
             "' is not x,y,phi: three finite numbers, the platform's pose at t = 0 (m, m, rad)";
    return false;
  }
  p->initial_pose_set = true;
  const auto& q = p->initial_pose;
  out->push_back({"initial_pose", "initial.platform_pose=[" + Number(q[0]) + ", " + Number(q[1]) +
                                      ", " + Number(q[2]) + "]"});
  return true;
}

// The solver parameters and ~end_stops as overrides of single entries of the scene: the loader
// checks them as it checks the file, and a solver parameter is an explicit setting that the
// accuracy knob keeps, as it would be in the file.
bool ReadSolverParams(const ros::NodeHandle& pnh, NodeParams* p, std::vector<SceneOverride>* out,
                      std::string* error) {
  std::string formulation, integrator, table;
  if (!Read(pnh, "formulation", std::string(), &formulation, error) ||
      !Read(pnh, "integrator", std::string(), &integrator, error) ||
      !Read(pnh, "table", std::string(), &table, error) ||
      !Read(pnh, "end_stops", false, &p->end_stops, error))
    return false;
  if (!formulation.empty())
    out->push_back({"formulation", "solver.formulation=" + Quoted(formulation)});
  if (!integrator.empty())
    out->push_back({"integrator", "solver.integrator=" + Quoted(integrator)});
  if (!table.empty()) out->push_back({"table", "solver.table=" + Quoted(table)});
  // ~verify: the closed-loop check of an accuracy request (the scene's accuracy.verify)
  if (pnh.hasParam("verify")) {
    bool verify = true;
    if (!Read(pnh, "verify", true, &verify, error)) return false;
    out->push_back({"verify", std::string("accuracy.verify=") + (verify ? "true" : "false")});
  }
  // The solver's tolerances, and the command limits, whose home is the scene's limits section.
  const std::pair<const char*, const char*> fields[] = {{"rtol", "solver.rtol"},
                                                        {"atol", "solver.atol"},
                                                        {"max_force", "limits.force"},
                                                        {"max_torque", "limits.torque"},
                                                        {"max_modal_force", "limits.modal_force"}};
  for (const auto& [name, field] : fields) {
    double value = 0.0;
    if (!pnh.hasParam(name)) continue;
    if (!Read(pnh, name, 0.0, &value, error)) return false;
    out->push_back({name, std::string(field) + "=" + Number(value)});
  }
  return true;
}

// ~sensors/NAME/KEY: the scene's sensors.NAME.KEY, as overrides like every other field, so that
// the loader checks names, keys and ranges as it checks the file. Naming a sensor turns it on
// (sensors.NAME.enabled=true first; its own ~sensors/NAME/enabled still wins).
bool ReadSensorParams(const ros::NodeHandle& pnh, std::vector<SceneOverride>* out,
                      std::string* error) {
  XmlRpc::XmlRpcValue all;
  if (!pnh.getParam("sensors", all)) return true;
  // rosrun's _sensors:="{...}" arrives as a string: roscpp parses no YAML mappings
  if (all.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    *error =
        "parameter ~sensors: not a mapping (set it with rosparam or a launch file's <rosparam>)";
    return false;
  }
  for (auto& [sensor, keys] : all) {
    const std::string field = "sensors." + sensor, param = "sensors/" + sensor;
    if (keys.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
      *error = "parameter ~" + param + ": not a mapping of the sensor's keys";
      return false;
    }
    out->push_back({param, field + ".enabled=true"});
    for (auto& [key, value] : keys) {
      std::string text;
      switch (value.getType()) {
        case XmlRpc::XmlRpcValue::TypeBoolean:
          text = static_cast<bool>(value) ? "true" : "false";
          break;
        case XmlRpc::XmlRpcValue::TypeInt: text = std::to_string(static_cast<int>(value)); break;
        case XmlRpc::XmlRpcValue::TypeDouble: text = Number(static_cast<double>(value)); break;
        case XmlRpc::XmlRpcValue::TypeString: text = Quoted(static_cast<std::string>(value)); break;
        default:
          *error = "parameter ~" + param + "/" + key + ": not a number, an integer or a boolean";
          return false;
      }
      out->push_back({param + "/" + key, field + "." + key + "=" + text});
    }
  }
  return true;
}

// ~scene with the overrides, loaded with ~accuracy (m; the scene's accuracy.end_effector when
// 0). An error about an override names its parameter: "parameter ~rtol: solver.rtol: ...".
bool LoadOverridden(NodeParams* p, double accuracy, const std::vector<SceneOverride>& overrides,
                    std::string* error) {
  std::vector<const char*> texts;
  for (const SceneOverride& o : overrides) texts.push_back(o.text.c_str());
  const f3r_scene_options options = {accuracy, texts.data(), static_cast<int>(texts.size())};
  f3r_error err{};
  f3r_scene loaded;
  if (f3r_scene_load_with(p->scene_path.c_str(), &options, &loaded, &err) == F3R_OK) {
    f3r_scene_free(&p->scene);  // a second load (~end_stops) replaces the first, tables and all
    p->scene = loaded;
    return true;
  }
  const std::string message = err.message;
  for (const SceneOverride& o : overrides) {
    const std::string prefix = "--set " + o.text + ": ";
    if (message.compare(0, prefix.size(), prefix) == 0) {
      *error = std::string("parameter ~") + o.param + ": " + message.substr(prefix.size());
      return false;
    }
  }
  *error = "parameter ~scene: " + message;
  return false;
}

// ~scene, with ~accuracy and the solver parameters. ~end_stops (true) makes the scene's stroke
// hard: a file without effects.end_stops gets an empty one (a file with it has hard stops
// already, whose values an override would replace).
bool LoadScene(const ros::NodeHandle& pnh, NodeParams* p, std::string* error) {
  if (!Read(pnh, "scene", DefaultScenePath(), &p->scene_path, error)) return false;
  double accuracy = 0.0;
  if (!Read(pnh, "accuracy", 0.0, &accuracy, error)) return false;
  if (accuracy != 0.0 && !(accuracy >= 1e-9 && accuracy <= 1.0)) {
    std::ostringstream os;
    os << "parameter ~accuracy: " << accuracy << " is out of range 1e-09..1 (m; 0 for the scene's)";
    *error = os.str();
    return false;
  }
  std::vector<SceneOverride> overrides;
  if (!ReadSolverParams(pnh, p, &overrides, error) || !ReadInitialPose(pnh, p, &overrides, error) ||
      !ReadSensorParams(pnh, &overrides, error) || !LoadOverridden(p, accuracy, overrides, error))
    return false;
  if (!p->end_stops || p->scene.end_stops) return true;
  overrides.push_back({"end_stops", "effects.end_stops={}"});
  return LoadOverridden(p, accuracy, overrides, error);
}

// Opens the session on the (validated) scene: the accuracy knob fixes what the scene left open
// (commands are held from publish time to publish time, so its relation is the commanded one and
// its model is sized for accuracy.excitation), and the closed-loop check, when the scene asks for
// one, is left to the node's own thread. The node's scene becomes the resolved one.
bool ResolveScene(NodeParams* p, std::string* error) {
  f3r_error err{};
  f3r_session_options options{};
  options.commanded = 1;
  options.measure_apart = 1;
  if (f3r_session_open_scene(&p->scene, &options, &p->session, &err) != F3R_OK) {
    // ~initial_pose when it set the pose the error is about (one the legs cannot reach, or
    // beyond the end stops), else the scene
    const std::string message = err.message;
    const bool about_pose = message.find("initial.platform_pose") != std::string::npos ||
                            message.find("pose (") != std::string::npos;
    *error = (p->initial_pose_set && about_pose ? "parameter ~initial_pose" : p->scene_path) +
             ": " + message;
    return false;
  }
  f3r_scene resolved = f3r_default_scene();
  if (f3r_scene_copy(&resolved, f3r_session_scene(p->session), &err) != F3R_OK) {
    *error = err.message;
    return false;
  }
  f3r_scene_free(&p->scene);
  p->scene = resolved;
  p->accuracy = *f3r_session_choice(p->session);
  p->settings = f3r_solver_settings_from_scene(&p->scene);
  p->settings.stop_at_outputs = 1;  // commands take effect exactly at publish times
  return true;
}

// Rates, queues, limits, frames' names and the base pose, read and range-checked.
bool ReadRunParams(const ros::NodeHandle& pnh, NodeParams* p, std::string* error) {
  const bool read =
      Read(pnh, "publish_rate", 1000.0, &p->publish_rate, error) &&
      Read(pnh, "beam_points", p->scene.beam_points, &p->beam_points, error) &&
      Read(pnh, "realtime_factor", 1.0, &p->realtime_factor, error) &&
      Read(pnh, "tf_prefix", std::string(), &p->tf_prefix, error) &&
      Read(pnh, "world_frame", std::string("world"), &p->world_frame, error) &&
      Read(pnh, "base_frame", NormalisePrefix(p->tf_prefix) + "base", &p->base_frame, error) &&
      Read(pnh, "paused", false, &p->start_paused, error) &&
      Read(pnh, "command_timeout", 0.0, &p->command_timeout, error) &&
      Read(pnh, "duration", 0.0, &p->duration, error) &&
      Read(pnh, "wait_for_subscribers", 0, &p->wait_for_subscribers, error) &&
      Read(pnh, "subscriber_timeout", 30.0, &p->subscriber_timeout, error) &&
      Read(pnh, "subscriber_grace", 0.5, &p->subscriber_grace, error) &&
      Read(pnh, "queue_size", 10, &p->queue_size, error) &&
      Read(pnh, "command_queue_size", 1000, &p->command_queue_size, error) &&
      Read(pnh, "beam_marker_exaggeration", 1.0, &p->beam_marker_exaggeration, error) &&
      Read(pnh, "lockstep", false, &p->lockstep, error) &&
      Read(pnh, "lockstep_warn_after", 2.0, &p->lockstep_warn_after, error) &&
      ReadBasePose(pnh, &p->base_pose, error);
  if (!read) return false;
  if (p->duration < 0.0) p->duration = p->scene.duration;  // the scene's run.duration
  if (!Positive("publish_rate", p->publish_rate, error) ||
      !Positive("beam_points", p->beam_points, error) ||
      !NonNegative("realtime_factor", p->realtime_factor, error) ||
      !NonNegative("command_timeout", p->command_timeout, error) ||
      !NonNegative("duration", p->duration, error) ||
      !NonNegative("wait_for_subscribers", p->wait_for_subscribers, error) ||
      !Positive("subscriber_timeout", p->subscriber_timeout, error) ||
      !NonNegative("subscriber_grace", p->subscriber_grace, error) ||
      !Positive("queue_size", p->queue_size, error) ||
      !Positive("command_queue_size", p->command_queue_size, error) ||
      !Positive("beam_marker_exaggeration", p->beam_marker_exaggeration, error) ||
      !Positive("lockstep_warn_after", p->lockstep_warn_after, error))
    return false;
  if (p->beam_points < 2 || p->beam_points > 101) {
    *error =
        "parameter ~beam_points: " + std::to_string(p->beam_points) + " is out of range 2..101";
    return false;
  }
  return true;
}

// The frame names read by ReadRunParams, checked, and every frame the node publishes.
bool MakeFrames(NodeParams* p, std::string* error) {
  if (!FrameName("tf_prefix", p->tf_prefix, error, true) ||
      !FrameName("world_frame", p->world_frame, error) ||
      !FrameName("base_frame", p->base_frame, error))
    return false;
  p->tf_prefix = NormalisePrefix(p->tf_prefix);
  p->frames = MakeFrameNames(p->tf_prefix, p->world_frame, p->base_frame, p->beam_points);
  if (p->base_frame == p->world_frame && p->base_pose != std::array<double, 3>{}) {
    *error = "parameter ~base_pose: the base frame is the world frame ('" + p->world_frame +
             "'), so it cannot stand elsewhere; give a ~tf_prefix or a ~base_frame of its own";
    return false;
  }
  return true;
}

// One clock: stamps follow /use_sim_time (simulated time, with /clock from this node, as
// gazebo_ros does), unless ~stamps says otherwise.
bool ReadClock(const ros::NodeHandle& pnh, NodeParams* p, std::string* error) {
  bool use_sim_time = false;
  if (ros::param::has("/use_sim_time")) {
    XmlRpc::XmlRpcValue value;
    ros::param::get("/use_sim_time", value);
    if (value.getType() != XmlRpc::XmlRpcValue::TypeBoolean) {
      *error = "parameter /use_sim_time: not a boolean";
      return false;
    }
    use_sim_time = static_cast<bool>(value);
  }
  std::string stamps;
  if (!Read(pnh, "stamps", std::string(use_sim_time ? "sim" : "wall"), &stamps, error) ||
      !Read(pnh, "publish_clock", use_sim_time, &p->publish_clock, error))
    return false;
  if (stamps != "sim" && stamps != "wall") {
    *error = "parameter ~stamps: '" + stamps + "' is not one of sim, wall";
    return false;
  }
  p->sim_stamps = stamps == "sim";
  if (p->publish_clock && !p->sim_stamps) {
    *error = "parameter ~publish_clock: true needs simulated stamps (~stamps: sim)";
    return false;
  }
  return true;
}

}  // namespace

bool LoadParams(const ros::NodeHandle& pnh, NodeParams* p, std::string* error) {
  return LoadScene(pnh, p, error) && ResolveScene(p, error) && ReadRunParams(pnh, p, error) &&
         MakeFrames(p, error) && ReadClock(pnh, p, error);
}

}  // namespace flex3rpr
