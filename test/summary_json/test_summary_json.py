#!/usr/bin/python3
"""flex3rpr_sim --summary-json: the JSON parses, has every key, and its numbers are the human
summary's (each JSON number, printed with the human summary's own format, gives the printed text;
the human text is parsed here, in the test, and nowhere in scripts/ or bench/):
- paper simulation 1, JSON on stdout (-) with the human summary on stderr, and the same into a file
  with the human summary on stdout;
- the accuracy knob at 1e-4 m on paper simulations 1 and 3 (fixed-free) with the links' mode counts
  taken out, so that the knob chooses them: its modes, static shapes, exact kinematics, solver,
  estimates, request_met and choice CPU time;
- failures still write the JSON with an error object (status, message) and exit non-zero: a bad
  option, a bad --set, a leg collapse during the run, an unwritable CSV.

usage: test_summary_json.py --sim FLEX3RPR_SIM [--junit FILE]"""
import argparse
import json
import os
import re
import sys
import tempfile
import unittest

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "nodes"))
import flex3rpr_tools as T  # noqa: E402

ARGS = None
KEYS = {
    "top": {"format", "scene", "exit_code", "error", "settings", "accuracy", "run"},
    "settings": {"formulation", "integrator", "integrator_text", "jacobian", "table", "rtol", "atol",
                 "max_bdf_order", "exact_kinematics", "sundials_version", "sundials_build", "link_basis",
                 "state_dimension", "nq", "duration_s", "output_step_s", "beam_points"},
    "run": {"simulated_time_s", "steps", "residual_evals", "jacobian_evals", "cpu_time_s", "wall_time_s",
            "integration_wall_time_s", "outputs_wall_time_s", "real_time_factor_cpu", "real_time_factor_wall_integration",
            "real_time_factor_wall",
            "max_constraint_residual_m", "energy_balance_error_J", "energy_balance_relative", "max_deflection_m",
            "max_tip_deflection_m", "final_x_p_m", "final_y_p_m", "final_phi_p_rad", "csv", "energy_guard",
            "check_cpu_time_s"},
    "accuracy": {"request_m", "rigid", "modes", "static_correction", "static_shapes", "shape_mix", "model_error_m",
                 "extent_m",
                 "linear_evaluations", "choice_cpu_time_s", "exact_kinematics", "formulation", "integrator", "table",
                 "rtol", "atol", "kinematics_error_m", "kinematics_effect_m", "kinematics_linear_m", "solver_error_m",
                 "pilot", "pilot_ratio", "estimated_error_m", "measured_error_m", "error_basis", "configurations",
                 "request_met", "summary", "brief"},
}


def scene(name):
    return os.path.join(ROOT, "config", "scenes", name + ".yaml")


