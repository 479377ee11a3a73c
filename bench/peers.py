"""Peers of the work-precision benchmark: other solvers on flex3rpr's own compiled model.

Imported by bench/work_precision (plain /usr/bin/python3, Debian's numpy and scipy):
  ensure_installed()                      apt-get installs r-cran-desolve and python3-scipy if missing
                                          (not deTestSet: without it run_mebdfi fails, the rest runs)
  build_library()                         path of libf3r_peer.so (bench/c/f3r_peer.c): the CMake
                                          target's if built, else compiled here with gcc into build/peer/
  run_daspk(scene, rtol, atol, formulation="dae"|"minimal", jacobian=True)
                                          DASPK of R's deSolve calling the core's residual F(t, y, y')
                                          (and its Jacobian dF/dy + cj dF/dy') as compiled code
  run_mebdfi(scene, rtol, atol, jacobian=True)  MEBDFI of R's deTestSet (the paper's solver) on the
                                          plain index-3 residual (formulation index3) and its Jacobian,
                                          compiled; deTestSet is not in Debian: have_mebdfi() says
                                          whether it loads (R's library paths plus build/rlib)
  run_lsoda(scene, rtol, atol, jacobian=True)   scipy.integrate.solve_ivp, LSODA, on the minimal
  run_radau(scene, rtol, atol, jacobian=True)   formulation's explicit RHS f3r_explicit_rhs via ctypes

Each run_* returns None on failure, else a dict:
  traj            [(t, x_p, y_p)] at every output step (1 ms) from 0 to the scene's duration,
                  the rows of the CLI's --output-step 1e-3 CSV
  cpu_s           CPU time of the integration only (R: proc.time around daspk() or mebdfi() inside R, not R's
                  start; scipy: time.process_time around solve_ivp)
  steps           accepted steps
  residual_evals  evaluations of the model's residual (DASPK, MEBDFI) or explicit RHS (scipy) counted in the
                  library, including difference-quotient Jacobian columns the solver asks for
                  (scipy's with jacobian=False, DASPK's and MEBDFI's with jacobian=False, and those of the C
                  Jacobian of the explicit RHS, jacobian=True); not the difference quotients inside
                  the core's own minimal-formulation Jacobian (as the CLI does not count them)
  jacobian_evals  Jacobian evaluations
  solver_nfev     the solver's own count of function evaluations
  error           (on success: None)
Failures (a solver giving up, a missing dependency) return None; the reason is in last_error.

rtol and atol are rounded to 3 significant digits, as bench/work_precision passes them to the CLI
("%.3g"): rtol * 1e-2 is not exactly 1e-6 in floating point, and a one-ulp change of atol moves
DASPK's step count by ~2 % on paper_sim3_fixed_free.

Breakpoints of the scripted inputs (model->breakpoints) are integration stops, as in the CLI:
each segment is integrated separately, restarted from a consistent state at the breakpoint.
Scenes with end stops (impacts) are not supported (None).
jacobian=True: DASPK gets the core's Jacobian (jacres); scipy gets d f/d y by forward differences
of the explicit RHS computed in C (one call, ny RHS evaluations); jacobian=False: the solvers'
own difference quotients through the Python/R callback.
"""
import ctypes
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CMAKE_LIB = os.path.join(ROOT, "build/ws/devel/lib/libf3r_peer.so")
LOCAL_LIB = os.path.join(ROOT, "build/peer/libf3r_peer.so")
PEER_SOURCE = os.path.join(ROOT, "bench/c/f3r_peer.c")
CORE_SOURCES = ["beam_basis", "beam_modes", "constraints", "dense", "dynamics", "effects", "form_dae", "form_minimal", "form_minimal_jacobian",
                "forward",
                "impact", "modal", "model", "residual", "scene", "scene_overrides", "scene_yaml", "scene_yaml_reader", "status"]
CORE_LAYERS = sorted(os.path.join(ROOT, "src/core", d) for d in os.listdir(os.path.join(ROOT, "src/core"))
                     if os.path.isdir(os.path.join(ROOT, "src/core", d)))


def core_source(name):
    """src/core/<layer>/<name>.c"""
    return next(os.path.join(d, name + ".c") for d in CORE_LAYERS if os.path.exists(os.path.join(d, name + ".c")))


