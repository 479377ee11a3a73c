"""The C side of the module: libflex3rpr_py.so (src/python/flex3rpr_py.c) through ctypes.

Where the library is found, first hit wins: $F3R_LIBRARY (a file or a folder), the folders of
$LD_LIBRARY_PATH (a sourced catkin workspace puts devel/lib there), then build/ws/devel/lib of the
checkout this file is in.
"""
import ctypes
import os

LIBRARY = "libflex3rpr_py.so"
OUTPUT_NAME = 24  # F3R_OUTPUT_NAME
STATUS_NAMES = {0: "ok", 1: "argument", 2: "scene", 3: "memory", 4: "solver", 5: "singular",
                6: "nonfinite"}  # f3r_status, flex3rpr/status.h


class Error(RuntimeError):
    """A core error, with the core's message; .status names its kind (scene, singular, ...)."""

    def __init__(self, message, status="error"):
        super().__init__(message)
        self.status = status


class SceneError(Error, ValueError):
    """A scene the core refused: the message names the file, the field and the allowed range."""


class ArgumentError(Error, ValueError):
    """A command, a period or a state the core refused (the session's checks, the same as the
    node's): the message names the value and the allowed range; nothing changed."""


def error_class(kind):
    return {"scene": SceneError, "argument": ArgumentError}.get(kind, Error)


def _candidates():
    env = os.environ.get("F3R_LIBRARY")
    if env:
        yield os.path.join(env, LIBRARY) if os.path.isdir(env) else env
    for folder in os.environ.get("LD_LIBRARY_PATH", "").split(":"):
        if folder:
            yield os.path.join(folder, LIBRARY)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
    yield os.path.join(root, "build", "ws", "devel", "lib", LIBRARY)


def _load():
    tried = []
    for path in _candidates():
        if os.path.isfile(path):
            return ctypes.CDLL(path)
        tried.append(path)
    raise ImportError("flex3rpr: %s not found (build it: bash scripts/build, or cmake -S src/core; "
                      "then source build/ws/devel/setup.bash or set F3R_LIBRARY); looked in: %s"
                      % (LIBRARY, ", ".join(tried)))


lib = _load()
_p = ctypes.c_void_p
_d = ctypes.POINTER(ctypes.c_double)
_signatures = {
    "f3r_py_create": (ctypes.c_int, [ctypes.c_char_p, ctypes.c_double,
                                     ctypes.POINTER(ctypes.c_char_p), ctypes.c_int, ctypes.c_int,
                                     ctypes.POINTER(_p)]),
    "f3r_py_destroy": (None, [_p]),
    "f3r_py_message": (ctypes.c_char_p, [_p]),
    "f3r_py_nq": (ctypes.c_int, [_p]),
    "f3r_py_modes": (ctypes.c_int, [_p, ctypes.c_int]),
    "f3r_py_time": (ctypes.c_double, [_p]),
    "f3r_py_duration": (ctypes.c_double, [_p]),
    "f3r_py_output_step": (ctypes.c_double, [_p]),
    "f3r_py_columns": (ctypes.c_int, [_p]),
    "f3r_py_column_name": (ctypes.c_int, [_p, ctypes.c_int, ctypes.c_char_p]),
    "f3r_py_row": (None, [_p, _d]),
    "f3r_py_extras": (ctypes.c_int, [_p, _d]),
    "f3r_py_extra_group": (ctypes.c_char_p, [ctypes.c_int, ctypes.POINTER(ctypes.c_int)]),
    "f3r_py_check_step": (ctypes.c_int, [_p, ctypes.c_double, ctypes.c_double]),
    "f3r_py_measurement": (ctypes.c_int, [_p, _d, ctypes.POINTER(ctypes.c_int)]),
    "f3r_py_step": (ctypes.c_int, [_p, _d, ctypes.c_int, ctypes.c_double, ctypes.c_double, _d]),
    "f3r_py_reset": (ctypes.c_int, [_p]),
    "f3r_py_set_state": (ctypes.c_int, [_p, _d, _d, _d, _d, ctypes.c_int]),
    "f3r_py_run": (ctypes.c_int, [_p, ctypes.c_double, _d, ctypes.POINTER(ctypes.c_long)]),
    "f3r_py_linearise": (ctypes.c_int, [_p, ctypes.POINTER(_p)]),
    "f3r_py_linear_destroy": (None, [_p]),
    "f3r_py_modal": (ctypes.c_int, [_p, _d, ctypes.POINTER(ctypes.c_int)]),
    "f3r_py_choice": (ctypes.c_char_p, [_p]),
    "f3r_py_sensors": (ctypes.c_int, [_p, _d]),
    "f3r_py_sensor_columns": (ctypes.c_int, [_p]),
    "f3r_py_sensor_kinds": (ctypes.c_int, []),
    "f3r_py_sensor_kind_key": (ctypes.c_char_p, [ctypes.c_int, ctypes.c_int]),
    "f3r_py_sensor_column_name": (ctypes.c_char_p, [_p, ctypes.c_int]),
    "f3r_py_sensor_settings": (None, [_p, ctypes.c_int, _d]),
    "f3r_py_strain_row": (ctypes.c_int, [_p, ctypes.c_int, _d]),
    "f3r_py_close_loops": (ctypes.c_int, [_p, _d]),
}
for _name, (_restype, _argtypes) in _signatures.items():
    _f = getattr(lib, _name)
    _f.restype = _restype
    _f.argtypes = _argtypes


