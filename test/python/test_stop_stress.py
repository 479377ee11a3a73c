"""End stops under seeded random pushes and pulls, through the Python module and the CLI.

Each sequence (numpy's default_rng, fixed seeds) is 1 s of segments of 20 to 300 ms, each a hold
(the forces kept), a step or a ramp to new leg forces of up to 120 N (mostly pushes outwards or
inwards, so that legs reach their stops, often several at once) and, in some, a platform wrench of
up to 60 N and 3 N m, on rest_turned.yaml with end stops [0, 0.2] m and restitution 0, 0.3 and
0.8. The forces change on the 1 ms grid only:
  - flex3rpr.Sim.step_forces, one 1 ms period a call (as the node's ~step_with_command): after each
    period every stroke within its stops to 1e-9 m, every locked leg within 1e-9 m of its stop with
    a stop force that pushes (none on a free leg), no exception, the energy guard quiet;
  - flex3rpr_sim with the same forces as `inputs.*.table` (interpolation: hold; `--hold` takes at
    most 64 events, too few for ramps), a CSV every 1 ms: exit code 0, every rho_i within its
    stops to 1e-9 m, every leg with a stop force (a locked one) within 1e-9 m of its stop, the
    summary's energy guard quiet.
One sequence per restitution and path by default (about 10 s in all on a loaded 2-core machine:
a period with impacts costs the core about 1.5 ms); F3R_STOP_STRESS_CASES=N runs N of each.
The worst figures are printed (pytest -s shows them). No test asserts a duration."""
import csv
import json
import os
import subprocess

import numpy as np
import pytest

import flex3rpr

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
SCENE = os.path.join(ROOT, "config", "scenes", "rest_turned.yaml")
CLI = os.environ.get("F3R_CLI", os.path.join(ROOT, "build", "ws", "devel", "lib", "flex3rpr",
                                             "flex3rpr_sim"))
LO, HI = 0.0, 0.2          # m: the stroke, the end stops
TOL = 1e-9                 # m: past a stop, or off it while locked
FORCE_TOL = 1e-6           # N: a locked leg's stop force may not pull (its release root: 1e-8 N)
STEP = 1e-3                # s: the period of the forces and of the outputs
PERIODS = 1000             # 1 s
RESTITUTIONS = (0.0, 0.3, 0.8)
CASES = max(1, int(os.environ.get("F3R_STOP_STRESS_CASES") or 1))  # a restitution and path
INPUTS = ("rho_1", "rho_2", "rho_3", "platform_force_x", "platform_force_y", "platform_torque")


def seeds(restitution, path):
    """CASES seeds for a restitution; each path (0: Python, 1: CLI) its own sequences."""
    return [1000 * int(round(10 * restitution)) + 500 * path + c for c in range(CASES)]


def stops(restitution):
    return {"min": LO, "max": HI, "restitution": restitution}


def sequence(seed):
    """The forces of one sequence: (PERIODS, 6), row k acting over (k, k + 1] ms, columns
    INPUTS (N on rho_1..3, N and N m on the platform); and the segments' kinds."""
    rng = np.random.default_rng(seed)
    forces = np.zeros((PERIODS, 6))
    now = np.zeros(6)
    kinds = []
    k = 0
    while k < PERIODS:
        n = int(rng.integers(20, 301))  # ms
        kind = ("hold", "step", "ramp")[int(rng.integers(0, 3))]
        kinds.append(kind)
        target = now.copy()
        if kind != "hold":
            for i in range(3):
                r = rng.random()
                target[i] = (rng.uniform(40.0, 120.0) if r < 0.35 else
                             -rng.uniform(40.0, 120.0) if r < 0.7 else rng.uniform(-20.0, 20.0))
            wrench = rng.random() < 0.4
            target[3:5] = rng.uniform(-60.0, 60.0, 2) if wrench else 0.0
            target[5] = rng.uniform(-3.0, 3.0) if wrench else 0.0
        for j in range(min(n, PERIODS - k)):
            forces[k + j] = now + ((j + 1) / n if kind == "ramp" else 1.0) * (target - now)
        now = target
        k += n
    return forces, kinds


