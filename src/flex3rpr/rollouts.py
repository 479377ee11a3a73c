"""Batched rollouts: n closed- or open-loop runs of a scene across the machine's cores, stacked.

On one machine rollouts() forks a process a core. For more machines the same runs split into
parts (part=(k, parts)) that any sweep engine starts, e.g. GNU parallel or Slurm's array jobs:

    parallel python3 -m flex3rpr.rollouts spec.json --part {}/4 --out part{}.npz ::: 0 1 2 3
    python3 -m flex3rpr.rollouts --merge part*.npz --out all.npz

spec.json: {"scene": PATH, "n": N, "periods": P, "overrides": [{FIELD: VALUE}, ...] (n of them,
or one for all), "commands": PATH.npy (n x P x 6, optional), "policy": "module:function"
(optional)}.
"""
import argparse
import importlib
import json
import multiprocessing
import os
import sys

import numpy as np

from ._core import Error
from .sim import Sim


def _one_run(job):
    """One run's rows (the CSV's columns, then the scene's sensors' columns, as the CLI writes
    them), its status and its column names."""
    scene, overrides, periods, commands, policy, index, period = job
    sim = Sim(scene, overrides=overrides, period=period)
    width = len(sim.columns)
    columns = sim.columns + sim.sensor_names
    rows = np.empty((periods + 1, len(columns)))
    rows[0, :width] = sim.state.vector
    rows[0, width:] = sim.sensors
    status = ""
    for k in range(periods):
        try:
            if commands is not None:
                state = sim.step(commands[k])
            else:
                state = sim.step(policy(sim.state if k == 0 else state, k, index))
        except Error as e:  # the run ends where the physics stopped: the rest stays NaN
            rows[k + 1:] = np.nan
            status = str(e)
            break
        rows[k + 1, :width] = state.vector
        rows[k + 1, width:] = sim.sensors
    return rows, status, columns


_JOBS = []  # the runs of the rollouts() in progress, inherited by the forked workers


def _run_index(i):
    return _one_run(_JOBS[i])


def _jobs(scene, n, periods, commands, policy, overrides, period, part):
    if isinstance(overrides, dict) or overrides is None:
        overrides = [overrides or {}] * n
    if len(overrides) != n:
        raise ValueError("overrides: %d dicts for %d runs (give one, or one a run)"
                         % (len(overrides), n))
    if commands is not None:
        commands = np.asarray(commands, dtype=float)
        if commands.ndim == 2:
            commands = np.broadcast_to(commands, (n,) + commands.shape)
        if commands.shape[0] != n or commands.shape[1] < periods:
            raise ValueError("commands: shape %s, expected (%d, >= %d, 6 or nq)"
                             % (commands.shape, n, periods))
    elif policy is None:
        raise ValueError("give a policy (state, k, run) -> command, or command arrays")
    k, parts = part
    return [(scene, overrides[i], periods, None if commands is None else commands[i], policy, i,
             period) for i in range(n) if i % parts == k]