R_SCRIPT = os.path.join(ROOT, "bench/daspk.R")
MEBDFI_SCRIPT = os.path.join(ROOT, "bench/mebdfi.R")
R_LOCAL_LIBRARY = os.path.join(ROOT, "build/rlib")  # where a deTestSet built here is installed
OUTPUT_STEP = 1e-3
TIME_LIMIT_S = 600.0  # one run is abandoned (None) past this much CPU time
FORMULATIONS = {"dae": 0, "minimal": 1}

last_error = None


def _fail(message):
    global last_error
    last_error = message
    return None


# --- dependencies and the library -----------------------------------------------------------------

def _have_desolve():
    if not shutil.which("Rscript"):
        return False
    p = subprocess.run(["Rscript", "-e", "suppressPackageStartupMessages(library(deSolve))"],
                       capture_output=True, text=True)
    return p.returncode == 0


def have_mebdfi():
    """Whether R's deTestSet (MEBDFI) loads, from R's library paths or build/rlib."""
    if not shutil.which("Rscript"):
        return False
    p = subprocess.run(["Rscript", "--vanilla", "-e",
                        f".libPaths(c(.libPaths(), {R_LOCAL_LIBRARY!r})); "
                        "suppressPackageStartupMessages(library(deTestSet))"],
                       capture_output=True, text=True)
    return p.returncode == 0


def _have_scipy():
    p = subprocess.run(["/usr/bin/python3", "-c", "import scipy.integrate, numpy"], capture_output=True, text=True)
    return p.returncode == 0


def ensure_installed():
    """Installs the peers' Debian packages if missing; raises RuntimeError if they cannot be had."""
    missing = []
    if not _have_desolve():
        missing.append("r-cran-desolve")
    if not _have_scipy():
        missing.append("python3-scipy")
    if missing:
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        cmd = ["apt-get", "install", "-y", "--no-install-recommends", *missing]
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if p.returncode != 0:  # stale package lists: update once and retry
            subprocess.run(["apt-get", "update"], capture_output=True, text=True, env=env)
            p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if p.returncode != 0:
            raise RuntimeError(f"apt-get install {' '.join(missing)} failed: {p.stderr.strip()[-300:]}")
    if not _have_desolve():
        raise RuntimeError("R's deSolve is not available")
    if not _have_scipy():
        raise RuntimeError("scipy is not available to /usr/bin/python3")
    build_library()


def _newest_source_mtime():
    paths = [PEER_SOURCE] + [core_source(n) for n in CORE_SOURCES]
    for d in [os.path.join(ROOT, "include/flex3rpr")] + CORE_LAYERS:
        paths += [os.path.join(d, f) for f in os.listdir(d) if f.endswith(".h")]
    return max(os.path.getmtime(p) for p in paths)


def build_library():
    """Path of libf3r_peer.so: the CMake target's (build/ws/devel/lib) when it is there and not
    older than bench/c/f3r_peer.c, else build/peer/libf3r_peer.so, compiled with gcc when stale."""
    if os.path.exists(CMAKE_LIB) and os.path.getmtime(CMAKE_LIB) >= os.path.getmtime(PEER_SOURCE):
        return CMAKE_LIB
    if os.path.exists(LOCAL_LIB) and os.path.getmtime(LOCAL_LIB) >= _newest_source_mtime():
        return LOCAL_LIB
    os.makedirs(os.path.dirname(LOCAL_LIB), exist_ok=True)
    tmp = LOCAL_LIB + ".tmp"
    # -O3 -DNDEBUG: the flags of the CMake Release build the CLI's core is compiled with
    cmd = ["gcc", "-O3", "-DNDEBUG", "-fPIC", "-shared", "-std=c11", "-D_GNU_SOURCE", "-I", os.path.join(ROOT, "include"),
           *["-I" + d for d in CORE_LAYERS], PEER_SOURCE, *[core_source(n) for n in CORE_SOURCES],
           "-lyaml", "-lm", "-o", tmp]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError("building libf3r_peer.so failed: " + p.stderr.strip()[-500:])
    os.replace(tmp, LOCAL_LIB)
    return LOCAL_LIB


# --- ctypes binding ------------------------------------------------------------------------------

_lib = None


