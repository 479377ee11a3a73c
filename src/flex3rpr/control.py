"""What the example controllers (nodes/pd_controller, nodes/lqr_controller) share: the scene
as `flex3rpr.Sim` loads and checks it (its home pose, stroke, the legs' joints of a pose through the
core's loop closure, its linear plant, the root strain gauges' rows, the sensors as the node has
them), a discrete LQR and a steady-state Kalman filter designed on that plant, and the lockstep
plumbing. Nothing here models the robot: every physical quantity comes from the core.

Lockstep (flex3rpr_node ~lockstep): the node publishes the state at t_k (joint_states, ~odom,
~beam_state, ~status, latched) and integrates [t_k, t_k+1] only after the next command arrives,
applying it over that period. So a controller answers every state it receives with exactly one
command, and a controller that reads several topics answers once it holds all of them with the
same stamp. `LockstepLoop` does that: it gathers joint_states, ~odom and ~beam_state by stamp,
waits until the node is connected to its command publisher before answering the first state,
calls `control(state)` every `decimation`-th state and resends the held command on the others,
and logs every state it answered (repr-exact floats) to a CSV.
"""
import csv
import json
import math
import os
import queue
import threading
import time

import numpy as np

import flex3rpr

JOINTS_RHO = ["leg_%d_prismatic" % (i + 1) for i in range(3)]
JOINTS_THETA = ["leg_%d_revolute" % (i + 1) for i in range(3)]


# ---- the scene, through flex3rpr.Sim -----------------------------------------------------------
def scene_overrides(value, name="~set"):
    """Scene overrides as flex3rpr_sim's --set gives them: "FIELD=VALUE" strings (a list, or
    one string), in order (a later one of the same field wins); None, "" or []: none. Returns
    the overrides for flex3rpr.Sim."""
    if value in (None, "", []):
        return {}
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, (list, tuple)):
        raise ValueError("%s: a list of FIELD=VALUE strings expected, got %r" % (name, value))
    out = {}
    for item in items:
        field, sep, text = str(item).partition("=")
        if not sep or not field.strip():
            raise ValueError("%s: %r is not FIELD=VALUE (as flex3rpr_sim --set)" % (name, item))
        out.pop(field.strip(), None)
        out[field.strip()] = text.strip()
    return out


def sensor_overrides(params, name="~sensors"):
    """The node's ~sensors parameters ({encoders: {delay: 1, ...}, strain_gauges: {...}}) as scene
    overrides, field by field over the scene's sensors section, as the node applies them: a
    sensor named is on (from the defaults where the scene has none)."""
    out = {}
    if not params:
        return out
    if not isinstance(params, dict):
        raise ValueError("%s: not a mapping: %r" % (name, params))
    for sensor, fields in params.items():
        if not isinstance(fields, dict):
            raise ValueError("%s/%s: not a mapping: %r" % (name, sensor, fields))
        for key, value in fields.items():
            out["sensors.%s.%s" % (sensor, key)] = value
    return out


def open_scene(scene, overrides=None):
    """flex3rpr.Sim of the scene with the overrides: checked as the node and the CLI check it
    (flex3rpr.SceneError names the file or override, the field and the allowed range)."""
    return flex3rpr.Sim(scene, overrides=overrides or {})


def home_pose(sim):
    """The scene's initial platform pose (x, y, phi)."""
    return tuple(float(v) for v in sim.state.pose)


def stroke(sim):
    """The stroke's limits (stroke_min, stroke_max) of rho_i, m."""
    g = sim.geometry
    return g["stroke_min"], g["stroke_max"]


def leg_joints(sim, pose, modal=None):
    """Strokes rho_i and leg directions theta_i of the platform pose (x, y, phi) with the links
    deflected by modal (the model's modal coordinates; None: straight), by the core's loop
    closure. flex3rpr.Error for a pose the legs cannot reach."""
    q = sim.close_loops(pose, modal)
    return [float(v) for v in q[0:3]], [float(v) for v in q[3:6]]


