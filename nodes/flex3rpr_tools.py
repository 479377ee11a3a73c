"""What the scripts share: finding and running flex3rpr_sim and reading its summary
(`--summary-json`), YAML values through PyYAML, JUnit XML, CSV, and the generated reports under
docs/benchmarks/.

  find_binary(name, env)      the build's flex3rpr_sim (or another of its executables)
  run(cmd, ...)               a command, its output captured as text
  run_sim(sim, scene, *args)  the CLI with --summary-json -: (summary dict or None, process)
  error_message(summary, p)   why a run failed, in one line
  yaml_value(v)               a value as `--set FIELD=VALUE` takes it (PyYAML, one line)
  write_junit(path, suite, cases)
  run_unittest(classes, junit_path, suite)   unittest cases, their report and their JUnit XML
  write_csv(path, rows)
  replace_section(path, begin, end, section)   a generated report between its marker lines
  machine_stamp()             CPU, cores, date and commit, for a report

Imported by the tools beside it (nodes/ in a checkout, lib/flex3rpr/ in an install space), by
the benchmarks in bench/ and the CI helpers in scripts/ci/ (which put nodes/ on their path) and
by the tests under test/. JUnit is written with xml.etree: rosunit.junitxml (python3-rosunit
1.15.8), which the ROS test tools use, cannot write a suite with cases: Result.xml_element() calls
TestCaseResult.xml(testsuite), which takes no argument (TypeError), and its cdata() wrappers are
escaped by ElementTree into literal text."""
import csv
import datetime
import json
import os
import shutil
import subprocess
import sys
import unittest
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)  # the checkout, when this file is nodes/flex3rpr_tools.py


def find_binary(name="flex3rpr_sim", env="F3R_SIM"):
    """The executable `name`: $env if set, beside this module (an install space), the catkin
    build's devel space ($F3R_WS or build/ws of the checkout), what catkin_find finds in the
    sourced workspaces, or on PATH. Raises FileNotFoundError when none is executable."""
    for candidate in _binary_candidates(name, env):
        if candidate and os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return os.path.abspath(candidate)
    raise FileNotFoundError(f"{name} not found: build it (bash scripts/build)" + (f" or set {env}" if env else ""))


def _binary_candidates(name, env):
    yield os.environ.get(env) if env else None
    yield os.path.join(HERE, name)
    yield os.path.join(os.environ.get("F3R_WS", os.path.join(ROOT, "build", "ws")), "devel", "lib", "flex3rpr", name)
    if shutil.which("catkin_find"):
        try:
            yield from run(["catkin_find", "--libexec", "flex3rpr", name], timeout=60).stdout.split()
        except subprocess.SubprocessError:
            pass
    yield shutil.which(name)


def run(cmd, check=False, **kwargs):
    """subprocess.run with stdout and stderr captured as text."""
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, check=check, **kwargs)


def read_summary(text):
    """The CLI's JSON summary from its text; None when it is not one (a crash, a timeout)."""
    try:
        summary = json.loads(text)
    except ValueError:
        return None
    return summary if isinstance(summary, dict) and "exit_code" in summary else None


def run_sim(sim, scene, *args, **kwargs):
    """flex3rpr_sim SCENE ARGS --summary-json -: (the summary as a dict, or None when the CLI wrote
    none, and the CompletedProcess). Its stdout is the JSON; the human summary goes to stderr.
    kwargs go to subprocess.run (timeout, env, ...)."""
    p = run([sim, scene, *args, "--summary-json", "-"], **kwargs)
    return read_summary(p.stdout), p


def error_message(summary, process):
    """Why a run failed, in one line: the summary's error message, else the CLI's last message
    on stderr, else the exit code."""
    if summary and summary.get("error"):
        return summary["error"]["message"]
    said = [l[len("flex3rpr_sim: "):] for l in (process.stderr or "").splitlines() if l.startswith("flex3rpr_sim: ")]
    return said[-1] if said else f"exit code {process.returncode}"


