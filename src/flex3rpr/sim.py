"""Sim: one simulation of a scene, stepped by a controller in Python, as the node's
~step_with_command steps it, or run open loop as the CLI runs it."""
import ctypes
import json
import os
import tempfile
import warnings

import numpy as np

from . import _core
from ._core import lib

_DOUBLE_P = ctypes.POINTER(ctypes.c_double)


def _ptr(array):
    return array.ctypes.data_as(_DOUBLE_P)


def _scene_file(scene):
    """(path, label, temporary): a scene given as a path, a YAML string or a dict."""
    if isinstance(scene, dict):
        text, label = json.dumps(scene), "<dict>"  # JSON is YAML
    elif isinstance(scene, (str, os.PathLike)) and os.path.isfile(scene):
        return os.fspath(scene), None, False
    elif isinstance(scene, str) and ("\n" in scene or ":" in scene):
        text, label = scene, "<string>"
    else:
        raise FileNotFoundError("flex3rpr: scene %r: no such file (give a path, a YAML string or "
                                "a dict)" % (scene,))
    handle, path = tempfile.mkstemp(prefix="flex3rpr_scene_", suffix=".yaml")
    with os.fdopen(handle, "w") as f:
        f.write(text)
    return path, label, True


def _override_text(field, value):
    if isinstance(value, bool):
        value = "true" if value else "false"
    elif isinstance(value, (list, tuple, dict)):
        value = json.dumps(value)
    elif isinstance(value, float):
        value = repr(value)
    return "%s=%s" % (field, value)


def scene_path(name):
    """The path of a scene the package ships (config/scenes/NAME), from any directory: in the
    checkout or a devel space (beside src/), or in an install space (share/flex3rpr)."""
    here = os.path.dirname(os.path.realpath(__file__))
    roots = [os.path.dirname(os.path.dirname(here)),  # src/flex3rpr -> the checkout
             os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(here)))),
                          "share", "flex3rpr")]  # lib/python3/dist-packages/flex3rpr -> prefix
    for root in roots:
        path = os.path.join(root, "config", "scenes", name)
        if os.path.isfile(path):
            return path
    raise FileNotFoundError("flex3rpr: the package's scene %s is not in %s"
                            % (name, " or ".join(os.path.join(r, "config", "scenes") for r in roots)))


def _describe(value):
    if isinstance(value, np.ndarray):
        return "%s array of shape %s%s" % (value.dtype, value.shape,
                                           "" if value.flags.c_contiguous else ", not contiguous")
    return type(value).__name__


class State:
    """The outputs at one time, in the CLI's CSV columns: `vector` (a numpy array, one value a
    column, the CSV's order; `names` says which) and each column by name (s.x_p, s["eta_1_2"]),
    plus the grouped fields t, q, v, pose, twist, modal, modal_rate, tip_deflection."""
    __slots__ = ("vector", "_sim")

    def __init__(self, vector, sim):
        self.vector = vector
        self._sim = sim

    @property
    def names(self):
        return self._sim.columns

    def __getitem__(self, name):
        return self.vector[self._sim.column_index[name]]

    def __getattr__(self, name):
        try:
            return self.vector[self._sim.column_index[name]]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def q(self):
        return self.vector[1:1 + self._sim.nq]

    @property
    def v(self):
        n = self._sim.nq
        return self.vector[4 + n:4 + 2 * n]

    pose = property(lambda s: s.q[6:9])
    twist = property(lambda s: s.v[6:9])
    modal = property(lambda s: s.q[9:])
    modal_rate = property(lambda s: s.v[9:])
    tip_deflection = property(lambda s: s.vector[1 + s._sim.nq:4 + s._sim.nq])

    def as_dict(self):
        return dict(zip(self._sim.columns, self.vector.tolist()))

    def __repr__(self):
        return "State(t=%.6g, pose=%s)" % (self.vector[0], np.array2string(self.pose))