def _library():
    global _lib
    if _lib is None:
        lib = ctypes.CDLL(build_library())
        P, D, I = ctypes.c_void_p, ctypes.POINTER(ctypes.c_double), ctypes.c_int
        lib.f3r_peer_create.argtypes = [ctypes.c_char_p, I, I, ctypes.POINTER(P)]
        lib.f3r_peer_last_error.restype = ctypes.c_char_p
        lib.f3r_peer_destroy.argtypes = [P]
        for name in ("state_size", "algebraic_count", "end_stops"):
            getattr(lib, "f3r_peer_" + name).argtypes = [P]
        lib.f3r_peer_duration.argtypes = [P]
        lib.f3r_peer_duration.restype = ctypes.c_double
        lib.f3r_peer_breakpoints.argtypes = [P, D, I]
        lib.f3r_peer_initial_state.argtypes = [P, D, D]
        lib.f3r_peer_restart_state.argtypes = [P, ctypes.c_double, D, D]
        lib.f3r_peer_rhs.argtypes = [P, ctypes.c_double, D, D]
        lib.f3r_peer_rhs_jacobian.argtypes = [P, ctypes.c_double, D, D, D]
        lib.f3r_peer_end_effector.argtypes = [P, D, D]
        lib.f3r_peer_counts.argtypes = [P, ctypes.POINTER(ctypes.c_long)]
        lib.f3r_peer_reset_counts.argtypes = [P]
        _lib = lib
    return _lib


class Model:
    """One handle of the library on a scene, in the minimal (explicit RHS) or dae formulation."""

    def __init__(self, scene_path, formulation="minimal"):
        self.handle = None
        import numpy as np
        self.np = np
        self.lib = _library()
        self.handle = ctypes.c_void_p()
        st = self.lib.f3r_peer_create(os.fsencode(scene_path), FORMULATIONS[formulation], 0, ctypes.byref(self.handle))
        if st != 0:
            self.handle = None
            raise RuntimeError(self.lib.f3r_peer_last_error().decode())
        self.ny = self.lib.f3r_peer_state_size(self.handle)
        self.duration = self.lib.f3r_peer_duration(self.handle)
        self.end_stops = bool(self.lib.f3r_peer_end_stops(self.handle))
        n = self.lib.f3r_peer_breakpoints(self.handle, None, 0)
        buf = (ctypes.c_double * max(n, 1))()
        self.lib.f3r_peer_breakpoints(self.handle, buf, n)
        self.breakpoints = list(buf)[:n]
        self._D = ctypes.POINTER(ctypes.c_double)

    def close(self):
        if self.handle:
            self.lib.f3r_peer_destroy(self.handle)
            self.handle = None

    def __del__(self):
        self.close()

    def _p(self, a):
        return a.ctypes.data_as(self._D)

    def _check(self, st):
        if st != 0:
            raise RuntimeError(self.lib.f3r_peer_last_error().decode())

    def initial_state(self):
        y, yp = self.np.zeros(self.ny), self.np.zeros(self.ny)
        self._check(self.lib.f3r_peer_initial_state(self.handle, self._p(y), self._p(yp)))
        return y, yp

    def restart_state(self, t, y):
        y = self.np.array(y, dtype=float)
        yp = self.np.zeros(self.ny)
        self._check(self.lib.f3r_peer_restart_state(self.handle, t, self._p(y), self._p(yp)))
        return y, yp

    def rhs(self, t, y):
        y = self.np.ascontiguousarray(y, dtype=float)
        out = self.np.empty(self.ny)  # a new array per call: the solvers keep what they are given
        self._check(self.lib.f3r_peer_rhs(self.handle, t, self._p(y), self._p(out)))
        return out

    def rhs_jacobian(self, t, y):
        y = self.np.ascontiguousarray(y, dtype=float)
        J = self.np.empty((self.ny, self.ny))
        self._check(self.lib.f3r_peer_rhs_jacobian(self.handle, t, self._p(y), None, self._p(J)))
        return J

    def end_effector(self, y):
        y = self.np.ascontiguousarray(y, dtype=float)
        xy = self.np.zeros(2)
        self._check(self.lib.f3r_peer_end_effector(self.handle, self._p(y), self._p(xy)))
        return float(xy[0]), float(xy[1])

    def counts(self):
        c = (ctypes.c_long * 3)()
        self.lib.f3r_peer_counts(self.handle, c)
        return {"residual": c[0], "jacobian": c[1], "rhs": c[2]}

    def reset_counts(self):
        self.lib.f3r_peer_reset_counts(self.handle)


def _tol(x):
    """A tolerance as the CLI receives it from bench/work_precision: 3 significant digits."""
    return float(f"{float(x):.3g}")


def output_times(duration, step=OUTPUT_STEP):
    """The CLI's output times: 0, then k * step for k = 1 .. round(duration / step), the last the duration."""
    n = int(round(duration / step))
    times = [k * step for k in range(n + 1)]
    times[-1] = duration
    return times