class Worst:
    """The worst figures over sequences, and the first violation of each bound."""

    def __init__(self, name):
        self.name = name
        self.penetration = -np.inf  # m past a stop (negative: no stroke reached one)
        self.drift = 0.0            # m off its stop while locked
        self.energy_ratio = 0.0     # energy balance error over the largest T + V
        self.impacts = 0
        self.multi_locked = 0       # outputs with two or more legs locked
        self.locked = 0             # outputs with a leg locked
        self.sequences = 0
        self.pull = -np.inf         # N: the largest stop force on a locked leg away from its stroke
        self.flickers = 0           # CLI: outputs where a leg held before and after has no force
        self.violations = []

    def fail(self, text):
        if len(self.violations) < 10:
            self.violations.append(text)

    def stroke(self, where, i, rho, side, force, strict_pull=True):
        """Leg i's stroke rho at one output; side: -1, +1 locked there, 0 free. strict_pull: a
        stop force that pulls is a violation (else only reported)."""
        past = max(rho - HI, LO - rho)
        self.penetration = max(self.penetration, past)
        if past > TOL:
            self.fail("%s: leg %d %.3g m past its stop (rho %.17g)" % (where, i + 1, past, rho))
        if side:
            drift = abs(rho - (HI if side > 0 else LO))
            self.drift = max(self.drift, drift)
            if drift > TOL:
                self.fail("%s: locked leg %d %.3g m off its stop (rho %.17g)"
                          % (where, i + 1, drift, rho))
            self.pull = max(self.pull, side * force)
            if side * force > FORCE_TOL and strict_pull:
                self.fail("%s: leg %d's stop pulls (%.6g N)" % (where, i + 1, force))

    def report(self):
        print("\nmeasured (%s): %d sequence(s) of %g s: worst penetration %.3g m, worst locked "
              "drift %.3g m, worst energy balance %.2g of T+V, %d impacts, %d outputs with a leg "
              "locked, %d with two or more; largest pull of a stop %.3g N%s"
              % (self.name, self.sequences, PERIODS * STEP, self.penetration, self.drift,
                 self.energy_ratio, self.impacts, self.locked, self.multi_locked, self.pull,
                 ", %d outputs with a held leg let go for one output" % self.flickers
                 if self.flickers else ""))

    def check(self):
        self.report()
        assert not self.violations, "\n".join(self.violations)
        assert self.penetration <= TOL and self.drift <= TOL
        assert self.impacts > 0, "the sequences must reach the stops"
        assert self.multi_locked > 0, "and hold several legs at once"


def python_sequence(restitution, seed, worst):
    forces, kinds = sequence(seed)
    sim = flex3rpr.Sim(SCENE, overrides={"effects.end_stops": stops(restitution)}, period=STEP)
    ke, pe = sim.column_index["kinetic_energy"], sim.column_index["potential_energy"]
    held = np.zeros(sim.nq)
    largest = 0.0
    for k in range(PERIODS):
        held[0:3] = forces[k, 0:3]
        held[6:9] = forces[k, 3:6]  # F_x, F_y, torque: the platform's generalized forces
        where = "restitution %g, seed %d, t %.3f s" % (restitution, seed, (k + 1) * STEP)
        try:
            row = sim.step_forces(held)
        except flex3rpr.Error as e:
            worst.fail("%s: %s" % (where, e))
            return
        x = sim.extras
        locked = 0
        for i in range(3):
            side = int(x["stop_locked"][i])
            worst.stroke(where, i, row[1 + i], side, x["stop_force"][i])
            if side:
                locked += 1
            elif x["stop_force"][i] != 0.0:
                worst.fail("%s: free leg %d has a stop force %g N" % (where, i + 1,
                                                                      x["stop_force"][i]))
        worst.locked += locked > 0
        worst.multi_locked += locked >= 2
        largest = max(largest, row[ke] + row[pe])
        error = x["energy_balance_error"]
        if largest > 0.0 and error > 1e-9:  # the guard's floor (F3R_ENERGY_GUARD_FLOOR)
            worst.energy_ratio = max(worst.energy_ratio, error / largest)
            if error > 0.1 * largest:       # F3R_ENERGY_GUARD
                worst.fail("%s: energy guard: balance error %.3g J of the largest T + V %.3g J"
                           % (where, error, largest))
    assert abs(sim.t - PERIODS * STEP) < 1e-12
    worst.impacts += sim.extras["impacts"]
    worst.sequences += 1