class Sim:
    """A simulation of `scene` (a path, a YAML string or a dict), with `overrides` as the CLI's
    --set gives them ({"links[0].modes": 4}; keyword arguments name a field with "__" for ".":
    Sim("rest.yaml", run__duration=2.0)), an optional accuracy request (m) for the knob, and
    `period` (s), the commanded period of step().

    Errors are exceptions carrying the core's message (SceneError for a bad scene: the message
    names the file, the field and the allowed range). A refused call changes nothing."""

    def __init__(self, scene, overrides=None, accuracy=0.0, period=1e-3, **fields):
        sets = [_override_text(k, v) for k, v in (overrides or {}).items()]
        sets += [_override_text(k.replace("__", "."), v) for k, v in fields.items()]
        path, label, temporary = _scene_file(scene)
        encoded = [s.encode() for s in sets]
        array = (ctypes.c_char_p * max(1, len(encoded)))(*encoded)
        handle = ctypes.c_void_p()
        try:
            status = lib.f3r_py_create(path.encode(), float(accuracy), array, len(encoded), 1,
                                       ctypes.byref(handle))
        finally:
            if temporary:
                os.unlink(path)
        self._h = handle
        if status != 0:
            message = lib.f3r_py_message(handle).decode() if handle else "out of memory"
            lib.f3r_py_destroy(handle)
            self._h = None
            if not message.startswith(path):  # an override's error names the field alone
                message = "%s: %s" % (path, message)
            if label:
                message = message.replace(path, label)
            kind = _core.STATUS_NAMES.get(status, "error")
            raise _core.error_class(kind)(message, kind)
        self.scene = label or path
        try:
            self.period = float(period)
        except (TypeError, ValueError):
            self.period = float("nan")
        _core.check(lib.f3r_py_check_step(handle, 1.0, self.period), handle)
        self.nq = lib.f3r_py_nq(handle)
        self.modes = [lib.f3r_py_modes(handle, i) for i in range(3)]
        name = ctypes.create_string_buffer(_core.OUTPUT_NAME)
        self.columns = []
        for k in range(lib.f3r_py_columns(handle)):
            lib.f3r_py_column_name(handle, k, name)
            self.columns.append(name.value.decode())
        self.column_index = {n: k for k, n in enumerate(self.columns)}
        self._row = np.zeros(len(self.columns))
        self._held = np.zeros(self.nq)
        self._extra_groups = _core.extra_groups()
        self._extras = np.zeros(sum(n for _, n in self._extra_groups))
        lib.f3r_py_row(handle, _ptr(self._row))
        # the enabled sensors' channels, as the CLI's columns: names and sizes from the core's table
        self.sensor_names = [lib.f3r_py_sensor_column_name(handle, c).decode()
                             for c in range(lib.f3r_py_sensor_columns(handle))]
        self._sensors = np.zeros(len(self.sensor_names))

    def __del__(self):
        if getattr(self, "_h", None):
            lib.f3r_py_destroy(self._h)
            self._h = None

    # --- commands -----------------------------------------------------------------------------
    def forces(self, command):
        """The generalized forces (nq) of a command: 6 values (leg forces on rho_1..3 in N, then
        cylinder torques on theta_1..3 in N m, ros_control's order), nq values, or a dict with
        the node's EffortCommand fields (leg_force, cylinder_torque, platform, modal)."""
        held = np.zeros(self.nq)
        if isinstance(command, dict):
            sizes = {"leg_force": 3, "cylinder_torque": 3, "platform": 3,
                     "modal": self.nq - 9}
            starts = {"leg_force": 0, "cylinder_torque": 3, "platform": 6, "modal": 9}
            for key, value in command.items():
                if key not in sizes:
                    raise ValueError("command: unknown field %r (leg_force, cylinder_torque, "
                                     "platform, modal); nothing changed" % key)
                value = np.asarray(value, dtype=float).ravel()
                if key == "modal" and value.size not in (0, sizes[key]):  # the node's words
                    raise ValueError("command: modal has %d values, expected 0 or %d; nothing "
                                     "changed" % (value.size, sizes[key]))
                if key != "modal" and value.size != sizes[key]:
                    raise ValueError("command: %s has %d values, expected %d; nothing changed"
                                     % (key, value.size, sizes[key]))
                held[starts[key]:starts[key] + value.size] = value
        else:
            value = np.asarray(command, dtype=float).ravel()
            if value.size == 6:
                held[:6] = value
            elif value.size == self.nq:
                held[:] = value
            else:
                raise ValueError("command: %d values, expected 6 (leg forces, cylinder torques) "
                                 "or %d (every generalized force); nothing changed"
                                 % (value.size, self.nq))
        return held  # finiteness and the scene's limits are the core's to check (step)

    def step(self, command=None, periods=1):
        """Holds `command` (see forces(); None: zero) for `periods` (a whole number) periods of
        `period` s, as the node's ~step_with_command, and returns the State at the end (its
        own copy). The core checks the command: a value that is not finite or beyond the
        scene's `limits` raises, naming it, and nothing changes; so does a step that fails."""
        held = self._held if command is None else self.forces(command)
        if command is None:
            held[:] = 0.0
        self._step(held, periods)
        self._warn_if_unmet()
        return State(self._row.copy(), self)

    def step_forces(self, held, periods=1):
        """step() with the generalized forces as they are, for a controller loop's speed: a
        C-contiguous float64 numpy array of nq values (anything else raises TypeError, nothing
        changed), checked by the core as step()'s. Returns the outputs' vector, which the next
        step overwrites (step() returns a State that stays)."""
        if not (isinstance(held, np.ndarray) and held.dtype == np.float64 and held.ndim == 1
                and held.flags.c_contiguous and held.size == self.nq):
            raise TypeError("step_forces: a C-contiguous float64 numpy array of %d values expected, "
                            "got %s; nothing changed" % (self.nq, _describe(held)))
        self._step(held, periods)
        return self._row

    def _step(self, held, periods):
        try:
            periods = float(periods)
        except (TypeError, ValueError):
            raise TypeError("periods: a whole number expected, got %r; nothing changed"
                            % (periods,)) from None
        status = lib.f3r_py_step(self._h, _ptr(held), held.size, periods, self.period,
                                 _ptr(self._row))
        _core.check(status, self._h)

    # --- state --------------------------------------------------------------------------------
    @property
    def t(self):
        return lib.f3r_py_time(self._h)

    @property
    def state(self):
        """The present State (a copy)."""
        row = np.empty_like(self._row)
        lib.f3r_py_row(self._h, _ptr(row))
        return State(row, self)

    @property
    def sensors(self):
        """The scene's sensors' readings now (sensor_names names them; empty without sensors):
        sampled at their rate, delayed, quantised and noisy as the scene says (docs/scenes.md),
        exactly as the node's ~sensors topics and the CLI's columns."""
        n = lib.f3r_py_sensors(self._h, _ptr(self._sensors))
        return self._sensors[:n].copy()

    @property
    def extras(self):
        """What the columns leave out: actuator (6) and passive (6) efforts, stop_locked (3),
        stop_force (3), energy_balance_error, actuation_condition, impacts."""
        lib.f3r_py_extras(self._h, _ptr(self._extras))
        out, start = {}, 0
        for name, count in self._extra_groups:  # the C side's table: names, counts, order
            values = self._extras[start:start + count]
            start += count
            whole = name in ("stop_locked", "impacts")
            if count == 1:
                out[name] = int(values[0]) if whole else float(values[0])
            else:
                out[name] = values.astype(int) if whole else values.copy()
        return out

    def set_state(self, pose, twist=(0.0, 0.0, 0.0), modal=None, modal_rate=None):
        """The platform pose (x, y, phi) and twist in the base frame and, optionally, the modal
        coordinates and rates; the legs follow through the loop closure. Time and held commands
        stay. An unreachable pose or a bad value raises, and nothing changes."""
        arrays = [np.ascontiguousarray(value, dtype=float).ravel() if value is not None else None
                  for value in (pose, twist, modal, modal_rate)]
        for name, a in zip(("pose", "twist"), arrays):  # the C side reads three values of each
            if a.size != 3:
                raise ValueError("%s: %d values, expected 3; nothing changed" % (name, a.size))
        modal_sizes = {a.size for a in arrays[2:] if a is not None}
        if len(modal_sizes) > 1:
            raise ValueError("modal and modal_rate: %d and %d values; nothing changed"
                             % (arrays[2].size, arrays[3].size))
        # the core checks the modal count against the model, and every range
        count = modal_sizes.pop() if modal_sizes else 0
        pointers = [None if a is None else _ptr(a) for a in arrays]
        _core.check(lib.f3r_py_set_state(self._h, *pointers, count), self._h)
        lib.f3r_py_row(self._h, _ptr(self._row))

    # --- the closed-loop measurement --------------------------------------------------------
    def _measurement(self):
        measured, met = ctypes.c_double(0.0), ctypes.c_int(0)
        if not lib.f3r_py_measurement(self._h, ctypes.byref(measured), ctypes.byref(met)):
            return None
        return measured.value, bool(met.value), lib.f3r_py_message(self._h).decode()

    @property
    def measured_error_m(self):
        """With an accuracy request (and the scene's accuracy.verify, on by default): the largest
        end-effector distance (m) so far between this run and the check configuration, a richer
        one stepped on the same commands, period by period (nan once the check could not follow:
        measurement_note says why). None without a request."""
        m = self._measurement()
        return None if m is None else m[0]

    @property
    def request_met(self):
        """True while measured_error_m is within 0.7 of the request (the check's margin, as the
        CLI's); None without a request."""
        m = self._measurement()
        return None if m is None else m[1]

    @property
    def measurement_note(self):
        m = self._measurement()
        return "" if m is None else m[2]

    def _warn_if_unmet(self):
        """Warns once (until reset) when the measured error passes the request."""
        if getattr(self, "_warned", False):
            return
        m = self._measurement()
        if m is not None and not m[1]:
            self._warned = True
            request = self.accuracy["request"]
            warnings.warn("flex3rpr: %s: the accuracy request %g m is not met: measured %.3g m "
                          "against the check at t = %.6g s%s" % (
                              self.scene, request, m[0], self.t, (": " + m[2]) if m[2] else ""),
                          RuntimeWarning, stacklevel=3)

    def reset(self):
        """Back to the scene's initial state at t = 0, commands zero (and the measurement)."""
        self._warned = False
        _core.check(lib.f3r_py_reset(self._h), self._h)
        lib.f3r_py_row(self._h, _ptr(self._row))

    # --- whole runs and analyses --------------------------------------------------------------
    def run(self, duration=None):
        """The scene from t = 0 as flex3rpr_sim runs it (its scripted inputs, outputs every
        run.output_step), in its own simulation: a dict of numpy arrays, one per CSV column,
        the same values as the CLI's CSV. This Sim's own state is untouched."""
        duration = lib.f3r_py_duration(self._h) if duration is None else float(duration)
        count = int(round(duration / lib.f3r_py_output_step(self._h)))
        rows = np.zeros((count + 1, len(self.columns)))
        written = ctypes.c_long(0)
        status = lib.f3r_py_run(self._h, duration, _ptr(rows), ctypes.byref(written))
        _core.check(status, self._h)
        return {name: rows[:written.value, k] for k, name in enumerate(self.columns)}

    def linearise(self):
        """The linearisation about the scene's initial pose, x' = A x + B u, y - y0 = C x + D u
        (flex3rpr/linear.h): a dict with A, B, C, D, x0, y0 and state_names, input_names,
        output_names."""
        ss = ctypes.c_void_p()
        _core.check(lib.f3r_py_linearise(self._h, ctypes.byref(ss)), self._h)
        try:
            s = ctypes.cast(ss, ctypes.POINTER(_core.StateSpace)).contents

            def matrix(pointer, rows, cols):  # column-major in C
                return np.ctypeslib.as_array(pointer, shape=(cols * rows,)).reshape(
                    (cols, rows)).T.copy()
            out = {"A": matrix(s.A, s.nx, s.nx), "B": matrix(s.B, s.nx, s.nu),
                   "C": matrix(s.C, s.ny, s.nx), "D": matrix(s.D, s.ny, s.nu),
                   "x0": np.ctypeslib.as_array(s.x0, shape=(s.nx,)).copy(),
                   "y0": np.array(s.y0[:]),
                   "state_names": [s.state_names[k].value.decode() for k in range(s.nx)],
                   "input_names": [s.input_names[k].value.decode() for k in range(s.nu)],
                   "output_names": [s.output_names[k].value.decode() for k in range(s.ny)]}
        finally:
            lib.f3r_py_linear_destroy(ss)
        return out

    def modal(self):
        """The natural frequencies (Hz) of the linearised model, ascending."""
        hz = np.zeros(2 * self.nq + 8)
        count = ctypes.c_int(0)
        _core.check(lib.f3r_py_modal(self._h, _ptr(hz), ctypes.byref(count)), self._h)
        return hz[:count.value].copy()

    @property
    def geometry(self):
        """The model's geometry (f3r_geometry, docs/model.md) as a dict: base_joint (A_i, 3 x 2,
        m), platform_angle (phi_i of C_i), platform_radius, link_length, the masses and inertia,
        end_stops (bool), stroke_min and stroke_max (m)."""
        g = lib.f3r_py_geometry(self._h).contents
        out = {name: getattr(g, name) for name, _ in _core.Geometry._fields_}
        out["base_joint"] = np.array([list(row) for row in g.base_joint])
        out["platform_angle"] = np.array(list(g.platform_angle))
        out["end_stops"] = bool(g.end_stops)
        return out

    @property
    def sensor_settings(self):
        """The scene's sensors as this Sim has them (overrides applied, defaults filled in):
        {"encoders": {"enabled", "rate", "delay", "seed", "stroke_noise", ...}, "strain_gauges":
        {..., "noise", "resolution"}, "accelerometer": {...}}, the scene file's names."""
        values, out = np.zeros(8), {}
        for kind, (name, keys) in enumerate(_core.sensor_keys()):
            lib.f3r_py_sensor_settings(self._h, kind, _ptr(values))
            s = {"enabled": bool(values[0]), "rate": float(values[1]), "delay": int(values[2]),
                 "seed": int(values[3])}
            s.update((key, float(values[4 + j])) for j, key in enumerate(keys) if key)
            out[name] = s
        return out

    def strain_rows(self):
        """The root strain gauges as rows over the modal coordinates (State.modal, the
        linearisation's eta states): eps = strain_rows() @ modal, a 3 x (nq - 9) array (rows of
        zeros for rigid links), the core's f3r_sensors_strain_row (docs/scenes.md, sensors)."""
        rows = np.zeros((3, self.nq - 9))
        c = np.zeros(_core.MAX_MODES)
        start = 0
        for i in range(3):
            n = lib.f3r_py_strain_row(self._h, i, _ptr(c))
            rows[i, start:start + n] = c[:n]
            start += self.modes[i]
        return rows

    def close_loops(self, pose, modal=None):
        """The coordinates q (nq values, State.q's order) of the platform `pose` (x, y, phi) with
        the links deflected by `modal` (nq - 9 values; None: straight): the core's loop closure
        gives the strokes q[0:3] and leg directions q[3:6]. The Sim's own state is untouched; a
        pose the legs cannot reach raises flex3rpr.Error."""
        q = np.zeros(self.nq)
        for name, value, start, size in (("pose", pose, 6, 3), ("modal", modal, 9, self.nq - 9)):
            if value is None and name == "modal":
                continue
            value = np.asarray(value, dtype=float).ravel()
            if value.size != size:
                raise ValueError("%s: %d values, expected %d" % (name, value.size, size))
            if not np.all(np.isfinite(value)):
                raise ValueError("%s: not finite: %s" % (name, value))
            q[start:start + value.size] = value
        _core.check(lib.f3r_py_close_loops(self._h, _ptr(q)), self._h)
        return q

    @property
    def accuracy(self):
        """The accuracy knob's choice and estimate, as a dict (request 0: none was made)."""
        return json.loads(lib.f3r_py_choice(self._h).decode())