# --- scipy ---------------------------------------------------------------------------------------

class _TimeLimit(Exception):
    pass


def _run_scipy(method, scene_path, rtol, atol, jacobian, time_limit):
    try:
        from scipy.integrate import solve_ivp, LSODA, Radau
    except ImportError as e:
        return _fail(f"scipy unavailable: {e}")
    try:
        model = Model(scene_path, "minimal")
    except (RuntimeError, OSError) as e:
        return _fail(str(e))
    if model.end_stops:
        return _fail("end stops (impacts) are not supported by the peers")
    base = {"LSODA": LSODA, "Radau": Radau}[method]
    rtol, atol = _tol(rtol), _tol(atol)
    steps = [0]

    class Counting(base):  # solve_ivp with a solver class that counts its accepted steps
        def _step_impl(self):
            ok, message = super()._step_impl()
            if ok:
                steps[0] += 1
            return ok, message

    times = output_times(model.duration)
    bounds = [0.0] + [b for b in model.breakpoints if 0.0 < b < model.duration] + [model.duration]
    y, _ = model.initial_state()
    start = time.process_time()
    deadline = start + time_limit

    calls = [0]

    def fun(t, yy):
        calls[0] += 1
        if not calls[0] & 1023 and time.process_time() > deadline:  # a clock read costs a syscall
            raise _TimeLimit()
        return model.rhs(t, yy)

    jac = model.rhs_jacobian if jacobian else None
    states = {0: y.copy()}
    cpu = 0.0
    nfev = njev = 0
    model.reset_counts()
    try:
        for a, b in zip(bounds, bounds[1:]):
            idx = [k for k, t in enumerate(times) if a < t < b]
            t_eval = [times[k] for k in idx] + [b]
            t0 = time.process_time()
            sol = solve_ivp(fun, (a, b), y, method=Counting, t_eval=t_eval, rtol=rtol, atol=atol, jac=jac)
            cpu += time.process_time() - t0
            if sol.status != 0 or len(sol.t) != len(t_eval):
                model.close()
                return _fail(f"{method} stopped at t = {sol.t[-1] if len(sol.t) else a:.9g}: {sol.message}")
            nfev += int(sol.nfev)
            njev += int(sol.njev)
            for j, k in enumerate(idx):
                states[k] = sol.y[:, j]
            y = sol.y[:, -1].copy()
            for k, t in enumerate(times):
                if t == b:
                    states[k] = y
            if b < model.duration:  # a breakpoint: restart (y is continuous for the explicit ODE)
                y, _ = model.restart_state(b, y)
    except _TimeLimit:
        model.close()
        return _fail(f"{method}: more than {time_limit:g} s of CPU time")
    except RuntimeError as e:  # the model could not be evaluated where the solver went
        model.close()
        return _fail(f"{method}: {e}")
    counts = model.counts()
    traj = [(t, *model.end_effector(states[k])) for k, t in enumerate(times)]
    model.close()
    return {"traj": traj, "cpu_s": cpu, "steps": steps[0], "residual_evals": counts["rhs"],
            "jacobian_evals": njev, "solver_nfev": nfev, "error": None}


def run_lsoda(scene_path, rtol, atol, jacobian=True, time_limit=TIME_LIMIT_S):
    """scipy solve_ivp LSODA on the minimal formulation's explicit RHS (see the module doc)."""
    return _run_scipy("LSODA", scene_path, rtol, atol, jacobian, time_limit)


def run_radau(scene_path, rtol, atol, jacobian=True, time_limit=TIME_LIMIT_S):
    """scipy solve_ivp Radau (order 5) on the minimal formulation's explicit RHS."""
    return _run_scipy("Radau", scene_path, rtol, atol, jacobian, time_limit)


# --- DASPK (R deSolve) ---------------------------------------------------------------------------