def yaml_value(value):
    """A value as --set takes it: YAML in flow style on one line (floats round-trip)."""
    import yaml  # python3-yaml; imported here so that the modules' other users need not have it
    text = yaml.safe_dump(value, default_flow_style=True, width=float("inf"), sort_keys=False,
                          allow_unicode=True)
    if text.endswith("\n...\n"):  # the end marker of a document that is a scalar
        text = text[: -len("\n...\n")]
    return text.strip()


def write_junit(path, suite, cases):
    """JUnit XML: cases are (classname, name, failure) with failure None or its text, or
    (classname, name, None, skipped) with skipped the reason a case could not run here (a
    <skipped> element: counted as neither passed nor failed, and listed by the CI's count). A
    failure's text goes in its message attribute (its last 2000 characters) and body."""
    failures = sum(1 for c in cases if c[2])
    skipped = sum(1 for c in cases if len(c) > 3 and c[3])
    root = ET.Element("testsuite", name=suite, tests=str(len(cases)), errors="0", failures=str(failures),
                      skipped=str(skipped))
    for classname, name, failure, *skip in cases:
        case = ET.SubElement(root, "testcase", classname=classname, name=name)
        if failure:
            ET.SubElement(case, "failure", message=failure[-2000:]).text = failure
        elif skip and skip[0]:
            ET.SubElement(case, "skipped", message=skip[0])
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    return failures


def run_unittest(test_case_classes, junit_path, suite_name):
    """Runs the unittest cases, prints unittest's report, writes JUnit XML when junit_path is
    given (classname SUITE.CLASS); exit code 0 when all pass."""
    loader = unittest.TestLoader()
    suite = unittest.TestSuite(loader.loadTestsFromTestCase(c) for c in test_case_classes)
    ids = [t.id() for t in _suite_tests(suite)]  # the suite lets go of its tests as they run
    result = unittest.TextTestRunner(verbosity=2, stream=sys.stdout).run(suite)
    if junit_path:
        bad = {t.id(): text for t, text in result.failures + result.errors}
        skips = {t.id(): reason for t, reason in result.skipped}
        cases = [(f"{suite_name}.{test_id.split('.')[-2]}", test_id.split(".")[-1], bad.get(test_id),
                  skips.get(test_id)) for test_id in ids]
        # a failed setUpClass or tearDownClass belongs to no test
        cases += [(suite_name, test_id.split(" ")[0], text) for test_id, text in bad.items() if test_id not in ids]
        write_junit(junit_path, suite_name, cases)
    return 0 if result.wasSuccessful() else 1


def _suite_tests(suite):
    for t in suite:
        if isinstance(t, unittest.TestSuite):
            yield from _suite_tests(t)
        else:
            yield t


def write_csv(path, rows):
    """rows (dicts) as CSV, every key of any row a column, in the order they first appear; none:
    no file."""
    if not rows:
        return
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
        w.writeheader()
        w.writerows(rows)


def replace_section(path, begin, end, section, title=None):
    """Writes section between the lines `begin` and `end` of the Markdown file path, creating the
    file (with `# title` and the markers) when it does not exist."""
    if not os.path.exists(path):
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        with open(path, "w") as f:
            f.write((f"# {title}\n\n" if title else "") + f"{begin}\n{end}\n")
    with open(path) as f:
        text = f.read()
    if begin not in text or end not in text:
        raise ValueError(f"{path}: no '{begin}' ... '{end}' markers to write between")
    text = text[: text.index(begin) + len(begin)] + "\n" + section + "\n" + text[text.index(end):]
    with open(path, "w") as f:
        f.write(text)


def git_commit(root=ROOT):
    return run(["git", "-C", root, "rev-parse", "--short", "HEAD"]).stdout.strip()


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            return next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        return "unknown CPU"


def machine_stamp():
    """'CPU, N cores; date; commit abc1234' for a generated report."""
    return f"{cpu_model()}, {os.cpu_count()} cores; {datetime.date.today()}; commit {git_commit()}"
