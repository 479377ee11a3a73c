#!/usr/bin/python3
"""Records 0.1 s of paper simulation 3 (fixed-free) through flex3rpr_node with launch/record.launch,
renders it in rviz under Xvfb with nodes/render_bag, and checks the result:

  bag_counts     rosbag info lists every recorded topic with its expected count: duration *
                 publish_rate + 1 on /clock, /tf, joint_states, ~status, ~beam_state, ~beams, ~odom,
                 one /tf_static, and at least one message on each command topic (a zero command
                 is published, latched, on all three before the run; a reconnection repeats it).
  platform_drawn in each frame the platform's colour (its URDF material) covers the platform's
                 triangle where the bag's TF and the rviz view (config/flex3rpr.rviz: top-down,
                 its scale and centre) put it, and its centroid is within 4 px of P.
  beams_drawn    in each frame the beams' colour (the ~beams marker colour) lies along each of the
                 three beams' TF stations, at least 60 px per beam away from the cylinders.
  frames_differ  the frames at 0.025 s and 0.1 s (P about 0.11 m apart) differ in the platform's
                 two regions, and the platform's centroid moved by the TF's displacement (+-4 px).

Exit 0 when all pass; otherwise 1 with a message per failure. --junit FILE writes JUnit XML
(for catkin's run_tests.py). Needs a sourced devel/setup.bash, Xvfb, rviz, ImageMagick.
Every process it starts is stopped at exit."""
import argparse
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from xml.sax.saxutils import escape

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCENE = os.path.join(ROOT, "config", "scenes", "paper_sim3_fixed_free.yaml")
CONFIG = os.path.join(ROOT, "config", "flex3rpr.rviz")
URDF = os.path.join(ROOT, "urdf", "flex3rpr.urdf")
DURATION, RATE = 0.1, 1000
TIMES = (0.025, 0.1)
OUTPUTS = ["/clock", "/tf", "/joint_states", "/flex3rpr_node/status", "/flex3rpr_node/beam_state",
           "/flex3rpr_node/beams", "/flex3rpr_node/odom"]
COMMANDS = {"/flex3rpr_node/command": ("flex3rpr/EffortCommand", "{}"),
            "/flex3rpr_node/effort_group/command": ("std_msgs/Float64MultiArray", "{data: [0, 0, 0, 0, 0, 0]}"),
            "/flex3rpr_node/platform_wrench": ("geometry_msgs/WrenchStamped", "{header: {frame_id: world}}")}
BACKGROUND = (48, 48, 48)
TOLERANCE = 30  # per channel, for the flat-lit colours

procs = []


def stop_all():
    while procs:
        p = procs.pop()
        if p.poll() is not None:
            continue
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(p.pid, sig)
                p.wait(5)
                break
            except ProcessLookupError:
                break
            except subprocess.TimeoutExpired:
                continue


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


class Checks:
    def __init__(self):
        self.cases = {}  # name -> list of failure messages
        self.settled = set()  # cases fully checked: a later crash does not touch them

    def case(self, name):
        self.cases.setdefault(name, [])

    def fail(self, name, msg):
        self.cases.setdefault(name, []).append(msg)
        print(f"FAIL {name}: {msg}", flush=True)

    def ok(self, name, msg):
        self.cases.setdefault(name, [])
        print(f"ok   {name}: {msg}", flush=True)

    def junit(self, path, seconds):
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        failures = sum(1 for f in self.cases.values() if f)
        lines = [f'<testsuite name="render_bag" tests="{len(self.cases)}" failures="{failures}" errors="0" '
                 f'time="{seconds:.1f}">']
        for name, fails in self.cases.items():
            lines.append(f'  <testcase classname="render_bag" name="{name}">')
            if fails:
                text = escape("\n".join(fails))
                lines.append(f'    <failure message="{escape(fails[0])}">{text}</failure>')
            lines.append("  </testcase>")
        lines.append("</testsuite>")
        with open(path, "w") as f:
            f.write("\n".join(lines) + "\n")


# --- geometry ---------------------------------------------------------------------------------------
def yaw(q):
    return 2.0 * math.atan2(q.z, q.w)