def rollouts(scene, policy=None, n=1, periods=1000, commands=None, overrides=None, period=1e-3,
             processes=None, part=(0, 1)):
    """Runs n simulations of `scene` for `periods` periods of `period` s each, across
    `processes` processes (default: every core), and returns a dict: each CSV column as an
    array (runs, periods + 1), "status" (one message a run, "" when it ran to the end; a run
    stopped by its physics has NaN after that) and "runs" (the run indices, for a part). A scene
    with sensors adds their columns (enc_rho_1, strain_1, accel_x, ...), as the CLI's CSV does.

    policy(state, k, run) -> command is called at every period (state: the State after period
    k - 1; run: the run's index); or commands (n x periods x 6 or nq, or periods x 6 for all)
    are held period by period. overrides: one dict of scene fields for all, or a list of n (a
    parameter study). part=(k, parts) runs only the runs i with i % parts == k."""
    jobs = _jobs(scene, n, periods, commands, policy, overrides, period, part)
    processes = processes or os.cpu_count() or 1
    if processes > 1 and len(jobs) > 1:
        # forked workers inherit the jobs: the policy need not be picklable, only the results
        _JOBS[:] = jobs
        context = multiprocessing.get_context("fork")
        try:
            with context.Pool(min(processes, len(jobs))) as pool:
                results = pool.map(_run_index, range(len(jobs)),
                                   chunksize=max(1, len(jobs) // (4 * processes)))
        finally:
            _JOBS[:] = []
    else:
        results = [_one_run(job) for job in jobs]
    columns = results[0][2] if results else []
    stacked = np.stack([r[0] for r in results]) if results else np.zeros((0, periods + 1, 0))
    out = {name: stacked[:, :, c] for c, name in enumerate(columns)}
    out["status"] = [r[1] for r in results]
    out["runs"] = np.array([job[5] for job in jobs])
    return out


def _study_run(i):
    scene, overrides, duration, keep = _JOBS[i]
    try:
        result = Sim(scene, overrides=overrides).run(duration)
    except Error as e:
        return {"status": str(e)}
    result = {k: v for k, v in result.items() if keep is None or k in keep}
    result["status"] = ""
    return result


def study(scene, overrides, duration=None, columns=None, processes=None):
    """A parameter study: the scene run open loop, as the CLI runs it (Sim.run), once for each
    dict of scene fields in `overrides`, across `processes` processes (default: every core).
    Returns one dict a run: the CSV's columns (only `columns` when given) and "status" ("" or
    the error that stopped the run)."""
    _JOBS[:] = [(scene, o, duration, None if columns is None else set(columns))
                for o in overrides]
    processes = processes or os.cpu_count() or 1
    try:
        if processes > 1 and len(_JOBS) > 1:
            with multiprocessing.get_context("fork").Pool(min(processes, len(_JOBS))) as pool:
                return pool.map(_study_run, range(len(_JOBS)), chunksize=1)
        return [_study_run(i) for i in range(len(_JOBS))]
    finally:
        _JOBS[:] = []


def _spec_call(spec, part):
    policy = spec.get("policy")
    if policy:
        module, function = policy.split(":")
        policy = getattr(importlib.import_module(module), function)
    commands = np.load(spec["commands"]) if spec.get("commands") else None
    return rollouts(spec["scene"], policy=policy, n=spec["n"], periods=spec["periods"],
                    commands=commands, overrides=spec.get("overrides"),
                    period=spec.get("period", 1e-3), processes=spec.get("processes"), part=part)


def _save(path, result):
    arrays = {k: v for k, v in result.items() if k != "status"}
    np.savez(path, status=np.array(result["status"], dtype=object), **arrays)


def merge(paths):
    """The parts' results (npz files of a split run) as one result, runs in index order."""
    parts = [dict(np.load(p, allow_pickle=True)) for p in paths]
    runs = np.concatenate([p["runs"] for p in parts])
    order = np.argsort(runs)
    out = {}
    for key in parts[0]:
        out[key] = np.concatenate([p[key] for p in parts])[order]
    out["status"] = list(out["status"])
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m flex3rpr.rollouts",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("spec", nargs="?", help="the runs, as JSON (see the module's doc)")
    parser.add_argument("--part", default="0/1", help="K/PARTS: the runs i with i %% PARTS == K")
    parser.add_argument("--merge", nargs="+", metavar="NPZ", help="merge the parts' files")
    parser.add_argument("--out", required=True, help="the result (.npz)")
    args = parser.parse_args(argv)
    if args.merge:
        _save(args.out, merge(args.merge))
        return 0
    if not args.spec:
        parser.error("give a spec, or --merge")
    k, parts = (int(x) for x in args.part.split("/"))
    with open(args.spec) as f:
        spec = json.load(f)
    _save(args.out, _spec_call(spec, (k, parts)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
