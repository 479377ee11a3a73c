"""Plots end-effector paths and tip deflections from flex3rpr_sim CSV files.

usage: plot_paths.py OUT.png CSV[:LABEL] [CSV[:LABEL] ...]
Each CSV is a flex3rpr_sim output. The figure shows the path of P (mm), X_p and Y_p against
time, and the tip deflections w_i(l) of each run."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {key: [float(r[key]) for r in rows] for key in rows[0]}


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    out = argv[1]
    runs = []
    for spec in argv[2:]:
        path, _, label = spec.partition(":")
        runs.append((label or path, read(path)))
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    for label, d in runs:
        ax[0, 0].plot([1e3 * x for x in d["x_p"]], [1e3 * y for y in d["y_p"]], label=label, lw=0.8)
        ax[0, 1].plot(d["t"], [1e3 * x for x in d["x_p"]], label=f"X_p {label}", lw=0.8)
        ax[0, 1].plot(d["t"], [1e3 * y for y in d["y_p"]], label=f"Y_p {label}", lw=0.8)
        for i in (1, 2, 3):
            ax[1, 0].plot(d["t"], [1e3 * w for w in d[f"w_tip_{i}"]], label=f"w_{i}(l) {label}", lw=0.7)
        ax[1, 1].plot(d["t"], d["phi_p"], label=label, lw=0.8)
    ax[0, 0].set(xlabel="X_p (mm)", ylabel="Y_p (mm)", title="End-effector path")
    ax[0, 0].axis("equal")
    ax[0, 1].set(xlabel="t (s)", ylabel="position (mm)", title="End-effector position")
    ax[1, 0].set(xlabel="t (s)", ylabel="w_i(l) (mm)", title="Tip deflections")
    ax[1, 1].set(xlabel="t (s)", ylabel="phi_p (rad)", title="Platform angle")
    for a in ax.flat:
        a.grid(True, lw=0.3)
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv)