def extra_groups():
    """The extras' groups as the C side exports them: [(name, count), ...] in their order."""
    groups, count = [], ctypes.c_int(0)
    while True:
        name = lib.f3r_py_extra_group(len(groups), ctypes.byref(count))
        if name is None:
            return groups
        groups.append((name.decode(), count.value))


class Geometry(ctypes.Structure):
    """f3r_geometry of flex3rpr/model.h."""
    _fields_ = [("base_joint", (ctypes.c_double * 2) * 3), ("platform_angle", ctypes.c_double * 3),
                ("platform_radius", ctypes.c_double), ("link_length", ctypes.c_double),
                ("link_mass", ctypes.c_double), ("cylinder_mass", ctypes.c_double),
                ("cylinder_length", ctypes.c_double), ("platform_mass", ctypes.c_double),
                ("platform_inertia", ctypes.c_double), ("end_stops", ctypes.c_int),
                ("stroke_min", ctypes.c_double), ("stroke_max", ctypes.c_double)]


lib.f3r_py_geometry.restype = ctypes.POINTER(Geometry)
lib.f3r_py_geometry.argtypes = [_p]
MAX_MODES = 20  # F3R_MAX_MODES, flex3rpr/coords.h
def sensor_keys():
    """The sensor kinds of the core's table (kinds.h), in its order: (name, (scene keys of
    noise[0], noise[1], resolution[0], resolution[1], None where the kind has none))."""
    def text(kind, key):
        value = lib.f3r_py_sensor_kind_key(kind, key)
        return value.decode() if value is not None else None
    return tuple((text(k, -1), tuple(text(k, j) for j in range(4)))
                 for k in range(lib.f3r_py_sensor_kinds()))


class StateSpace(ctypes.Structure):
    """f3r_state_space of flex3rpr/linear.h."""
    _fields_ = [("nx", ctypes.c_int), ("nu", ctypes.c_int), ("ny", ctypes.c_int),
                ("A", _d), ("B", _d), ("C", _d), ("D", _d), ("x0", _d),
                ("y0", ctypes.c_double * 12),
                ("state_names", ctypes.POINTER(ctypes.c_char * 24)),
                ("input_names", (ctypes.c_char * 24) * 6),
                ("output_names", (ctypes.c_char * 24) * 12)]


def check(status, handle):
    """Raises the core's error for a failed call on handle."""
    if status != 0:
        message = lib.f3r_py_message(handle).decode()
        kind = STATUS_NAMES.get(status, "error")
        raise error_class(kind)(message, kind)
