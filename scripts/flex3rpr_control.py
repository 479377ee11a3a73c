"""What the example controllers (scripts/pd_controller, scripts/lqr_controller) share: the
manipulator's geometry and inverse kinematics, the linear plant that `flex3rpr_sim SCENE
--linearise FILE.mat` exports and a discrete LQR designed on it, and the lockstep plumbing.

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
import subprocess
import tempfile
import threading
import time

import numpy as np

import flex3rpr_tools  # beside this module: finds flex3rpr_sim

# ---- geometry (docs/model.md; defaults of the scene's geometry and link sections) ---------
LEG_ANGLES = (-math.pi / 6, math.pi / 2, 7 * math.pi / 6)
JOINTS_RHO = ["leg_%d_prismatic" % (i + 1) for i in range(3)]
JOINTS_THETA = ["leg_%d_revolute" % (i + 1) for i in range(3)]


class Geometry:
    """A_i at radius base_side/sqrt(3) and angle phi_i, C_i at radius platform_side/sqrt(3) and
    angle phi_i + phi_p from P; the stroke rho_i = |C_i - A_i| - l (undeflected link)."""

    def __init__(self, base_side=0.66, platform_side=0.1, link_length=0.2, stroke_min=0.0,
                 stroke_max=0.2, home=(0.0, 0.0, 0.0)):
        self.r_a = base_side / math.sqrt(3.0)
        self.r_c = platform_side / math.sqrt(3.0)
        self.l = link_length
        self.stroke = (stroke_min, stroke_max)
        self.home = tuple(float(v) for v in home)

    @classmethod
    def from_scene(cls, path):
        """The geometry and the initial platform pose of a scene YAML (defaults where it is silent)."""
        import yaml
        with open(path) as fh:
            s = yaml.safe_load(fh) or {}
        g = s.get("geometry") or {}
        link = s.get("link") or {}
        init = s.get("initial") or {}
        return cls(g.get("base_side", 0.66), g.get("platform_side", 0.1), link.get("length", 0.2),
                   g.get("stroke_min", 0.0), g.get("stroke_max", 0.2),
                   init.get("platform_pose", (0.0, 0.0, 0.0)))

    def inverse_kinematics(self, pose):
        """Strokes rho_i and leg directions theta_i of the platform pose (x, y, phi), straight links."""
        x, y, phi = pose
        rho, theta = [], []
        for a in LEG_ANGLES:
            dx = x + self.r_c * math.cos(a + phi) - self.r_a * math.cos(a)
            dy = y + self.r_c * math.sin(a + phi) - self.r_a * math.sin(a)
            rho.append(math.hypot(dx, dy) - self.l)
            theta.append(math.atan2(dy, dx))
        return rho, theta


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


# ---- the linear plant ----------------------------------------------------------------------------
def load_plant(path):
    """The plant `flex3rpr_sim --linearise` writes: the JSON beside a .mat (or the .mat through
    scipy.io.loadmat, or a JSON given directly). Returns a dict of numpy arrays and name lists."""
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


def node_arguments(doc):
    """A controller node's command line: --help prints its docstring; the ROS remappings and
    roslaunch's __name:=, __log:= arguments pass (rospy.myargv takes them out)."""
    import argparse
    import rospy
    parts = doc.split("\n\n")
    ap = argparse.ArgumentParser(description=parts[0], epilog="\n\n".join(parts[1:]),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    return ap.parse_args(rospy.myargv()[1:])


def find_cli():
    """flex3rpr_sim: $F3R_SIM, beside this module (an install space), the source tree's build,
    catkin_find, or PATH (flex3rpr_tools.find_binary)."""
    try:
        return flex3rpr_tools.find_binary("flex3rpr_sim", "F3R_SIM")
    except FileNotFoundError:
        return "flex3rpr_sim"


def linearise(scene, cli=None):
    """Runs `flex3rpr_sim SCENE --linearise plant.mat` in a temporary folder and loads the plant."""
    cli = cli or find_cli()
    with tempfile.TemporaryDirectory(prefix="flex3rpr_plant_") as tmp:
        mat = os.path.join(tmp, "plant.mat")
        res = subprocess.run([cli, scene, "--linearise", mat], capture_output=True, text=True, timeout=600)
        if res.returncode != 0 or not os.path.exists(mat):
            raise RuntimeError("%s %s --linearise failed (exit %d): %s" % (cli, scene, res.returncode,
                                                                          (res.stderr or res.stdout).strip()))
        return load_plant(mat)


def discretise(A, B, dt):
    """Zero-order hold: the command is held over each period, as lockstep applies it."""
    import scipy.linalg
    nx, nu = B.shape
    M = np.zeros((nx + nu, nx + nu))
    M[:nx, :nx], M[:nx, nx:] = A * dt, B * dt
    E = scipy.linalg.expm(M)
    return E[:nx, :nx], E[:nx, nx:]


def tip_rows(plant):
    """The tip deflections' rows over the state: the plant's C rows tip_deflection_1..3, or
    psi_j(1) = 2 (-1)^j of fixed-free modes when the plant has no C."""
    nx = plant["A"].shape[0]
    names = plant.get("output_names", [])
    if "C" in plant and all("tip_deflection_%d" % (i + 1) in names for i in range(3)):
        return np.vstack([plant["C"][names.index("tip_deflection_%d" % (i + 1))] for i in range(3)])
    rows = np.zeros((3, nx))
    for k, s in enumerate(plant["state_names"]):
        if s.startswith("eta_") and not s.endswith("_rate"):
            i, j = (int(v) for v in s[4:].split("_"))
            rows[i - 1, k] = 2.0 * (-1) ** j
    return rows


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


def clamped_roots(end, count):
    """alpha_j, j = 1..count, of a fixed-free (cos a cosh a + 1 = 0) or fixed-pinned
    (tan a = tanh a) beam, bracketed near (j - 1/2) pi and (j + 1/4) pi."""
    from scipy.optimize import brentq
    if end == "fixed_free":
        f, centre = (lambda a: math.cos(a) * math.cosh(a) + 1.0), (lambda j: (j - 0.5) * math.pi)
    else:
        f, centre = (lambda a: math.tan(a) - math.tanh(a)), (lambda j: (j + 0.25) * math.pi)
    return [brentq(f, centre(j) - 0.4, centre(j) + 0.4, xtol=1e-15) for j in range(1, count + 1)]


def gauge_rows(plant, scene):
    """The root strain gauges' rows over the plant's state (docs/scenes.md, sensors):
    eps_i = (d/2) w_i''(0) = (d/2) / l^2 sum_j psi_j''(0) eta_ij, with psi_j''(0) = -2 alpha_j^2
    for the paper's modes. The plant's modal states must all be modes (no static correction:
    their curvatures are not closed-form; the core has them, f3r_sensors_strain_row)."""
    import yaml
    with open(scene) as fh:
        s = yaml.safe_load(fh) or {}
    link = s.get("link") or {}
    d, l = float(link.get("diameter", 0.010)), float(link.get("length", 0.2))
    links = s.get("links") or {}
    links = links if isinstance(links, list) else [links] * 3
    rows = np.zeros((3, plant["A"].shape[0]))
    for k, name in enumerate(plant["state_names"]):
        if name.startswith("eta_") and not name.endswith("_rate"):
            i, j = (int(v) for v in name[4:].split("_"))
            spec = links[i - 1] or {}
            if spec.get("static_correction"):
                raise ValueError("gauge_rows: link %d has static shapes; the observer needs plain modes" % i)
            alpha = clamped_roots(spec.get("model", "fixed_free"), j)[-1]
            rows[i - 1, k] = 0.5 * d / l ** 2 * (-2.0 * alpha ** 2)
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