def wrap(angle):
    """angle in (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def parse_pose(value, home):
    """~target_pose: a list [x, y, phi] or a string "x y phi" / "x,y,phi"; empty: home + 1 cm in x."""
    if value in (None, "", []):
        return (home[0] + 0.01, home[1], home[2])
    if isinstance(value, str):
        value = [float(v) for v in value.replace(",", " ").replace("[", " ").replace("]", " ").split()]
    value = [float(v) for v in value]
    if len(value) != 3 or not all(math.isfinite(v) for v in value):
        raise ValueError("target_pose must be three finite numbers [x, y, phi], got %r" % (value,))
    return tuple(value)


def node_arguments(doc):
    """A controller node's command line: --help prints its docstring; the ROS remappings and
    roslaunch's __name:=, __log:= arguments pass (rospy.myargv takes them out)."""
    import argparse
    import rospy
    parts = doc.split("\n\n")
    ap = argparse.ArgumentParser(description=parts[0], epilog="\n\n".join(parts[1:]),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    return ap.parse_args(rospy.myargv()[1:])


# ---- the linear plant ----------------------------------------------------------------------------
def load_plant(path):
    """A plant file as `flex3rpr_sim --linearise` writes it: the JSON beside a .mat (or the .mat
    through scipy.io.loadmat, or a JSON given directly). Returns a dict of numpy arrays and name
    lists, as flex3rpr.Sim.linearise()."""
    root, ext = os.path.splitext(path)
    json_path = path if ext == ".json" else root + ".json"
    plant = {}
    if os.path.exists(json_path):
        with open(json_path) as fh:
            plant = json.load(fh)
    if ext == ".mat":
        import scipy.io
        mat = scipy.io.loadmat(path)
        for key in ("A", "B", "C", "D", "x0", "y0"):
            if key in mat:
                plant[key] = mat[key]
    missing = [k for k in ("A", "B", "state_names", "input_names") if k not in plant]
    if missing:
        raise ValueError("%s: the plant lacks %s" % (path, ", ".join(missing)))
    out = {k: np.atleast_2d(np.asarray(plant[k], dtype=float)) for k in ("A", "B", "C", "D") if k in plant}
    for k in ("x0", "y0"):
        if k in plant:
            out[k] = np.asarray(plant[k], dtype=float).ravel()
    for k in ("state_names", "input_names", "output_names"):
        if k in plant:
            out[k] = [str(v).strip() for v in plant[k]]
    nx = out["A"].shape[0]
    if out["A"].shape != (nx, nx) or out["B"].shape[0] != nx or len(out["state_names"]) != nx:
        raise ValueError("%s: A is %s, B %s, %d state names" % (path, out["A"].shape, out["B"].shape,
                                                                len(out["state_names"])))
    return out


def complete_plant(plant, sim, label="the plant"):
    """A loaded plant without outputs (C, y0, output_names) gets the scene's, the same states
    required: the tip deflections' rows and the encoders' come from the core's linearisation."""
    if "C" in plant and "output_names" in plant and "y0" in plant:
        return plant
    own = sim.linearise()
    if own["state_names"] != plant["state_names"]:
        raise ValueError("%s has no outputs (C, y0, output_names) and its states are not the scene's "
                         "(%s against %s)" % (label, plant["state_names"], own["state_names"]))
    out = dict(plant)
    for key in ("C", "D", "y0", "output_names"):
        out[key] = own[key]
    return out


def modal_states(plant, sim):
    """The plant's state indices of the model's modal coordinates eta_i_j, in State.modal's order
    (link 1's, then 2's, then 3's); ValueError when the plant's modal states are not the model's."""
    names = plant["state_names"]
    want = ["eta_%d_%d" % (i + 1, j + 1) for i in range(3) for j in range(sim.modes[i])]
    have = [n for n in names if n.startswith("eta_") and not n.endswith("_rate")]
    if sorted(have) != sorted(want):
        raise ValueError("the plant's modal states %s are not the scene's model's %s (modes %s)"
                         % (have, want, sim.modes))
    return [names.index(n) for n in want]


def discretise(A, B, dt):
    """Zero-order hold: the command is held over each period, as lockstep applies it."""
    import scipy.linalg
    nx, nu = B.shape
    M = np.zeros((nx + nu, nx + nu))
    M[:nx, :nx], M[:nx, nx:] = A * dt, B * dt
    E = scipy.linalg.expm(M)
    return E[:nx, :nx], E[:nx, nx:]


def tip_rows(plant):
    """The tip deflections' rows over the state: the plant's C rows tip_deflection_1..3 (a loaded
    plant without them: complete_plant first)."""
    names = plant.get("output_names", [])
    want = ["tip_deflection_%d" % (i + 1) for i in range(3)]
    if "C" not in plant or not all(n in names for n in want):
        raise ValueError("the plant has no C rows %s (complete_plant gives it the scene's)" % ", ".join(want))
    return np.vstack([plant["C"][names.index(n)] for n in want])


def lqr_design(plant, dt, pose_scale=(0.01, 0.01, 0.03), rate_scale=(0.3, 0.3, 1.0), tip_scale=1e-6,
               force_scale=1.0, torque_scale=0.03):
    """Discrete LQR on the zero-order-hold plant (the command is held over each period, as
    lockstep applies it): J = sum x'Qx + u'Ru, weights by Bryson's rule (1 / scale^2): the pose
    errors (x_p, y_p, phi_p) and their rates, the tip deflections C_tip x (this is what damps the
    links' vibration: tip_scale 1 um), the leg forces and the cylinder torques.
    Returns the gain K (u = u_ff - K (x - x_target)) and the discrete plant (Ad, Bd)."""
    import scipy.linalg
    A, B = plant["A"], plant["B"]
    nx, nu = B.shape
    names = plant["state_names"]
    Q = np.zeros((nx, nx))
    for k, s in enumerate(("x_p", "y_p", "phi_p")):
        Q[names.index(s), names.index(s)] += pose_scale[k] ** -2
        Q[names.index(s + "_rate"), names.index(s + "_rate")] += rate_scale[k] ** -2
    T = tip_rows(plant)
    Q += T.T @ T / tip_scale ** 2
    R = np.diag([force_scale ** -2 if n.startswith("leg_force") else torque_scale ** -2
                 for n in plant["input_names"]])
    Ad, Bd = discretise(A, B, dt)
    P = scipy.linalg.solve_discrete_are(Ad, Bd, Q, R)
    K = np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    return K, Ad, Bd


def gauge_rows(plant, sim):
    """The root strain gauges' rows over the plant's state (docs/scenes.md, sensors): eps_i =
    (d/2) w_i''(0), the core's rows over the modal coordinates (flex3rpr.Sim.strain_rows,
    f3r_sensors_strain_row: static shapes included) placed at the plant's eta states."""
    rows = np.zeros((3, plant["A"].shape[0]))
    rows[:, modal_states(plant, sim)] = sim.strain_rows()
    return rows


def kalman_predictor(Ad, Bd, groups, process, noise):
    """A steady-state Kalman filter for measurements y_g,k = C_g x_{k - d_g} + v (groups: a list
    of (C_g, d_g), d_g the sensor's delay in periods): the state is augmented with the delay's
    past states, xi = (x_k, x_{k-1}, ..., x_{k-max d}). process: the covariance of the plant's
    disturbance per period (nx x nx); noise: the measurements' (ny x ny), in the groups' order.
    Returns (Aa, Ba, Ca, L): predict xi- = Aa xi + Ba u, correct xi = xi- + L (y - Ca xi-)."""
    import scipy.linalg
    nx, nu = Bd.shape
    delay = max(d for _, d in groups)
    n = nx * (delay + 1)
    ny = sum(C.shape[0] for C, _ in groups)
    Aa, Ba, Ca = np.zeros((n, n)), np.zeros((n, nu)), np.zeros((ny, n))
    Aa[:nx, :nx], Ba[:nx] = Ad, Bd
    for k in range(delay):
        Aa[(k + 1) * nx:(k + 2) * nx, k * nx:(k + 1) * nx] = np.eye(nx)
    row = 0
    for C, d in groups:
        Ca[row:row + C.shape[0], d * nx:(d + 1) * nx] = C
        row += C.shape[0]
    Qa = np.zeros((n, n))
    Qa[:nx, :nx] = process
    Qa += 1e-30 * np.eye(n)  # the copies carry no noise of their own; keep the Riccati regular
    P = scipy.linalg.solve_discrete_are(Aa.T, Ca.T, Qa, noise)
    L = P @ Ca.T @ np.linalg.inv(Ca @ P @ Ca.T + noise)
    return Aa, Ba, Ca, L


def feedforward(plant, x_target):
    """u_ff holding the target state: the least-squares solution of A x + B u = 0 (zero where the
    target is an equilibrium without force, as a pose of the unloaded rest scene is)."""
    A, B = plant["A"], plant["B"]
    u, *_ = np.linalg.lstsq(B, -A @ x_target, rcond=None)
    return u


def input_order(plant):
    """Positions of leg_force_1..3 and cylinder_torque_1..3 in the plant's inputs."""
    names = plant["input_names"]
    return ([names.index("leg_force_%d" % (i + 1)) for i in range(3)],
            [names.index("cylinder_torque_%d" % (i + 1)) for i in range(3)])


# ---- the state a controller sees -----------------------------------------------------------------
class State:
    """One period's state, from joint_states, ~odom and ~beam_state of one stamp."""
    __slots__ = ("stamp", "rho", "rho_dot", "theta", "theta_dot", "pose", "pose_rate", "modal",
                 "modal_rate", "tip", "tip_rate", "sensors")

    @staticmethod
    def from_messages(js, odom, beam):
        s = State()
        s.stamp = js.header.stamp
        idx = {n: k for k, n in enumerate(js.name)}
        s.rho = [js.position[idx[n]] for n in JOINTS_RHO]
        s.rho_dot = [js.velocity[idx[n]] for n in JOINTS_RHO]
        s.theta = [js.position[idx[n]] for n in JOINTS_THETA]
        s.theta_dot = [js.velocity[idx[n]] for n in JOINTS_THETA]
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        phi = 2.0 * math.atan2(q.z, q.w)
        s.pose = [p.x, p.y, phi]
        # the twist is in the platform (child) frame: turn it into world rates
        v, w = odom.twist.twist.linear, odom.twist.twist.angular
        c, sn = math.cos(phi), math.sin(phi)
        s.pose_rate = [c * v.x - sn * v.y, sn * v.x + c * v.y, w.z]
        s.modal = list(beam.modal)
        s.modal_rate = list(beam.modal_rate)
        s.tip = list(beam.tip_deflection)
        s.tip_rate = list(beam.tip_deflection_rate)
        return s


LOG_COLUMNS = (["t"] + ["rho_%d" % i for i in (1, 2, 3)] + ["theta_%d" % i for i in (1, 2, 3)]
               + ["rho_%d_dot" % i for i in (1, 2, 3)] + ["theta_%d_dot" % i for i in (1, 2, 3)]
               + ["x_p", "y_p", "phi_p"] + ["w_tip_%d" % i for i in (1, 2, 3)]
               + ["leg_force_%d" % i for i in (1, 2, 3)] + ["cylinder_torque_%d" % i for i in (1, 2, 3)])


def log_row(state, command):
    """A CSV row: floats as repr (exact round trip), the stamp as sec.nsec."""
    t = "%d.%09d" % (state.stamp.secs, state.stamp.nsecs)
    vals = (state.rho + state.theta + state.rho_dot + state.theta_dot + state.pose + state.tip
            + list(command[0]) + list(command[1]))
    return [t] + [repr(float(v)) for v in vals]


def read_log(path):
    """A controller's log as a dict of numpy columns."""
    with open(path) as fh:
        rows = list(csv.reader(fh))
    head, body = rows[0], rows[1:]
    return {h: np.array([float(r[k]) for r in body]) for k, h in enumerate(head)}


# ---- the lockstep loop ---------------------------------------------------------------------------
class LockstepLoop:
    """Answers every state of flex3rpr_node with one EffortCommand (see the module docstring).

    control(state) -> (leg_force[3], cylinder_torque[3]) is called every `decimation`-th state;
    the states between get the held command again."""

    def __init__(self, control, node="flex3rpr_node", decimation=1, log_path="", name="controller",
                 sensors=False):
        import rospy
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import JointState
        from flex3rpr.msg import BeamState, EffortCommand
        self.rospy, self.EffortCommand = rospy, EffortCommand
        self.control, self.decimation, self.name = control, max(1, int(decimation)), name
        self.lock = threading.Lock()
        self.pending = {}            # stamp (ns) -> {topic: msg}
        self.ready = queue.Queue()   # complete sets, in stamp order
        self.last_stamp = None       # the last stamp answered (ns)
        self.answered = 0
        self.held = ([0.0] * 3, [0.0] * 3)
        self.log_path = log_path
        self.log = None
        if log_path:
            d = os.path.dirname(os.path.abspath(log_path))
            os.makedirs(d, exist_ok=True)
            self.log_file = open(log_path, "w", newline="")
            self.log = csv.writer(self.log_file)
            self.log.writerow(LOG_COLUMNS)
        base = node.rstrip("/")
        self.pub = rospy.Publisher(base + "/command", EffortCommand, queue_size=100, tcp_nodelay=True)
        opts = dict(queue_size=None, tcp_nodelay=True)
        rospy.Subscriber("joint_states", JointState, self._got, "joint_states", **opts)
        rospy.Subscriber(base + "/odom", Odometry, self._got, "odom", **opts)
        rospy.Subscriber(base + "/beam_state", BeamState, self._got, "beam", **opts)
        self.topics = 3
        if sensors:  # the encoders and strain gauges of the node's scene, one reading a period
            from flex3rpr.msg import SensorReading
            rospy.Subscriber(base + "/sensors/encoders", JointState, self._got, "encoders", **opts)
            rospy.Subscriber(base + "/sensors/strain", SensorReading, self._got, "strain", **opts)
            self.topics = 5

    def _got(self, msg, topic):
        t = msg.header.stamp.to_nsec()
        with self.lock:
            if self.last_stamp is not None and t <= self.last_stamp:
                if t != 0:
                    return  # a latched repeat of a state already answered
                self.last_stamp = None  # the node started over (~reset)
            entry = self.pending.setdefault(t, {})
            entry[topic] = msg
            if len(entry) == self.topics:
                del self.pending[t]
                # anything older can no longer complete
                for old in [k for k in self.pending if k < t]:
                    del self.pending[old]
                self.ready.put((t, entry))

    def spin(self):
        rospy = self.rospy
        # the node hears a command only once its subscriber is connected to this publisher; a
        # recorder's subscription can satisfy this wait first, and then the node sends the waiting
        # state again once it connects (docs/ros.md, Lockstep), which is answered like a reset
        while not rospy.is_shutdown() and self.pub.get_num_connections() == 0:
            time.sleep(0.01)  # wall time: /clock may not run yet
        rospy.loginfo("%s: connected to %s", self.name, self.pub.resolved_name)
        try:
            while not rospy.is_shutdown():
                try:
                    t, entry = self.ready.get(timeout=0.1)
                except queue.Empty:
                    continue
                with self.lock:
                    if self.last_stamp is not None and t <= self.last_stamp:
                        continue
                    if self.last_stamp is None:
                        self.answered = 0
                    self.last_stamp = t
                state = State.from_messages(entry["joint_states"], entry["odom"], entry["beam"])
                state.sensors = entry
                if self.answered % self.decimation == 0:
                    self.held = self.control(state)
                self.answered += 1
                # the row before the command: once the node has it, it may integrate to its
                # duration and exit, and roslaunch stop this process
                if self.log:
                    self.log.writerow(log_row(state, self.held))
                    self.log_file.flush()
                cmd = self.EffortCommand()
                cmd.header.stamp = state.stamp
                cmd.leg_force = [float(v) for v in self.held[0]]
                cmd.cylinder_torque = [float(v) for v in self.held[1]]
                self.pub.publish(cmd)
        finally:
            if self.log:
                self.log_file.close()
