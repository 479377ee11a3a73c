"""The Python module (import flex3rpr) against the CLI it must equal, and as a user calls it.

Run by ctest (CMakeLists.txt: python module) with the catkin workspace's environment; F3R_CLI
names flex3rpr_sim. No test asserts a duration or a rate."""
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import flex3rpr

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
SCENES = os.path.join(ROOT, "config", "scenes")
CLI = os.environ.get("F3R_CLI", os.path.join(ROOT, "build", "ws", "devel", "lib", "flex3rpr",
                                             "flex3rpr_sim"))
REST = os.path.join(SCENES, "rest.yaml")


def cli_csv(scene, sets, workdir):
    out = os.path.join(workdir, "run.csv")
    args = [CLI, scene, "--out", out]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def test_the_module_and_the_generated_messages_import_side_by_side():
    import flex3rpr.msg
    import flex3rpr.srv
    assert hasattr(flex3rpr.msg, "EffortCommand") and hasattr(flex3rpr.srv, "StepWithCommand")
    assert flex3rpr.Sim is flex3rpr.sim.Sim


@pytest.mark.parametrize("scene,sets", [
    ("paper_sim1.yaml", ["run.duration=0.03"]),
    ("end_stop_impact.yaml", ["run.duration=0.03"]),  # impacts, and the stop-force columns
    ("paper_sim3_fixed_free.yaml", ["run.duration=0.01", "solver.integrator=erk"]),
])
def test_run_gives_the_values_of_the_cli_csv(scene, sets, tmp_path):
    header, rows = cli_csv(os.path.join(SCENES, scene), sets, str(tmp_path))
    sim = flex3rpr.Sim(os.path.join(SCENES, scene),
                       overrides=dict(s.split("=", 1) for s in sets))
    result = sim.run()
    assert list(result) == header
    digits = {name: 15 for name in header}
    digits.update({"t": 10, "constraint_residual": 3})
    digits.update({n: 10 for n in header if n.startswith(("lambda_", "stop_force_"))})
    assert len(result["t"]) == len(rows)
    for c, name in enumerate(header):
        for k, row in enumerate(rows):
            # the CSV holds each value at its column's digits: the same text, read back
            assert float(row[c]) == float("%.*g" % (digits[name], result[name][k])), (name, k)


def test_a_bad_scene_names_the_file_the_field_and_the_range():
    with pytest.raises(flex3rpr.SceneError) as e:
        flex3rpr.Sim(REST, overrides={"links[0].modes": 99})
    message = str(e.value)
    assert "links[0].modes" in message and "1..20" in message and "rest.yaml" in message
    assert e.value.status == "scene"
    with pytest.raises(flex3rpr.SceneError) as e:
        flex3rpr.Sim({"links": {"model": "fixed_free", "modes": 2}, "run": {"duration": -1}})
    assert "<dict>" in str(e.value) and "run.duration" in str(e.value)
    with pytest.raises(FileNotFoundError):
        flex3rpr.Sim("no_such_scene.yaml")


def test_keyword_overrides_and_yaml_strings_are_the_scene_fields():
    a = flex3rpr.Sim(REST, links__modes=3)
    b = flex3rpr.Sim("links: {model: fixed_free, modes: 3, damping_ratio: 0.01}\n"
                     "effects:\n  joint_friction: {prismatic: [5.0, 5.0, 5.0], "
                     "revolute: [0.01, 0.01, 0.01]}\n  end_stops: {}\n")
    assert a.modes == b.modes == [3, 3, 3]
    for k in range(20):
        sa = a.step([5.0 * np.sin(k), 1.0, -2.0, 0.0, 0.0, 0.0]).vector.copy()
        sb = b.step([5.0 * np.sin(k), 1.0, -2.0, 0.0, 0.0, 0.0]).vector
        assert np.array_equal(sa, sb)


def test_a_bad_command_is_refused_and_changes_nothing():
    a, b = flex3rpr.Sim(REST), flex3rpr.Sim(REST)
    a.step([10.0, 0, 0, 0, 0, 0], periods=3)
    b.step([10.0, 0, 0, 0, 0, 0], periods=3)
    before = a.state.vector.copy()
    for bad in ([np.nan, 0, 0, 0, 0, 0], [1.0, 2.0], {"leg_forces": [1, 2, 3]},
                {"leg_force": [1, 2]}, [0, 0, 0, np.inf, 0, 0]):
        with pytest.raises(ValueError):
            a.step(bad)
        assert np.array_equal(a.state.vector, before)
    held = np.zeros(a.nq)
    held[0] = np.nan
    with pytest.raises(flex3rpr.Error) as e:  # the fast path: the core refuses it
        a.step_forces(held)
    assert "not finite" in str(e.value)
    assert np.array_equal(a.state.vector, before)
    # and the simulation runs on as if nothing had been sent
    for k in range(10):
        assert np.array_equal(a.step([1.0 * k, 0, 0, 0, 0.01, 0]).vector.copy(),
                              b.step([1.0 * k, 0, 0, 0, 0.01, 0]).vector)