def open_scene(name, directory):
    """The shipped scene without its links' mode counts, as bench/accuracy_knob gives it to the
    knob (here through PyYAML)."""
    with open(scene(name)) as f:
        data = yaml.safe_load(f)
    links = data.get("links")
    for link in links if isinstance(links, list) else [links]:
        if isinstance(link, dict):
            link.pop("modes", None)
    path = os.path.join(directory, name + ".open.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(data, f)
    return path


def human_lines(text):
    """The human summary's 'key   value' lines: key -> value (the first of each key)."""
    lines = {}
    for line in text.splitlines():
        m = re.match(r"^(\S.*?)\s{2,}(\S.*)$", line)
        if m and m.group(1) not in lines:
            lines[m.group(1)] = m.group(2)
    return lines


def g(value, spec):
    """A JSON number as C's printf prints it with spec; null (non-finite) as printf's inf."""
    return "inf" if value is None else format(value, spec)


class Summary(unittest.TestCase):
    def check_keys(self, summary, *objects):
        self.assertEqual(set(summary), KEYS["top"])
        for name in objects:
            self.assertIsInstance(summary[name], dict, name)
            self.assertEqual(set(summary[name]), KEYS[name], name)

    def check_run_numbers(self, summary, human):
        """Every number of the human summary against the JSON's, at the human's precision."""
        h, s, r = human_lines(human), summary["settings"], summary["run"]
        self.assertEqual(h["scene"], summary["scene"])
        self.assertEqual(h["formulation"], f"{s['formulation']}, rtol {g(s['rtol'], 'g')}, "
                                           f"atol {g(s['atol'], 'g')}, {s['integrator_text']}")
        if s["integrator"] == "ida":
            self.assertEqual(h["max BDF order"], str(s["max_bdf_order"]))
        else:
            self.assertEqual(h["butcher table"], s["table"])
        self.assertEqual(h["sundials"], f"{s['sundials_version']}, {s['sundials_build']}")
        self.assertEqual(h["links"], "; ".join(s["link_basis"]))
        self.assertEqual(h["state dimension"], f"{s['state_dimension']} (nq {s['nq']})")
        self.assertEqual(h["simulated time"], f"{g(r['simulated_time_s'], '.6g')} s")
        self.assertEqual(h["steps"], str(r["steps"]))
        self.assertEqual(h["residual evals"], str(r["residual_evals"]))
        self.assertEqual(h["jacobian evals"], str(r["jacobian_evals"]))
        # every time names its clock (issue 28, item 5): the process CPU clock for the whole run,
        # the monotonic (wall) clock for the run and its split
        self.assertEqual(h["cpu time"], f"{g(r['cpu_time_s'], '.6f')} s (process CPU clock, the whole run)")
        self.assertEqual(h["wall time"], f"{g(r['wall_time_s'], '.6f')} s (monotonic clock; integration "
                                         f"{g(r['integration_wall_time_s'], '.6f')} s, computing outputs "
                                         f"{g(r['outputs_wall_time_s'], '.6f')} s)")
        self.assertEqual(h["real-time factor"], f"{g(r['real_time_factor_cpu'], '.3g')} of cpu time (of wall time: "
                                                f"{g(r['real_time_factor_wall_integration'], '.3g')} integrating, "
                                                f"{g(r['real_time_factor_wall'], '.3g')} with the outputs)")
        # each factor is the simulated time over its own clock's time
        t = r["simulated_time_s"]
        self.assertAlmostEqual(r["real_time_factor_cpu"], t / r["cpu_time_s"], delta=1e-12 * r["real_time_factor_cpu"])
        self.assertAlmostEqual(r["real_time_factor_wall_integration"], t / r["integration_wall_time_s"],
                               delta=1e-12 * r["real_time_factor_wall_integration"])
        self.assertAlmostEqual(r["real_time_factor_wall"], t / (r["integration_wall_time_s"] + r["outputs_wall_time_s"]),
                               delta=1e-12 * r["real_time_factor_wall"])
        self.assertEqual(h["max constraint res"], f"{g(r['max_constraint_residual_m'], '.3e')} m")
        self.assertEqual(h["energy balance err"], f"{g(r['energy_balance_error_J'], '.3e')} J "
                                                  f"({g(r['energy_balance_relative'], '.3e')} of max T+V)")
        self.assertEqual(h["max deflection"], f"{g(r['max_deflection_m'], '.6e')} m (largest |w| at "
                                              f"{s['beam_points']} stations a link; at the tips "
                                              f"{g(r['max_tip_deflection_m'], '.6e')} m)")
        self.assertEqual(h["final pose"], f"x_p {g(r['final_x_p_m'], '.9f')} y_p {g(r['final_y_p_m'], '.9f')} "
                                          f"phi_p {g(r['final_phi_p_rad'], '.9f')}")
        if r["csv"]:
            self.assertEqual(h["csv"], r["csv"])

    def check_choice_numbers(self, summary, human):
        """The knob's summary text against the JSON's accuracy object."""
        k = summary["accuracy"]
        m = re.search(r"^accuracy (\S+) m on the end-effector path", human, re.M)
        self.assertEqual(m.group(1), g(k["request_m"], "g"))
        for i in range(3):
            line = re.search(rf"^links\[{i}\]: (.*)$", human, re.M).group(1)
            if k["rigid"][i]:
                self.assertEqual(line, "rigid")
                continue
            m = re.match(r"(\d+) modes?(?: \+ (\d+) static shapes?(?: \(tip force \+ (\S+) uniform load\))?)?",
                         line)
            self.assertEqual(int(m.group(1)), k["modes"][i])
            self.assertEqual(bool(m.group(2)), k["static_correction"][i])
            self.assertEqual(int(m.group(2) or 0), k["static_shapes"][i])
            if m.group(3):  # one mixed shape: its load ratio, to the 3 digits the text gives
                self.assertEqual(g(k["shape_mix"][i], ".3g"), m.group(3))
            else:
                self.assertIsNone(k["shape_mix"][i])
        ek = re.search(r"^exact kinematics: (on|off)", human, re.M)
        if ek:
            self.assertEqual(ek.group(1) == "on", k["exact_kinematics"])
        table = f" {k['table']}" if k["table"] else ""
        m = re.search(r"^solver: (\S+), (\S+?)( \S+)?, rtol (\S+), atol (\S+?):", human, re.M)
        self.assertIsNotNone(m, human)
        self.assertEqual((m.group(1), m.group(2), m.group(3) or ""),
                         (k["formulation"], k["integrator"], table))
        self.assertEqual((m.group(4), m.group(5)), (g(k["rtol"], "g"), g(k["atol"], "g")))
        m = re.search(r"^estimated error (\S+) m \(model (\S+), kinematics (\S+), solver (\S+)\)", human, re.M)
        self.assertEqual(m.groups(), tuple(g(k[f], ".3g") for f in ("estimated_error_m", "model_error_m",
                                                                       "kinematics_error_m", "solver_error_m")))
        m = re.search(r"^accuracy\s+measured (\S+) m against a richer run \(estimate (\S+) m\); request (\S+) m "
                      r"(met|NOT met) \(measured, within 0.7 of it\)$", human, re.M)
        if k["error_basis"] == "measured":
            self.assertEqual(m.groups(), (g(k["measured_error_m"], ".3g"), g(k["estimated_error_m"], ".3g"),
                                          g(k["request_m"], "g"), "met" if k["request_met"] else "NOT met"))
        else:
            self.assertIsNone(m)
            self.assertIsNone(k["measured_error_m"])
            self.assertEqual("\nnot met: " not in human, k["request_met"])
        m = re.search(r"^pilot: .* scale the linear estimate by (\S+)$", human, re.M)
        if m:
            self.assertTrue(k["pilot"])
            self.assertEqual(m.group(1), g(k["pilot_ratio"], ".3g"))
        m = re.search(r"^choice cpu time\s+(\S+) s \((\d+) linear models\)", human, re.M)
        self.assertEqual((m.group(1), int(m.group(2))), (g(k["choice_cpu_time_s"], ".6f"), k["linear_evaluations"]))
        self.assertIn(k["summary"], human)

    def test_a_paper_sim1_on_stdout(self):
        summary, p = T.run_sim(ARGS.sim, scene("paper_sim1"))
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIsNotNone(summary, p.stdout)
        self.check_keys(summary, "settings", "run")
        self.assertIsNone(summary["error"])
        self.assertIsNone(summary["accuracy"])
        self.assertEqual(summary["exit_code"], 0)
        self.check_run_numbers(summary, p.stderr)

    def test_b_paper_sim1_into_a_file(self):
        with tempfile.TemporaryDirectory() as tmp:
            path, out = os.path.join(tmp, "summary.json"), os.path.join(tmp, "run.csv")
            p = T.run([ARGS.sim, scene("paper_sim1"), "--out", out, "--summary-json", path])
            self.assertEqual(p.returncode, 0, p.stderr)
            with open(path) as f:
                summary = json.load(f)
        self.check_keys(summary, "settings", "run")
        self.assertEqual(summary["run"]["csv"], out)
        self.check_run_numbers(summary, p.stdout)

    def test_c_the_accuracy_knob(self):
        with tempfile.TemporaryDirectory() as tmp:
            for name in ("paper_sim1", "paper_sim3_fixed_free"):
                with self.subTest(scene=name):
                    summary, p = T.run_sim(ARGS.sim, open_scene(name, tmp), "--accuracy", "1e-4")
                    self.assertEqual(p.returncode, 0, p.stderr)
                    self.check_keys(summary, "settings", "run", "accuracy")
                    self.assertEqual(summary["accuracy"]["request_m"], 1e-4)
                    self.check_choice_numbers(summary, p.stderr)
                    self.check_run_numbers(summary, p.stderr)
                    # the choice is what ran
                    k, s = summary["accuracy"], summary["settings"]
                    self.assertEqual((s["formulation"], s["integrator"], s["rtol"], s["atol"], s["exact_kinematics"]),
                                     (k["formulation"], k["integrator"], k["rtol"], k["atol"], k["exact_kinematics"]))

    def test_f_the_request_is_measured(self):
        """The knob's run is measured against a richer one: measured_error_m, error_basis and the
        check's CPU time; --no-verify leaves the estimate alone, and says so."""
        with tempfile.TemporaryDirectory() as tmp:
            path = open_scene("paper_sim3_fixed_free", tmp)
            summary, p = T.run_sim(ARGS.sim, path, "--accuracy", "1e-4")
            self.assertEqual(p.returncode, 0, p.stderr)
            k, r = summary["accuracy"], summary["run"]
            self.assertEqual(k["error_basis"], "measured")
            self.assertLessEqual(k["measured_error_m"], 0.7 * 1e-4, "within the check's margin")
            self.assertGreater(k["measured_error_m"], 0.0)
            self.assertTrue(k["request_met"])
            self.assertEqual(k["configurations"], 2)
            self.assertGreater(r["check_cpu_time_s"], 0.0)
            self.check_choice_numbers(summary, p.stderr)
            summary, p = T.run_sim(ARGS.sim, path, "--accuracy", "1e-4", "--no-verify")
            self.assertEqual(p.returncode, 0, p.stderr)
            k = summary["accuracy"]
            self.assertEqual(k["error_basis"], "estimated")
            self.assertIsNone(k["measured_error_m"])
            self.assertIsNone(summary["run"]["check_cpu_time_s"])
            self.assertIn("not measured (accuracy.verify is off)", p.stderr)
            self.check_choice_numbers(summary, p.stderr)

    def test_g_a_miss_escalates_or_says_so(self):
        """resonance.yaml driven for 0.5 s at 1e-5 m: the knob's choice misses (the resonance builds
        up late, where no estimate looks); the next configuration meets it. With no escalation
        allowed the run exits 3, names the request and the measured error, and still writes the
        path it measured."""
        with tempfile.TemporaryDirectory() as tmp:
            path, csv = open_scene("resonance", tmp), os.path.join(tmp, "run.csv")
            base = [path, "--accuracy", "1e-5", "--duration", "0.5", "--out", csv]
            summary, p = T.run_sim(ARGS.sim, *base)
            self.assertEqual(p.returncode, 0, p.stderr)
            k = summary["accuracy"]
            self.assertTrue(k["request_met"], p.stderr)
            self.assertGreaterEqual(k["configurations"], 3, p.stderr)
            self.assertLessEqual(k["measured_error_m"], 0.7 * 1e-5)
            summary, p = T.run_sim(ARGS.sim, *base, "--set", "accuracy.escalations=0")
            self.assertEqual(p.returncode, 3, p.stderr)
            self.assertEqual(summary["exit_code"], 3)
            k = summary["accuracy"]
            self.assertFalse(k["request_met"])
            self.assertGreater(k["measured_error_m"], 0.7 * 1e-5)
            self.assertIn(f"the accuracy request 1e-05 m is not met: measured {k['measured_error_m']:.3g} m", p.stderr)
            with open(csv) as f:
                self.assertEqual(sum(1 for _ in f), 1 + 1 + 5000, "the header, t = 0 and every output")

    def test_g2_a_path_past_impacts_is_not_chased(self):
        """A 40 N push drives leg 1 into its stop (restitution 0.3) under a 180 Hz torque on
        link 2, 0.1 s, at 1e-6 m with the modes chosen: the measured error stops shrinking from
        one configuration to the next (4.6e-6, then 3.6e-6 m), so escalation stops there and the
        run exits 3 naming the impacts and the first one's time, instead of running on for
        minutes."""
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "impacts.yaml")
            with open(path, "w") as f:
                f.write("links: {model: fixed_free, modes: auto, damping_ratio: 0.01}\n"
                        "effects:\n"
                        "  joint_friction: {prismatic: [5.0, 5.0, 5.0], revolute: [0.01, 0.01, 0.01]}\n"
                        "  end_stops: {min: 0.0, max: 0.2, restitution: 0.3}\n"
                        "initial: {platform_pose: [0.0, 0.0, 0.3]}\n"
                        "inputs:\n  rho_1: {offset: 40}\n"
                        "  theta_2: {amplitude: 0.5, frequency: 180}\n"
                        "run: {duration: 0.1, output_step: 1e-3}\n")
            summary, p = T.run_sim(ARGS.sim, path, "--accuracy", "1e-6")
            self.assertEqual(p.returncode, 3, p.stderr)
            self.assertFalse(summary["accuracy"]["request_met"])
            self.assertLessEqual(summary["accuracy"]["configurations"], 4, p.stderr)
            self.assertIn("escalation stopped: the measured error did not shrink", p.stderr)
            self.assertRegex(p.stderr, r"\d+ end-stop impacts, the first at t = 0\.0\d+ s")

    def test_h_the_energy_guard(self):
        """Two configurations known to exit 0 with garbage trip the guard; a correct run does not."""
        # (Verner 6(5) at rtol 1e-4 was the explicit one until its steps evaluated all their
        # stages, #59; Dormand-Prince 5(4), whose last stage is its solution, is unchanged)
        for args in (["--erk", "--table", "ARKODE_DORMAND_PRINCE_7_4_5", "--rtol", "3e-2"],
                     ["--ida", "--max-order", "3", "--rtol", "1e-3"]):
            with self.subTest(args=args):
                summary, p = T.run_sim(ARGS.sim, scene("paper_sim3_fixed_free"), *args)
                self.assertTrue(summary["run"]["energy_guard"], p.stderr)
                self.assertGreater(summary["run"]["energy_balance_relative"], 0.1)
                self.assertIn("warning", p.stderr)
                self.assertIn("the energy balance error reached", p.stderr)
        summary, p = T.run_sim(ARGS.sim, scene("paper_sim3_fixed_free"))
        self.assertFalse(summary["run"]["energy_guard"])
        self.assertNotIn("energy balance error reached", p.stderr)

    def test_i_no_shipped_scene_trips_the_energy_guard(self):
        folder = os.path.join(ROOT, "config", "scenes")
        for name in sorted(os.listdir(folder)):
            with self.subTest(scene=name):
                summary, p = T.run_sim(ARGS.sim, os.path.join(folder, name), "--output-step", "1e-3")
                self.assertEqual(p.returncode, 0, p.stderr)
                self.assertFalse(summary["run"]["energy_guard"], f"{name}: {summary['run']['energy_balance_relative']}")

    def check_failure(self, args, status, message, exit_code=1, ran=False):
        summary, p = T.run_sim(ARGS.sim, *args)
        self.assertEqual(p.returncode, exit_code, p.stderr)
        self.assertIsNotNone(summary, p.stdout)
        self.assertEqual(summary["exit_code"], exit_code)
        self.assertEqual(set(summary["error"]), {"status", "message"})
        self.assertEqual(summary["error"]["status"], status)
        self.assertIn(message, summary["error"]["message"])
        self.assertIn("flex3rpr_sim: " + summary["error"]["message"], p.stderr, "the message printed")
        self.assertEqual(summary["run"] is not None, ran)
        return summary

    def test_d_failures_write_the_error(self):
        self.check_failure([scene("paper_sim1"), "--bogus"], "usage", "unknown or incomplete option '--bogus'", 2)
        bad = self.check_failure([scene("paper_sim1"), "--set", "solver.rtol=-1"], "F3R_ERR_SCENE",
                                 "solver.rtol: -1 is out of range")
        self.assertIsNone(bad["settings"])
        collapse = self.check_failure([scene("paper_sim3_fixed_free"), "--duration", "0.02", "--set",
                                       "inputs.rho_1.offset=-1000", "--set", "inputs.rho_1.amplitude=0"],
                                      "F3R_ERR_SINGULAR", "leg 1 collapsed", ran=True)
        self.check_keys(collapse, "settings", "run")
        self.assertLess(collapse["run"]["simulated_time_s"], 0.02)
        self.check_failure([scene("paper_sim1"), "--out", "/nonexistent/run.csv"], "io",
                           "cannot write /nonexistent/run.csv")
        summary, p = T.run_sim(ARGS.sim, "--modal", scene("paper_sim1"))
        self.assertEqual(p.returncode, 2, "--summary-json - with an analysis that prints on stdout")
        self.assertEqual(summary["error"]["status"], "usage")

    def test_e_an_unwritable_summary_fails_the_run(self):
        p = T.run([ARGS.sim, scene("paper_sim1"), "--duration", "0.01", "--summary-json", "/nonexistent/s.json"])
        self.assertEqual(p.returncode, 1)
        self.assertIn("flex3rpr_sim: cannot write /nonexistent/s.json", p.stderr)


def main():
    global ARGS
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sim", required=True, help="the flex3rpr_sim to test")
    ap.add_argument("--junit", help="write the cases as JUnit XML")
    ARGS = ap.parse_args()
    return T.run_unittest([Summary], ARGS.junit, "summary_json")


if __name__ == "__main__":
    sys.exit(main())
