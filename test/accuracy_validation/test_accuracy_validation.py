#!/usr/bin/env python3
"""The accuracy knob's measured error, on a quick subset of the held-out validation suite
(bench/validate_accuracy; the full suite and its table: docs/benchmarks/accuracy_validation.md).

Three of test/accuracy_validation/scenes, cut to their first 0.1 s, at 1e-3 and 1e-4 m, against
references on the corrected basis at r = 8 and rtol 1e-11 (cached in --work). For each (scene,
request):
  a  the knob's path is within the request of the reference, or the run says it is not met
     (request_met false, exit 3): no request missed silently;
  b  the measured error is at least a third of the true error: the measurement does not flatter.
And the script itself: its JSON and JUnit reports on one cached case. No timing is asserted.

usage: test_accuracy_validation.py --sim FLEX3RPR_SIM [--junit FILE] [--work DIR]"""
import argparse
import importlib.machinery
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "bench", "validate_accuracy")
sys.path.insert(0, os.path.join(ROOT, "nodes"))
import flex3rpr_tools as T  # noqa: E402

# An undamped resonance (the case the check was added for), mixed fixed-pinned and fixed-free
# bases in one run, and friction with an actuator lag: the three cheapest kinds of the suite to
# cover its different paths through the knob.
QUICK_SCENES = ["resonance_undamped_0p5s", "mixed_pinned_free_free", "friction_lag_fixed_free"]
QUICK_SETS = ["run.duration=0.1"]
REQUESTS = [1e-3, 1e-4]
ARGS = None


def load_script():
    """bench/validate_accuracy as a module (it has no .py suffix)."""
    loader = importlib.machinery.SourceFileLoader("validate_accuracy", SCRIPT)
    module = importlib.util.module_from_spec(importlib.util.spec_from_loader(loader.name, loader))
    loader.exec_module(module)
    return module


class Validation(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.script = load_script()
        cls.work = ARGS.work or tempfile.mkdtemp(prefix="f3r_accuracy_validation_")
        paths = cls.script.scene_paths(",".join(QUICK_SCENES))
        result = cls.script.validate(ARGS.sim, paths, REQUESTS, jobs=2, work=cls.work, sets=QUICK_SETS)
        cls.cases = {(c["scene"], c["request_m"]): c for c in result["cases"]}

    def case(self, scene, request):
        c = self.cases[(scene, request)]
        self.assertNotIn(c["verdict"], ("reference too coarse", "reference failed", "run failed"),
                         f"{scene} at {request:g} m: {c['verdict']}: {c.get('failure')}")
        return c

    def check_a(self, scene, request):
        c = self.case(scene, request)
        self.assertTrue(c["a_holds"], f"{scene} at {request:g} m: {c['failure']}")

    def check_b(self, scene, request):
        c = self.case(scene, request)
        self.assertTrue(c["b_holds"], f"{scene} at {request:g} m: {c['failure']}")

    def test_script_reports(self):
        """The script's command line on one case (its reference cached by setUpClass): JSON with
        the case's numbers, JUnit with one test case, exit status 0 when the case holds."""
        out = os.path.join(self.work, "report")
        p = T.run([sys.executable, SCRIPT, "--sim", ARGS.sim, "--scenes", QUICK_SCENES[2], "--requests", "1e-3",
                   "--jobs", "1", "--work", self.work, *[a for s in QUICK_SETS for a in ("--set", s)],
                   "--json", out + ".json", "--junit", out + ".xml"], timeout=600)
        self.assertEqual(p.returncode, 0, p.stderr[-2000:])
        with open(out + ".json") as f:
            report = json.load(f)
        (case,) = report["cases"]
        for key in ("true_error_m", "measured_error_m", "estimated_error_m", "verdict", "configurations",
                    "cpu_with_check_s", "cpu_without_check_s", "cpu_ratio"):
            self.assertIn(key, case)
        self.assertEqual(case["verdict"], "met")
        suite = ET.parse(out + ".xml").getroot()
        self.assertEqual((suite.get("tests"), suite.get("failures")), ("1", "0"))


def add_case_tests():
    for scene in QUICK_SCENES:
        for request in REQUESTS:
            tag = f"{scene}_{request:.0e}".replace("-", "m")
            setattr(Validation, f"test_a_not_missed_silently_{tag}",
                    lambda self, s=scene, r=request: self.check_a(s, r))
            setattr(Validation, f"test_b_measurement_does_not_flatter_{tag}",
                    lambda self, s=scene, r=request: self.check_b(s, r))


add_case_tests()


def main():
    global ARGS
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sim", required=True, help="the flex3rpr_sim to test")
    ap.add_argument("--junit", help="write the cases as JUnit XML")
    ap.add_argument("--work", help="cache the references here (default: a new temporary folder)")
    ARGS = ap.parse_args()
    ARGS.sim = os.path.abspath(ARGS.sim)
    return T.run_unittest([Validation], ARGS.junit, "accuracy_validation")


if __name__ == "__main__":
    sys.exit(main())
