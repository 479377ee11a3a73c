#!/usr/bin/env python3
"""The install space works on its own (JUnit cases):

  catkin_make_install  `catkin_make install` in the test's workspace, then, in an environment
                       holding nothing but the install space's setup.bash: rospack finds the
                       package there, the messages import, rosrun runs the CLI, make_urdf.py
                       writes a URDF, and `roslaunch flex3rpr sim.launch` runs the node to its
                       duration and exits cleanly
  catkin_build         the same from `catkin build` with an install space in a fresh workspace
                       (catkin_tools; skipped with --no-catkin-build)
  catkin_lint          `catkin_lint --strict` on the source tree finds nothing, and the scripts it
                       is told to ignore as uninstalled are the checkout's own tools: the
                       benchmarks (bench/), the CI helpers (scripts/ci/) and the user's
                       commands in scripts/
  roslaunch_check      roslaunch-check on every launch file: each package it uses is a dependency
  launch_clock         every launch file sets /use_sim_time true by default
  launch_arguments     sim.launch's end_stops, paused, accuracy and tf_prefix reach the node
  rosdep_keys          each package.xml dependency is a ROS package or a known rosdep key whose
                       Debian package is installed

usage: install_space.py --junit FILE --workspace WS [--no-catkin-build]"""
import argparse
import re
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time

