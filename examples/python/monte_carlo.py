#!/usr/bin/python3
"""A Monte-Carlo robustness study: the LQR designed on the nominal plant (lqr_scipy.py's) run
on robots whose payload (0 .. 0.1 kg, uniform) and link stiffness (Young's modulus 73 GPa, 5 %
standard deviation) are drawn at random, with flex3rpr.rollouts on every core.

Writes monte_carlo.png (final error and largest tip deflection against payload and stiffness)
and monte_carlo.json (their spread) to --out.
"""
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import example_common as ex  # noqa: E402
import flex3rpr  # noqa: E402


def main():
    args = ex.arguments(__doc__)
    runs, periods = (8, 100) if args.quick else (100, 400)
    rng = np.random.default_rng(11)
    payload = rng.uniform(0.0, 0.1, runs)
    modulus = rng.normal(73e9, 0.05 * 73e9, runs)
    nominal = flex3rpr.Sim(ex.SCENE, overrides=ex.START_FIELDS)
    plant = nominal.linearise()
    K, _, _ = ex.lqr(plant, nominal.period)
    x_target = np.zeros(plant["A"].shape[0])
    x_target[:3] = ex.TARGET - plant["x0"][:3]

    def policy(state, k, run):
        return -K @ (ex.plant_state(state, plant) - x_target)

    overrides = [dict(ex.START_FIELDS, **{"effects.payload.mass": float(m),
                                          "link.youngs_modulus": float(e)})
                 for m, e in zip(payload, modulus)]
    out = flex3rpr.rollouts(ex.SCENE, policy=policy, n=runs, periods=periods, overrides=overrides)
    final = np.hypot(out["x_p"][:, -1] - ex.TARGET[0], out["y_p"][:, -1] - ex.TARGET[1])
    tips = np.max(np.abs(np.stack([out["w_tip_%d" % i] for i in (1, 2, 3)])), axis=(0, 2))
    result = {"runs": runs, "periods": periods, "stopped": sum(bool(s) for s in out["status"]),
              "final_error_m": {"median": float(np.median(final)), "max": float(np.max(final))},
              "max_tip_deflection_m": {"median": float(np.median(tips)),
                                       "max": float(np.max(tips))}}
    with open(os.path.join(args.out, "monte_carlo.json"), "w") as f:
        json.dump(result, f, indent=1)
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.5))
    s = a.scatter(1e3 * payload, 1e3 * final, c=modulus / 1e9)
    a.set_xlabel("payload (g)"), a.set_ylabel("final error (mm)")
    b.scatter(1e3 * payload, 1e6 * tips, c=modulus / 1e9)
    b.set_xlabel("payload (g)"), b.set_ylabel("largest tip deflection (um)")
    fig.colorbar(s, ax=b, label="E (GPa)")
    fig.suptitle("LQR on %d random robots, %d periods" % (runs, periods))
    fig.savefig(os.path.join(args.out, "monte_carlo.png"), dpi=90, bbox_inches="tight")
    print("monte_carlo: %d runs; final error median %.3g m, max %.3g m; largest tip deflection "
          "median %.3g m, max %.3g m" % (runs, result["final_error_m"]["median"],
                                         result["final_error_m"]["max"],
                                         result["max_tip_deflection_m"]["median"],
                                         result["max_tip_deflection_m"]["max"]))


if __name__ == "__main__":
    main()