def state_at(bag_path, t):
    """Platform pose, C_i, the beam stations and the cylinders' ends (world, m) of the /tf stamped t."""
    import rosbag

    static, frames = {}, None
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, _ in bag.read_messages(topics=["/tf", "/tf_static"]):
            if topic == "/tf_static":
                for tf in msg.transforms:
                    tr = tf.transform.translation
                    static[(tf.header.frame_id, tf.child_frame_id)] = (tr.x, tr.y)
            elif msg.transforms and abs(msg.transforms[0].header.stamp.to_sec() - t) < 1e-7:
                frames = {tf.child_frame_id: (tf.transform.translation.x, tf.transform.translation.y,
                                              yaw(tf.transform.rotation)) for tf in msg.transforms}
    if frames is None:
        raise RuntimeError(f"no /tf stamped {t} s in {bag_path}")
    x, y, phi = frames["platform"]
    corners = []
    for i in (1, 2, 3):
        ox, oy = static[("platform", f"platform_c{i}")]
        corners.append((x + math.cos(phi) * ox - math.sin(phi) * oy, y + math.sin(phi) * ox + math.cos(phi) * oy))
    beams = []
    for i in (1, 2, 3):
        # station 0 is the piston (a static child of it): B_i = A_i + rho_i (cos, sin) theta_i
        ax, ay, theta = frames[f"leg_{i}_cylinder"]
        rho = frames[f"leg_{i}_piston"][0]
        root = (ax + rho * math.cos(theta), ay + rho * math.sin(theta))
        beams.append([root] + [frames[f"leg_{i}_beam_{k}"][:2] for k in range(1, 100) if f"leg_{i}_beam_{k}" in frames])
    return {"P": (x, y), "C": corners, "beams": beams}


def rviz_view(config):
    """Scale (px/m) and centre (m) of the top-down view in the rviz config."""
    import yaml

    with open(config) as f:
        cfg = yaml.safe_load(f)
    view = cfg["Visualization Manager"]["Views"]["Current"]
    if view["Class"] != "rviz/TopDownOrtho" or abs(float(view.get("Angle", 0))) > 1e-9:
        raise RuntimeError(f"{config}: the test expects an unrotated TopDownOrtho view")
    return float(view["Scale"]), (float(view["X"]), float(view["Y"]))


def view_box(img):
    """The 3D view: rows and columns with at least a quarter of background-coloured pixels."""
    import numpy as np

    mask = np.all(img == np.array(BACKGROUND), axis=2)
    rows = np.where(mask.sum(axis=1) > 0.25 * mask.shape[1])[0]
    cols = np.where(mask.sum(axis=0) > 0.25 * mask.shape[0])[0]
    if len(rows) == 0 or len(cols) == 0:
        return None
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


def colour_mask(img, rgb):
    import numpy as np

    return np.all(np.abs(img.astype(int) - np.array(rgb)) <= TOLERANCE, axis=2)


def segment_distance(px, py, a, b):
    """Distance of pixel coordinates (arrays) from the segment a-b (pixels)."""
    import numpy as np

    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy
    u = np.clip(((px - ax) * dx + (py - ay) * dy) / L2, 0.0, 1.0) if L2 > 0 else 0.0
    return np.hypot(px - (ax + u * dx), py - (ay + u * dy))


def urdf_colour(urdf, link_name):
    root = ET.parse(urdf).getroot()
    materials = {m.get("name"): m.find("color").get("rgba") for m in root.findall("material")
                 if m.find("color") is not None}
    for link in root.findall("link"):
        if link.get("name") == link_name:
            mat = link.find("visual").find("material")
            rgba = mat.find("color").get("rgba") if mat.find("color") is not None else materials[mat.get("name")]
            return tuple(round(255 * float(v)) for v in rgba.split()[:3])
    raise RuntimeError(f"{urdf}: no link {link_name}")


def marker_colour(bag_path):
    import rosbag

    with rosbag.Bag(bag_path) as bag:
        for _, msg, _ in bag.read_messages(topics=["/flex3rpr_node/beams"]):
            c = msg.markers[0].color
            return tuple(round(255 * v) for v in (c.r, c.g, c.b))
    raise RuntimeError("no ~beams in the bag")