# the repository itself, not the workspace's folder of links to it (catkin_lint does not walk links)
ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "nodes"))
import flex3rpr_tools  # noqa: E402  (nodes/: JUnit)
# The sanitizers' settings pass into the clean environment (an instrumented node needs them).
KEEP = ("HOME", "ROS_HOME", "ASAN_OPTIONS", "LSAN_OPTIONS", "UBSAN_OPTIONS")
# what a devel space's setup sets (catkin's setup_cached.sh)
DEVEL_SETUP = ("CMAKE_PREFIX_PATH", "LD_LIBRARY_PATH", "PKG_CONFIG_PATH", "PYTHONPATH", "ROS_DISTRO", "ROS_ETC_DIR",
               "ROS_MASTER_URI", "ROS_PACKAGE_PATH", "ROS_PYTHON_VERSION", "ROS_VERSION", "ROSLISP_PACKAGE_DIRECTORIES")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def clean_shell(setup, script, timeout):
    """Runs script in bash with only the install space's setup.bash sourced."""
    env = {k: os.environ[k] for k in KEEP if k in os.environ}
    env["PATH"] = "/usr/bin:/bin"
    p = subprocess.run(["/bin/bash", "-c", f"set -e; source '{setup}'; {script}"], env=env, capture_output=True,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


def check_install(prefix):
    """The install space alone runs the package. Returns a failure message or ''."""
    setup = os.path.join(prefix, "setup.bash")
    if not os.path.exists(setup):
        return f"no {setup}"
    share = os.path.join(prefix, "share", "flex3rpr")
    rc, out = clean_shell(setup, "rospack find flex3rpr", 120)
    if rc != 0 or out.strip() != share:
        return f"rospack find flex3rpr gave '{out.strip()}', expected {share}"
    rc, out = clean_shell(setup, "echo $ROS_PACKAGE_PATH:$CMAKE_PREFIX_PATH:$LD_LIBRARY_PATH:$PYTHONPATH", 120)
    stray = [e for e in out.strip().split(":") if e and not (e.startswith(prefix) or e.startswith("/usr"))]
    if stray:
        return "the clean environment reaches beyond the install space: " + " ".join(stray)
    checks = [
        ("/usr/bin/python3 -c 'from flex3rpr.msg import SimStatus, EffortCommand, BeamState; print(SimStatus._type)'",
         "flex3rpr/SimStatus"),
        ("rosmsg show flex3rpr/SimStatus", "outside_stroke"),
        ("rosrun flex3rpr flex3rpr_sim --geometry $(rospack find flex3rpr)/config/scenes/rest.yaml", "stroke_max"),
        ("rosrun flex3rpr make_urdf.py --beam-points 4 --prefix r1", "r1/leg_3_beam_3"),
        # the bag, sweep and Slurm tools, with their package files found in share/flex3rpr
        ("rosrun flex3rpr render_bag --help | tr -d '\\n '", f"{share}/config/flex3rpr.rviz"),
        ("rosrun flex3rpr plot_bag --help", "usage"),
        ("rosrun flex3rpr sweep --help", "Slurm"),
        ("rosrun flex3rpr plot_sweep --help", "usage"),
        ("rosrun flex3rpr slurm_cluster status /tmp/f3r_no_such_cluster || true", "no such directory"),
        ("ls $(rospack find flex3rpr)/config/flex3rpr.rviz $(rospack find flex3rpr)/launch/paper_sim1.launch",
         "paper_sim1.launch"),
    ]
    for command, expect in checks:
        rc, out = clean_shell(setup, command, 300)
        if rc != 0 or expect not in out:
            return f"`{command}` from the install space (exit {rc}):\n{out[-3000:]}"
    port = free_port()
    rc, out = clean_shell(setup, f"roslaunch -p {port} flex3rpr sim.launch duration:=0.2 realtime_factor:=0 "
                                 "required:=true 2>&1", 900)
    if "reached the duration" not in out or "flex3rpr_node-" not in out:
        return f"roslaunch flex3rpr sim.launch from the install space (exit {rc}):\n{out[-4000:]}"
    if "lib/flex3rpr/flex3rpr_node" in out and prefix not in out:
        return "the node did not come from the install space:\n" + out[-3000:]
    return ""


def case_catkin_make_install(workspace):
    workspace = os.path.abspath(workspace)
    # catkin_make takes the workspace from $PWD. It runs without what the devel space's setup put
    # into this test's environment: should it re-run cmake in the workspace the other tests use,
    # catkin writes only what differs from the environment into their setup (setup_cached.sh),
    # which would then hold nothing, and the tests after this one would not find the package.
    env = {k: v for k, v in os.environ.items() if k not in DEVEL_SETUP}
    env["PWD"] = workspace
    p = subprocess.run(["catkin_make", "install", "-j2"], cwd=workspace, env=env, capture_output=True, text=True,
                       timeout=1800)
    if p.returncode != 0:
        return "catkin_make install failed:\n" + (p.stdout + p.stderr)[-4000:]
    return check_install(os.path.join(workspace, "install"))


def case_catkin_build():
    ws = tempfile.mkdtemp(prefix="f3r_catkin_build_")
    try:
        pkg = os.path.join(ws, "src", "flex3rpr")
        os.makedirs(pkg)
        for entry in os.listdir(ROOT):  # as scripts/build: the package without its build outputs
            if entry not in ("build", "output", ".git"):
                os.symlink(os.path.join(ROOT, entry), os.path.join(pkg, entry))
        # nothing of the test's own workspace: it would become the new one's underlay
        env = {k: os.environ[k] for k in KEEP if k in os.environ}
        env["PATH"] = "/usr/bin:/bin"
        # CMAKE_BUILD_TYPE=None and F3R_LTO=OFF: no optimisation and no link-time pass, which
        # together take the build from 2:50 to 1:36 of CPU on the 2-core machine; what this case
        # checks is how catkin_tools builds and installs, and the node runs only 0.2 s here.
        for cmd in (["catkin", "init"], ["catkin", "config", "--install"],
                    ["catkin", "build", "--no-status", "--no-notify", "-j2", "flex3rpr", "--cmake-args",
                     "-DCMAKE_BUILD_TYPE=None", "-DF3R_LTO=OFF", "-DPYTHON_EXECUTABLE=/usr/bin/python3",
                     "-DCATKIN_ENABLE_TESTING=OFF"]):
            p = subprocess.run(cmd, cwd=ws, env=env, capture_output=True, text=True, timeout=3600)
            if p.returncode != 0:
                return f"{' '.join(cmd)} failed:\n" + (p.stdout + p.stderr)[-4000:]
        return check_install(os.path.join(ws, "install"))
    finally:
        shutil.rmtree(ws, ignore_errors=True)


# Executables that work on the source tree and its build/ folder and so are not installed; the
# pragma in CMakeLists.txt silences catkin_lint on exactly these. They are sorted by folder: the
# benchmarks in bench/, the CI helpers in scripts/ci/, and the commands a user runs in a checkout
# (scripts/; what rosrun starts is in nodes/, all installed).
CHECKOUT_FOLDERS = ("bench/", "scripts/ci/")
CHECKOUT_COMMANDS = {"scripts/install_deps", "scripts/build", "scripts/build_sundials", "scripts/demo"}


def uninstalled_misfiled(ignored):
    """Of catkin_lint's uninstalled executables (paths in the package), those that are neither
    in a checkout folder nor a checkout command: a rosrun tool left out of the install, or a
    benchmark or CI helper filed in scripts/."""
    return sorted(p for p in ignored if p not in CHECKOUT_COMMANDS and not p.startswith(CHECKOUT_FOLDERS))


def case_catkin_lint():
    """catkin_lint --strict on the source tree itself (the workspace's package is a folder of
    links, which catkin_lint does not walk into), and the only uninstalled executables it
    ignores are the checkout's own tools: those in bench/ and scripts/ci/, and the user's
    commands in scripts/."""
    p = subprocess.run(["catkin_lint", "--strict", ROOT], capture_output=True, text=True, timeout=600)
    if p.returncode != 0 or "found 0 problems" not in p.stdout + p.stderr:
        return "catkin_lint --strict:\n" + p.stdout + p.stderr
    p = subprocess.run(["catkin_lint", "--strict", "--show-ignored", ROOT], capture_output=True, text=True,
                       timeout=600)
    ignored = set(re.findall(r"file '([^']+)' is executable but not installed", p.stdout + p.stderr))
    misfiled = uninstalled_misfiled(ignored)
    if misfiled:
        return (f"uninstalled executables {misfiled} are in none of {', '.join(CHECKOUT_FOLDERS)} and not a "
                f"user's command in scripts/: install them (catkin_install_python) or move them")
    stale = sorted(CHECKOUT_COMMANDS - ignored)
    if stale:
        return f"{stale} are no longer uninstalled executables: update CHECKOUT_COMMANDS"
    for folder in CHECKOUT_FOLDERS:
        if not any(p.startswith(folder) for p in ignored):
            return f"catkin_lint names no uninstalled executable in {folder}: update CHECKOUT_FOLDERS"
    return ""


def case_rosdep_keys():
    """Each dependency of package.xml is a ROS package on this machine, or a rosdep key of
    rosdistro (test/rosdep_keys.yaml) or of rosdep/flex3rpr.yaml whose Debian package is installed."""
    import xml.etree.ElementTree as ET
    import yaml
    known = yaml.safe_load(open(os.path.join(ROOT, "test", "rosdep_keys.yaml")))
    ours = {k: v["debian"] for k, v in yaml.safe_load(open(os.path.join(ROOT, "rosdep", "flex3rpr.yaml"))).items()}
    tags = ("depend", "build_depend", "exec_depend", "test_depend", "buildtool_depend")
    keys = {e.text.strip() for e in ET.parse(os.path.join(ROOT, "package.xml")).getroot() if e.tag in tags}
    for key in sorted(keys):
        found = subprocess.run(["rospack", "find", key], capture_output=True, text=True)
        # A catkin package: rosdep resolves it through the ROS distribution. (Debian's urdfdom
        # ships a package.xml too, but is a plain CMake package: its key is liburdfdom-dev.)
        if found.returncode == 0 and key == "catkin" or found.returncode == 0 and re.search(r"<buildtool_depend[^>]*>\s*catkin\s*<",
                                               open(os.path.join(found.stdout.strip(), "package.xml")).read()):
            continue
        debs = known.get(key) or ours.get(key)
        if not debs:
            return f"package.xml: '{key}' is neither a ROS package nor a rosdep key (test/rosdep_keys.yaml, rosdep/flex3rpr.yaml)"
        for deb in debs:
            st = subprocess.run(["dpkg-query", "-W", "-f=${Status}", deb], capture_output=True, text=True)
            if "install ok installed" not in st.stdout:
                return f"package.xml: key '{key}' resolves to the Debian package {deb}, which is not installed"
    return ""


def dump_params(path, *args):
    """The parameters roslaunch would set for a launch file (--dump-params, no master needed):
    a dict, or the failure's output as a string."""
    import yaml
    p = subprocess.run(["roslaunch", "--dump-params", path, *args], capture_output=True, text=True, timeout=600)
    params = yaml.safe_load(p.stdout) if p.returncode == 0 else None
    return params if isinstance(params, dict) else (p.stdout[-2000:] + p.stderr[-2000:])


def case_launch_clock():
    """Every launch file runs on simulated time by default: /use_sim_time is true."""
    import glob
    for path in sorted(glob.glob(os.path.join(ROOT, "launch", "*.launch"))):
        params = dump_params(path, "bag:=/tmp/none.bag")
        if not isinstance(params, dict):
            return f"roslaunch --dump-params {os.path.basename(path)} failed:\n{params}"
        if params.get("/use_sim_time") is not True:
            return f"{os.path.basename(path)}: /use_sim_time is {params.get('/use_sim_time')} by default, not true"
    return ""


def case_launch_arguments():
    """sim.launch hands its arguments to the node's parameters that the rostests exercise
    (end stops, start paused, the accuracy knob, the frame prefix)."""
    args = {"end_stops": ("true", True), "paused": ("true", True), "accuracy": ("1e-4", 1e-4),
            "tf_prefix": ("robot1", "robot1")}
    params = dump_params(os.path.join(ROOT, "launch", "sim.launch"), *[f"{k}:={v}" for k, (v, _) in args.items()])
    if not isinstance(params, dict):
        return "roslaunch --dump-params sim.launch failed:\n" + params
    for k, (_, want) in args.items():
        if params.get("/flex3rpr_node/" + k) != want:
            return f"sim.launch {k}:= gives ~{k} = {params.get('/flex3rpr_node/' + k)!r}, not {want!r}"
    return ""


def case_roslaunch_check():
    """Every launch file's packages are dependencies in package.xml (rviz with rviz:=true)."""
    import glob
    for path in sorted(glob.glob(os.path.join(ROOT, "launch", "*.launch"))):
        p = subprocess.run(["/usr/bin/python3", "/usr/share/roslaunch/scripts/roslaunch-check", path,
                            "bag:=/tmp/none.bag", "rviz:=true"], capture_output=True, text=True, timeout=600)
        if p.returncode != 0 or "passed" not in p.stdout:
            return f"roslaunch-check {os.path.basename(path)}:\n" + p.stdout + p.stderr
    return ""


def main():
    a = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    a.add_argument("--junit", required=True)
    a.add_argument("--workspace", required=True)
    a.add_argument("--no-catkin-build", action="store_true")
    args = a.parse_args()
    cases = [("catkin_lint", case_catkin_lint),
             ("roslaunch_check", case_roslaunch_check),
             ("launch_clock", case_launch_clock),
             ("launch_arguments", case_launch_arguments),
             ("rosdep_keys", case_rosdep_keys),
             ("catkin_make_install", lambda: case_catkin_make_install(args.workspace))]
    junit = []
    if not args.no_catkin_build:
        if shutil.which("catkin"):
            cases.append(("catkin_build", case_catkin_build))
        else:  # a skip, said as one: the case could not run here, so it did not pass
            print("SKIP catkin_build: catkin_tools is not installed (python3-catkin-tools)")
            junit.append(("install_space", "catkin_build", None,
                          "catkin_tools is not installed (python3-catkin-tools)"))
    for name, run in cases:
        start = time.time()
        try:
            why = run()
        except Exception as e:  # a hung or crashed step is a failure, with its reason
            why = f"{type(e).__name__}: {e}"
        print(f"{'ok  ' if not why else 'FAIL'} {name} ({time.time() - start:.0f} s)" + (f"\n{why}" if why else ""))
        junit.append(("install_space", name, why or None))
    failed = flex3rpr_tools.write_junit(args.junit, "install_space", junit)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
