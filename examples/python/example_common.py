"""What the Python examples share: the scene, a controllable start, the move, arguments, LQR."""
import argparse
import os

import numpy as np
import scipy.linalg
import scipy.signal

import flex3rpr

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
SCENE = os.path.join(ROOT, "config", "scenes", "rest.yaml")
# Home (phi = 0) is a type-II singularity of leg-force actuation (actuation condition 1e16): leg
# forces cannot turn the platform there. Turned by 0.3 rad the condition number is 2.0.
START = [0.0, 0.0, 0.3]
TARGET = np.array([0.01, 0.0, 0.3])  # a 1 cm move in x
START_FIELDS = {"initial.platform_pose": START}


def arguments(doc):
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a few short runs (the tests')")
    parser.add_argument("--out", default=os.path.join(ROOT, "output", "python"),
                        help="folder for the plot and the numbers (default output/python)")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    return args


def legs_at(pose, overrides=None):
    """The leg strokes rho_1..3 that put the platform at pose (the loop closure, via set_state)."""
    sim = flex3rpr.Sim(SCENE, overrides=dict(START_FIELDS, **(overrides or {})))
    sim.set_state(pose)
    return sim.state.q[:3].copy()


def lqr(plant, dt, pose_scale=(0.001, 0.001, 0.003), rate_scale=(0.05, 0.05, 0.15),
        tip_scale=1e-6, force_scale=5.0, torque_scale=0.05):
    """The discrete LQR gain K (u = -K x) of the plant (Sim.linearise()) at period dt, with
    Bryson's weights: pose error, its rate, and the tip deflections (which damp the links)."""
    A, B, C = plant["A"], plant["B"], plant["C"]
    n = A.shape[0] // 2
    Ad, Bd, _, _, _ = scipy.signal.cont2discrete((A, B, C, np.zeros((C.shape[0], 6))), dt)
    q = np.zeros(2 * n)
    q[:3] = 1.0 / np.square(pose_scale)
    q[n:n + 3] = 1.0 / np.square(rate_scale)
    tips = C[9:12, :]  # the tip deflections' rows (output_names)
    Q = np.diag(q) + tips.T @ tips / tip_scale ** 2
    R = np.diag([1.0 / force_scale ** 2] * 3 + [1.0 / torque_scale ** 2] * 3)
    P = scipy.linalg.solve_discrete_are(Ad, Bd, Q, R)
    return np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad), Ad, Bd


def plant_state(state, plant):
    """x = (z - z0, z') of the plant from a State: z = (pose, modal coordinates)."""
    z = np.concatenate([state.pose, state.modal])
    zdot = np.concatenate([state.twist, state.modal_rate])
    n = len(z)
    return np.concatenate([z - plant["x0"][:n], zdot])