def _run_r(script, tag, name, scene_path, formulation, rtol, atol, jacobian, time_limit):
    """Runs an R peer script (LIB SCENE FORMULATION RTOL ATOL OUT_CSV JACOBIAN OUTPUT_STEP) and
    reads its summary line `tag ok=1 ...` and its CSV into run_*'s dict (None on failure)."""
    if not shutil.which("Rscript"):
        return _fail("Rscript not found (ensure_installed())")
    try:
        lib = build_library()
    except RuntimeError as e:
        return _fail(str(e))
    fd, csv_path = tempfile.mkstemp(prefix=f"f3r_{name.lower()}_", suffix=".csv")
    os.close(fd)
    try:
        cmd = ["Rscript", "--vanilla", script, lib, os.path.abspath(scene_path), formulation,
               repr(_tol(rtol)), repr(_tol(atol)), csv_path, "1" if jacobian else "0", repr(OUTPUT_STEP)]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=time_limit + 30)
        except subprocess.TimeoutExpired:
            return _fail(f"{name}: more than {time_limit:g} s")
        line = next((l for l in p.stdout.splitlines() if l.startswith(tag + " ")), None)
        if line is None:
            return _fail(f"{name}: " + (p.stderr.strip() or p.stdout.strip())[-300:])
        fields = dict(kv.split("=", 1) for kv in line.split()[1:] if "=" in kv)
        if p.returncode != 0 or fields.get("ok") != "1":
            return _fail(f"{name}: " + line.split("error=", 1)[-1])
        traj = []
        with open(csv_path) as f:
            next(f)
            for row in f:
                t, x, y = (float(v) for v in row.split(","))
                traj.append((t, x, y))
    finally:
        os.unlink(csv_path)
    if not traj or not all(math.isfinite(v) for r in traj for v in r):
        return _fail(f"{name}: non-finite output")
    return {"traj": traj, "cpu_s": float(fields["cpu_s"]), "steps": int(fields["steps"]),
            "residual_evals": int(float(fields["residual_evals"])), "jacobian_evals": int(float(fields["jacobian_evals"])),
            "solver_nfev": int(fields["nre"]), "error": None}


def run_daspk(scene_path, rtol, atol, formulation="dae", jacobian=True, time_limit=TIME_LIMIT_S):
    """DASPK of R's deSolve on the core's residual in `formulation` (dae: GGL index 2 with the
    multipliers as index-2 variables; minimal: an implicit ODE). Runs bench/daspk.R."""
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation {formulation!r}: dae or minimal")
    return _run_r(R_SCRIPT, "F3R_DASPK", "DASPK", scene_path, formulation, rtol, atol, jacobian, time_limit)


# --- MEBDFI (R deTestSet) ------------------------------------------------------------------------

def run_mebdfi(scene_path, rtol, atol, jacobian=True, time_limit=TIME_LIMIT_S):
    """MEBDFI of R's deTestSet, the paper's solver, on the core's plain index-3 residual (q, W index
    1; v index 2; lambda index 3, MEBDFI's nind) with the core's Jacobian (jacobian=True) or
    MEBDFI's difference quotients. Runs bench/mebdfi.R; None with last_error "deTestSet is
    not installed ..." when deTestSet does not load (see have_mebdfi())."""
    return _run_r(MEBDFI_SCRIPT, "F3R_MEBDFI", "MEBDFI", scene_path, "index3", rtol, atol, jacobian, time_limit)


if __name__ == "__main__":  # a quick look: python3 bench/peers.py [SCENE [RTOL]]
    import argparse

    ap = argparse.ArgumentParser(description="A quick look: each peer once on SCENE at RTOL (atol RTOL/100), "
                                             "after installing what is missing (ensure_installed).")
    ap.add_argument("scene", nargs="?", default=os.path.join(ROOT, "config/scenes/paper_sim3_fixed_free.yaml"))
    ap.add_argument("rtol", nargs="?", type=float, default=1e-6)
    cli_args = ap.parse_args()
    scene, rtol = cli_args.scene, cli_args.rtol
    ensure_installed()
    for name, fn in (("MEBDFI index3", lambda: run_mebdfi(scene, rtol, rtol * 1e-2)),
                     ("DASPK dae", lambda: run_daspk(scene, rtol, rtol * 1e-2, formulation="dae")),
                     ("DASPK minimal", lambda: run_daspk(scene, rtol, rtol * 1e-2, formulation="minimal")),
                     ("LSODA", lambda: run_lsoda(scene, rtol, rtol * 1e-2)),
                     ("Radau", lambda: run_radau(scene, rtol, rtol * 1e-2))):
        r = fn()
        if r is None:
            print(f"{name:14s} failed: {last_error}")
        else:
            print(f"{name:14s} cpu {r['cpu_s']:.3f} s, steps {r['steps']}, evals {r['residual_evals']}, "
                  f"end ({r['traj'][-1][1]:.12f}, {r['traj'][-1][2]:.12f})")