def test_commands_in_every_form_and_periods_agree():
    a, b, c = flex3rpr.Sim(REST), flex3rpr.Sim(REST), flex3rpr.Sim(REST)
    sa = a.step([3.0, -1.0, 0.5, 0.01, 0.0, -0.01], periods=7).vector
    for _ in range(7):
        sb = b.step({"leg_force": [3.0, -1.0, 0.5], "cylinder_torque": [0.01, 0.0, -0.01]})
    held = np.zeros(c.nq)
    held[:6] = [3.0, -1.0, 0.5, 0.01, 0.0, -0.01]
    for _ in range(7):
        sc = c.step_forces(held)
    assert np.array_equal(sa, sb.vector) and np.array_equal(sa, sc)
    assert sb.t == pytest.approx(0.007, abs=1e-15)
    assert np.array_equal(sb.pose, [sb.x_p, sb.y_p, sb.phi_p])
    assert sb["eta_1_1"] == sb.modal[0]


def test_state_set_state_and_reset():
    sim = flex3rpr.Sim(REST, overrides={"effects.end_stops": {}})
    start = sim.state.vector.copy()
    sim.set_state([0.01, -0.005, 0.1], [0.0, 0.0, 0.0])
    assert np.array_equal(sim.state.pose, [0.01, -0.005, 0.1])
    with pytest.raises(flex3rpr.Error) as e:
        sim.set_state([0.3, 0.0, 0.0])  # a stroke beyond the end stops
    assert "stroke" in str(e.value) or "stop" in str(e.value)
    assert np.array_equal(sim.state.pose, [0.01, -0.005, 0.1])
    with pytest.raises(ValueError):
        sim.set_state([0.0, 0.0])
    sim.step([1.0, 0, 0, 0, 0, 0], periods=5)
    sim.reset()
    assert np.array_equal(sim.state.vector, start)
    assert sim.t == 0.0


def test_linearise_equals_the_cli_export(tmp_path):
    mat = os.path.join(str(tmp_path), "plant.mat")
    subprocess.run([CLI, REST, "--linearise", mat], check=True, stdout=subprocess.DEVNULL)
    with open(mat[:-4] + ".json") as f:
        exported = json.load(f)
    plant = flex3rpr.Sim(REST).linearise()
    for key in ("A", "B", "C", "D"):
        assert np.array_equal(plant[key], np.array(exported[key])), key
    assert plant["state_names"] == exported["state_names"]
    assert plant["input_names"] == exported["input_names"]
    assert plant["output_names"] == exported["output_names"]


def test_modal_frequencies_are_the_linear_plants():
    sim = flex3rpr.Sim(REST)
    hz = sim.modal()
    plant = sim.linearise()
    eig = np.linalg.eigvals(plant["A"])
    flexible = np.sort(np.abs(eig.imag[eig.imag > 1.0])) / (2 * np.pi)
    assert len(hz) == 3 + sum(sim.modes)
    # the damped modes' frequencies are the natural ones within their 1 % damping
    assert np.allclose(np.sort(hz[hz > 1.0]), flexible, rtol=1e-3)


def test_the_accuracy_knob_reports_its_choice():
    sim = flex3rpr.Sim(REST, overrides={"links.modes": "auto"}, accuracy=1e-4)
    report = sim.accuracy
    assert report["request"] == 1e-4
    assert report["error_basis"] == "estimated"
    assert sim.modes == report["modes"]
    assert report["estimated_error"] > 0


def test_rollouts_equal_runs_one_by_one_and_split_into_parts(tmp_path):
    rng = np.random.default_rng(5)
    commands = rng.normal(0.0, 5.0, size=(4, 30, 6))
    commands[:, :, 3:] *= 0.001
    whole = flex3rpr.rollouts(REST, commands=commands, n=4, periods=30, processes=2)
    for i in range(4):
        sim = flex3rpr.Sim(REST)
        for k in range(30):
            s = sim.step(commands[i, k])
        assert whole["x_p"][i, -1] == s.x_p and whole["w_tip_2"][i, -1] == s.w_tip_2
    assert whole["status"] == [""] * 4
    parts = []
    for k in range(2):
        path = os.path.join(str(tmp_path), "part%d.npz" % k)
        flex3rpr.rollouts.__globals__["_save"](
            path, flex3rpr.rollouts(REST, commands=commands, n=4, periods=30, part=(k, 2)))
        parts.append(path)
    merged = flex3rpr.rollouts.__globals__["merge"](parts)
    assert np.array_equal(merged["x_p"], whole["x_p"])