def table(column):
    """A hold table: value[j] on (time[j], time[j + 1]], the last held on; points where the
    force changes (a ramp: every period)."""
    ks = [0] + [k for k in range(1, PERIODS) if column[k] != column[k - 1]]
    times, values = [k * STEP for k in ks], [float(column[k]) for k in ks]
    if len(ks) == 1:
        times.append(PERIODS * STEP)
        values.append(values[0])
    assert len(times) <= 1024
    return {"table": {"time": times, "value": values, "interpolation": "hold"}}


def cli_sequence(restitution, seed, workdir, worst):
    forces, kinds = sequence(seed)
    with open(SCENE) as f:
        text = f.read()
    # rest_turned.yaml with the forces as inputs (JSON is YAML; repr round-trips every double)
    text += "\ninputs:\n" + "".join("  %s: %s\n" % (name, json.dumps(table(forces[:, c])))
                                    for c, name in enumerate(INPUTS))
    scene = os.path.join(workdir, "stress_%g_%d.yaml" % (restitution, seed))
    with open(scene, "w") as f:
        f.write(text)
    out, summary = scene[:-5] + ".csv", scene[:-5] + ".json"
    args = [CLI, scene, "--out", out, "--summary-json", summary,
            "--set", "effects.end_stops=" + json.dumps(stops(restitution)),
            "--set", "run.duration=%r" % (PERIODS * STEP), "--set", "run.output_step=%r" % STEP]
    run = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    where = "CLI, restitution %g, seed %d" % (restitution, seed)
    if run.returncode != 0:
        worst.fail("%s: exit code %d: %s" % (where, run.returncode, run.stderr.strip()))
        return
    with open(out) as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    assert len(rows) == PERIODS + 1, (where, len(rows))
    col = {name: header.index(name) for name in header}
    rho = np.array([[float(row[col["rho_%d" % (i + 1)]]) for i in range(3)] for row in rows])
    force = np.array([[float(row[col["stop_force_%d" % (i + 1)]]) for i in range(3)]
                      for row in rows])
    # The CSV has no stop_locked: a leg with a stop force is held at the stop it is at.
    side = np.where(force == 0.0, 0, np.where(rho > 0.5 * (LO + HI), 1, -1))
    for k, row in enumerate(rows):
        for i in range(3):
            worst.stroke("%s, t %s s" % (where, row[col["t"]]), i, rho[k, i], side[k, i],
                         force[k, i])
    worst.locked += int(((side != 0).sum(axis=1) > 0).sum())
    worst.multi_locked += int(((side != 0).sum(axis=1) >= 2).sum())
    # a leg held before and after an output, at its stop there with no stop force
    gap = np.minimum(np.abs(rho - LO), np.abs(rho - HI)) <= 1e-12
    worst.flickers += int(((side[1:-1] == 0) & gap[1:-1] & (side[:-2] != 0) &
                           (side[2:] != 0)).sum())
    with open(summary) as f:
        result = json.load(f)["run"]
    if result["energy_guard"]:
        worst.fail("%s: energy guard (balance error %s J)" % (where,
                                                             result["energy_balance_error_J"]))
    worst.energy_ratio = max(worst.energy_ratio, result["energy_balance_relative"])
    worst.impacts += result["impacts"]
    worst.sequences += 1


@pytest.mark.parametrize("restitution", RESTITUTIONS)
def test_python_stepping_keeps_every_leg_within_its_stops(restitution):
    worst = Worst("Python step_forces, restitution %g" % restitution)
    for seed in seeds(restitution, 0):
        python_sequence(restitution, seed, worst)
    worst.check()


@pytest.mark.parametrize("restitution", RESTITUTIONS)
def test_cli_hold_tables_keep_every_leg_within_its_stops(restitution, tmp_path):
    worst = Worst("flex3rpr_sim hold tables, restitution %g" % restitution)
    for seed in seeds(restitution, 1):
        cli_sequence(restitution, seed, str(tmp_path), worst)
    worst.check()


def test_the_sequences_are_seeded_and_mixed():
    a, kinds = sequence(7)
    b, _ = sequence(7)
    assert np.array_equal(a, b)
    assert set(kinds) == {"hold", "step", "ramp"} or len(kinds) < 6
    assert np.abs(a[:, :3]).max() <= 120.0 and np.abs(a[:, 3:5]).max() <= 60.0
    assert np.abs(a[:, 5]).max() <= 3.0
    assert (a[:, :3] > 40.0).any() and (a[:, :3] < -40.0).any()  # pushes both ways