# --- the test ---------------------------------------------------------------------------------------
def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--junit", help="write JUnit XML results here")
    ap.add_argument("--keep", help="keep the bag and the frames in this folder")
    args = ap.parse_args()
    t_start = time.time()
    checks = Checks()
    for name in ("bag_counts", "platform_drawn", "beams_drawn", "frames_differ"):
        checks.case(name)
    signal.signal(signal.SIGTERM, lambda *a: sys.exit(143))
    work = tempfile.mkdtemp(prefix="test_render_bag.")
    try:
        run(args, checks, work)
    except Exception as e:  # a crash is a failure of every case not yet fully checked
        for name, fails in checks.cases.items():
            if name not in checks.settled and not fails:
                checks.fail(name, f"not checked: {type(e).__name__}: {e}")
    finally:
        stop_all()
        if args.keep:
            os.makedirs(args.keep, exist_ok=True)
            for f in os.listdir(work):
                if f.endswith((".bag", ".png", ".log")):
                    shutil.copy(os.path.join(work, f), args.keep)
        shutil.rmtree(work, ignore_errors=True)
    seconds = time.time() - t_start
    if args.junit:
        checks.junit(args.junit, seconds)
    failed = [n for n, f in checks.cases.items() if f]
    print(f"test_render_bag: {len(checks.cases) - len(failed)} passed, {len(failed)} failed "
          f"({', '.join(failed) or 'none'}) in {seconds:.0f} s")
    return 1 if failed else 0