def test_a_policy_and_per_run_overrides_make_a_parameter_study():
    def policy(state, k, run):
        return [-200.0 * (state.rho_1 - 0.12), 0, 0, 0, 0, 0]
    masses = [0.0, 0.05, 0.1]
    out = flex3rpr.rollouts(REST, policy=policy, n=3, periods=50,
                            overrides=[{"effects.payload.mass": m} for m in masses], processes=2)
    one = flex3rpr.Sim(REST, overrides={"effects.payload.mass": 0.1})
    state = one.state
    for k in range(50):
        state = one.step(policy(state, k, 2))
    assert out["rho_1"][2, -1] == state.rho_1
    assert out["rho_1"][0, -1] != out["rho_1"][2, -1]  # the payload shows


def test_the_environment_has_gymnasiums_shape():
    env = flex3rpr.Flex3rprEnv(scene=REST, horizon=20, start=[0.0, 0.02, 0.0], start_noise=1e-3)
    o1, info = env.reset(seed=3)
    o2, _ = env.reset(seed=3)
    assert np.array_equal(o1, o2) and len(o1) == len(env.observation_names)
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step(np.zeros(6))
        steps += 1
        assert np.isfinite(reward)
        if terminated or truncated:
            break
    assert truncated and steps == 20 and info["reason"].startswith("horizon")
    env = flex3rpr.Flex3rprEnv(scene=REST, limit=1e-3, horizon=10000)
    env.reset(seed=0)
    for _ in range(5000):
        obs, reward, terminated, truncated, info = env.step([200.0, -200.0, 0, 0, 0, 0])
        if terminated:
            break
    assert terminated and info["reason"].startswith("limit")


@pytest.mark.parametrize("example", ["pd_grid_search.py", "lqr_scipy.py", "monte_carlo.py"])
def test_the_examples_run(example, tmp_path):
    subprocess.run([sys.executable, os.path.join(ROOT, "examples", "python", example), "--quick",
                    "--out", str(tmp_path)], check=True)
    assert any(name.endswith(".png") for name in os.listdir(str(tmp_path)))


def test_the_scenes_sensors_are_read_as_the_cli_writes_them(tmp_path):
    scene = os.path.join(ROOT, "test", "scenes", "sensors_fixed_free.yaml")
    a, b = flex3rpr.Sim(scene), flex3rpr.Sim(scene)
    assert a.sensor_names == ["enc_rho_1", "enc_rho_2", "enc_rho_3", "enc_theta_1",
                              "enc_theta_2", "enc_theta_3", "strain_1", "strain_2", "strain_3",
                              "accel_x", "accel_y", "gyro_z"]
    header, _ = cli_csv(scene, ["run.duration=0.002"], str(tmp_path))
    assert header[-len(a.sensor_names):] == a.sensor_names
    readings = []
    for k in range(30):
        a.step([20.0, 0, 0, 0, 0, 0])
        b.step([20.0, 0, 0, 0, 0, 0])
        assert np.array_equal(a.sensors, b.sensors)  # the noise is the seed's, every run
        readings.append(a.sensors)
    readings = np.array(readings)
    # the encoders are quantised to their 1 um resolution
    assert np.allclose(readings[:, 0] / 1e-6, np.round(readings[:, 0] / 1e-6), atol=1e-6)
    env = flex3rpr.Flex3rprEnv(scene=scene, horizon=5)
    obs, _ = env.reset(seed=1)
    assert env.observation_names == a.sensor_names and len(obs) == 12


def test_rollouts_split_over_gnu_parallel_merge_into_the_whole(tmp_path):
    spec = {"scene": REST, "n": 3, "periods": 20,
            "overrides": [{"effects.payload.mass": m} for m in (0.0, 0.05, 0.1)],
            "policy": "rollout_policy:push", "processes": 1}
    with open(str(tmp_path / "spec.json"), "w") as f:
        json.dump(spec, f)
    with open(str(tmp_path / "rollout_policy.py"), "w") as f:
        f.write("def push(state, k, run):\n    return [5.0, -2.0, 0.0, 0.0, 0.0, 0.0]\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path) + os.pathsep +
               os.environ.get("PYTHONPATH", ""))
    subprocess.run(["parallel", sys.executable, "-m", "flex3rpr.rollouts",
                    str(tmp_path / "spec.json"), "--part", "{}/2", "--out",
                    str(tmp_path / "part{}.npz"), ":::", "0", "1"], check=True, env=env,
                   cwd=str(tmp_path))
    subprocess.run([sys.executable, "-m", "flex3rpr.rollouts", "--merge",
                    str(tmp_path / "part0.npz"), str(tmp_path / "part1.npz"), "--out",
                    str(tmp_path / "all.npz")], check=True, env=env)
    merged = np.load(str(tmp_path / "all.npz"), allow_pickle=True)
    whole = flex3rpr.rollouts(REST, policy=lambda s, k, r: [5.0, -2.0, 0, 0, 0, 0], n=3,
                              periods=20, overrides=spec["overrides"], processes=1)
    assert list(merged["runs"]) == [0, 1, 2]
    assert np.array_equal(merged["x_p"], whole["x_p"])
