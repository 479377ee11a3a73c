#!/usr/bin/python3
"""A PD on the leg strokes, tuned by a grid search over 200 rollouts: a 1 cm move of rest.yaml's
platform from a controllable start, scored by tracking error plus tip vibration.

Each rollout holds u_i = kp (rho_i* - rho_i) - kd rho_i' on leg i at 1 kHz (rho* from the loop
closure at the target) for 0.3 s; flex3rpr.rollouts runs them on every core. Writes
pd_grid.png (the cost over the grid) and pd_grid.json (the best gains) to --out.
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
    kps = np.geomspace(200.0, 2e4, 5 if args.quick else 20)
    kds = np.geomspace(2.0, 200.0, 4 if args.quick else 10)
    periods = 100 if args.quick else 300
    grid = [(kp, kd) for kp in kps for kd in kds]
    reference = ex.legs_at(ex.TARGET)

    def policy(state, k, run):
        kp, kd = grid[run]
        rho, rate = state.q[:3], state.v[:3]
        return np.concatenate([kp * (reference - rho) - kd * rate, np.zeros(3)])

    out = flex3rpr.rollouts(ex.SCENE, policy=policy, n=len(grid), periods=periods,
                            overrides=ex.START_FIELDS)
    error = np.hypot(out["x_p"] - ex.TARGET[0], out["y_p"] - ex.TARGET[1])
    tips = np.sqrt(out["w_tip_1"] ** 2 + out["w_tip_2"] ** 2 + out["w_tip_3"] ** 2)
    cost = np.nanmean(error ** 2, axis=1) + 1e2 * np.nanmean(tips ** 2, axis=1)
    cost[np.array([bool(s) for s in out["status"]])] = np.inf  # a run the physics stopped
    best = int(np.argmin(cost))
    result = {"rollouts": len(grid), "periods": periods, "best_kp": grid[best][0],
              "best_kd": grid[best][1], "best_cost": float(cost[best]),
              "final_error_m": float(error[best, -1]), "max_tip_deflection_m":
              float(np.nanmax(tips[best]))}
    with open(os.path.join(args.out, "pd_grid.json"), "w") as f:
        json.dump(result, f, indent=1)
    image = np.log10(cost.reshape(len(kps), len(kds)))
    fig, ax = plt.subplots(figsize=(6, 4.5))
    mesh = ax.pcolormesh(kds, kps, image, shading="nearest")
    ax.set_xscale("log"), ax.set_yscale("log")
    ax.plot(grid[best][1], grid[best][0], "r*", markersize=14)
    ax.set_xlabel("kd (N s/m)"), ax.set_ylabel("kp (N/m)")
    ax.set_title("PD on the legs: log10 cost, %d rollouts" % len(grid))
    fig.colorbar(mesh)
    fig.savefig(os.path.join(args.out, "pd_grid.png"), dpi=90, bbox_inches="tight")
    print("pd_grid_search: %d rollouts; best kp %.4g N/m, kd %.4g N s/m: final error %.3g m, "
          "largest tip deflection %.3g m" % (len(grid), result["best_kp"], result["best_kd"],
                                             result["final_error_m"],
                                             result["max_tip_deflection_m"]))


if __name__ == "__main__":
    main()