def run(args, checks, work):
    import numpy as np
    from PIL import Image

    for tool in ("roslaunch", "rosmaster", "rostopic", "rosbag", "Xvfb", "rviz", "/usr/bin/import"):
        if not shutil.which(tool):
            raise RuntimeError(f"{tool} not found (source devel/setup.bash; Debian packages xvfb rviz imagemagick)")
    env = dict(os.environ)
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    env["PYENV_VERSION"] = "system"
    env["ROS_HOSTNAME"] = "localhost"
    port = free_port()
    env["ROS_MASTER_URI"] = f"http://localhost:{port}/"
    env.setdefault("ROS_HOME", os.path.join(work, "ros_home"))
    bag = os.path.join(work, "paper_sim3_fixed_free.bag")

    # --- record ---------------------------------------------------------------------------------
    log = open(os.path.join(work, "record.log"), "w")
    procs.append(subprocess.Popen(["rosmaster", "--core", "-p", str(port)], env=env, stdin=subprocess.DEVNULL,
                                  stdout=log, stderr=subprocess.STDOUT, start_new_session=True))
    import rosgraph

    master = rosgraph.Master("/test_render_bag", master_uri=env["ROS_MASTER_URI"])
    deadline = time.time() + 120
    while not master.is_online():
        if time.time() > deadline:
            raise RuntimeError("the master did not start")
        time.sleep(0.1)
    for topic, (mtype, value) in COMMANDS.items():  # latched zero commands, delivered on connection
        procs.append(subprocess.Popen(["rostopic", "pub", "--latch", topic, mtype, value], env=env,
                                      stdin=subprocess.DEVNULL, stdout=log,
                                      stderr=subprocess.STDOUT, start_new_session=True))
    deadline = time.time() + 120
    while not all(t in {n for n, _ in master.getSystemState()[0]} for t in COMMANDS):
        if time.time() > deadline:
            raise RuntimeError("the command publishers did not come up")
        time.sleep(0.2)
    # Paced slowly and held long at both ends, so that rosbag record (100 messages a topic in its
    # queues, fixed in rosbag) keeps up on a loaded machine: the counts below then do not depend
    # on how the recorder was scheduled.
    cmd = ["roslaunch", "-p", str(port), "flex3rpr", "record.launch", f"scene:={SCENE}", f"bag:={bag}",
           f"duration:={DURATION}", f"publish_rate:={RATE}", "realtime_factor:=0.05", "subscriber_grace:=3.0"]
    if os.environ.get("F3R_NODE_LAUNCH_PREFIX"):
        cmd.append("launch_prefix:=" + os.environ["F3R_NODE_LAUNCH_PREFIX"])
    t0 = time.time()
    rc = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                        timeout=600).returncode
    print(f"recorded in {time.time() - t0:.1f} s (roslaunch exit {rc})", flush=True)
    stop_all()  # the command publishers and the master
    if not os.path.isfile(bag):
        log.flush()
        with open(os.path.join(work, "record.log"), errors="replace") as f:
            lines = [re.sub(r"\x1b\[[0-9;]*m", "", l).strip() for l in f]
        node = [l for l in lines if "flex3rpr_node:" in l or "ERROR" in l][-3:]
        if not any("has its subscribers" in l for l in lines):
            node.append("the node did not wait for the recorder (~wait_for_subscribers)")
        checks.fail("bag_counts", f"no {bag}" + (" (only .active: not closed)" if os.path.exists(bag + ".active")
                                                    else " (nothing recorded)") + f"; roslaunch exit {rc}; " + " | ".join(node))
        raise RuntimeError("no bag to render")

    import yaml

    info = yaml.safe_load(subprocess.run(["rosbag", "info", "--yaml", "--key", "topics", bag], env=env,
                                         capture_output=True, text=True, check=True).stdout) or []
    counts = {t["topic"]: t["messages"] for t in info}
    expected = {t: int(round(DURATION * RATE)) + 1 for t in OUTPUTS}
    expected["/tf_static"] = 1
    # The commands come from latched publishers outside the node: a latched message is delivered
    # again on every new connection, so how often the recorder saw it is not the node's doing.
    # Present is all that is asked of them.
    bad = {t: (counts.get(t, 0), n) for t, n in expected.items() if counts.get(t, 0) != n}
    bad.update({t: (counts.get(t, 0), ">= 1") for t in COMMANDS if counts.get(t, 0) < 1})
    expected.update({t: 1 for t in COMMANDS})
    extra = sorted(set(counts) - set(expected))
    if bad or extra:
        checks.fail("bag_counts", "topic: (found, expected) " + ", ".join(f"{t}: {v}" for t, v in bad.items())
                    + (f"; unexpected topics {extra}" if extra else ""))
    else:
        checks.ok("bag_counts", ", ".join(f"{t} {counts[t]}" for t in sorted(counts)))
    checks.settled.add("bag_counts")

    # --- render -------------------------------------------------------------------------------------
    frames_dir = os.path.join(work, "frames")
    t0 = time.time()
    r = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "nodes", "render_bag"), bag, "--at",
                        ",".join(str(t) for t in TIMES), "--out", frames_dir], env=env, stdin=subprocess.DEVNULL,
                       capture_output=True, text=True, timeout=900)
    with open(os.path.join(work, "render.log"), "w") as f:
        f.write(r.stdout + r.stderr)
    print(f"rendered in {time.time() - t0:.1f} s (exit {r.returncode})", flush=True)
    pngs = [os.path.join(frames_dir, "rviz_t%.3f.png" % t) for t in TIMES]
    if r.returncode != 0 or not all(os.path.isfile(p) for p in pngs):
        raise RuntimeError(f"render_bag failed (exit {r.returncode}): " + (r.stdout + r.stderr)[-1500:])
    for p in pngs:
        shutil.copy(p, work)

    # --- pixels ---------------------------------------------------------------------------------------
    scale, (vx, vy) = rviz_view(CONFIG)
    green, orange = urdf_colour(URDF, "platform"), marker_colour(bag)
    blue = urdf_colour(URDF, "leg_1_cylinder")
    if len({green, orange, blue, BACKGROUND}) < 4:
        raise RuntimeError(f"platform {green}, beams {orange}, cylinders {blue} and background are not distinct")
    centroids, states, images = [], [], []
    for t, png in zip(TIMES, pngs):
        img = np.asarray(Image.open(png).convert("RGB"))
        images.append(img)
        box = view_box(img)
        if box is None:
            raise RuntimeError(f"{png}: no 3D view (background {BACKGROUND}) found")
        cx, cy = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0

        def to_px(p):
            return cx + scale * (p[0] - vx), cy - scale * (p[1] - vy)

        s = state_at(bag, t)
        states.append((s, to_px))
        ys, xs = np.mgrid[0:img.shape[0], 0:img.shape[1]]
        inside = (xs >= box[0]) & (xs < box[2]) & (ys >= box[1]) & (ys < box[3])

        # platform: green along the triangle's sides, centroid at P
        g = colour_mask(img, green) & inside
        corners = [to_px(c) for c in s["C"]]
        near = np.zeros_like(g)
        for k in range(3):
            near |= segment_distance(xs, ys, corners[k], corners[(k + 1) % 3]) <= 0.006 * scale + 3
        on, off = int((g & near).sum()), int((g & ~near).sum())
        side_px = 0.1 * scale  # each side 0.1 m, drawn 12 mm wide
        pgx, pgy = to_px(s["P"])
        if on == 0:
            checks.fail("platform_drawn", f"t={t}: no platform colour {green} near the platform at ({pgx:.0f}, {pgy:.0f})")
            centroids.append(None)
            continue
        gy, gx = np.where(g & near)
        cen = (gx.mean(), gy.mean())
        centroids.append(cen)
        err = math.hypot(cen[0] - pgx, cen[1] - pgy)
        # the triangle's sides, 12 mm wide, less the joint spheres: at least half of 3 * side * width
        need = int(0.5 * 3 * side_px * 0.012 * scale)
        if on < need or off > 0.1 * on or err > 4.0:
            checks.fail("platform_drawn", f"t={t}: {on} platform pixels on its triangle (need {need}), {off} elsewhere, "
                        f"centroid ({cen[0]:.1f}, {cen[1]:.1f}) vs P ({pgx:.1f}, {pgy:.1f}): {err:.1f} px")
        else:
            checks.ok("platform_drawn", f"t={t}: {on} px on the triangle, {off} elsewhere, centroid {err:.1f} px from P")

        # beams: orange along each beam's stations, outside the cylinders
        o = colour_mask(img, orange) & inside
        for i, stations in enumerate(s["beams"]):
            pts = [to_px(p) for p in stations]
            near_b = np.zeros_like(o)
            for k in range(len(pts) - 1):
                near_b |= segment_distance(xs, ys, pts[k], pts[k + 1]) <= 6
            n = int((o & near_b).sum())
            if n < 60:
                checks.fail("beams_drawn", f"t={t}: beam {i + 1}: {n} px of {orange} along its stations (need 60)")
            else:
                checks.ok("beams_drawn", f"t={t}: beam {i + 1}: {n} px along its stations")

    # --- two frames ---------------------------------------------------------------------------------
    if all(c is not None for c in centroids):
        (s1, px1), (s2, px2) = states
        p1, p2 = px1(s1["P"]), px2(s2["P"])
        want = (p2[0] - p1[0], p2[1] - p1[1])
        got = (centroids[1][0] - centroids[0][0], centroids[1][1] - centroids[0][1])
        import numpy as np  # noqa: F811

        diff = np.any(images[0].astype(int) != images[1].astype(int), axis=2)
        ys, xs = np.mgrid[0:diff.shape[0], 0:diff.shape[1]]
        radius = 0.06 * scale
        changed = [int((diff & (np.hypot(xs - p[0], ys - p[1]) <= radius)).sum()) for p in (p1, p2)]
        err = math.hypot(got[0] - want[0], got[1] - want[1])
        if math.hypot(*want) < 20:
            checks.fail("frames_differ", f"P moved only {math.hypot(*want):.1f} px between {TIMES}: choose other times")
        elif min(changed) < 300 or err > 4.0:
            checks.fail("frames_differ", f"changed pixels around P at {TIMES}: {changed} (need 300 each); centroid moved "
                        f"({got[0]:.1f}, {got[1]:.1f}) px, TF says ({want[0]:.1f}, {want[1]:.1f})")
        else:
            checks.ok("frames_differ", f"{changed} pixels changed around P; the platform moved ({got[0]:.1f}, {got[1]:.1f}) "
                      f"px, TF ({want[0]:.1f}, {want[1]:.1f})")
    else:
        checks.fail("frames_differ", "the platform was not found in both frames")


if __name__ == "__main__":
    sys.exit(main())
