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
REST_TURNED = os.path.join(SCENES, "rest_turned.yaml")


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
    with pytest.raises(flex3rpr.ArgumentError) as e:  # the fast path: the core refuses it
        a.step_forces(held)
    assert "leg_force_1 is nan, not finite" in str(e.value)
    assert np.array_equal(a.state.vector, before)
    # the session's checks, the node's: the scene's limits, whole periods, arrays as numpy has them
    refusals = [
        (lambda: a.step([5000.0, 0, 0, 0, 0, 0]), flex3rpr.ArgumentError,
         "leg_force_1 is 5000, out of range -1000..1000 (the scene's limits.force)"),
        (lambda: a.step([0, 0, 0, 0, 150.0, 0]), flex3rpr.ArgumentError,
         "cylinder_torque_2 is 150, out of range -100..100 (the scene's limits.torque)"),
        (lambda: a.step({"modal": [0, 0, 0, 2e3, 0, 0]}), flex3rpr.ArgumentError, "modal_force[3]"),
        (lambda: a.step([1e12, 0, 0, 0, 0, 0]), flex3rpr.ArgumentError, "leg_force_1 is 1e+12"),
        (lambda: a.step(None, periods=2.9), flex3rpr.ArgumentError, "periods is 2.9"),
        (lambda: a.step(None, periods=-3), flex3rpr.ArgumentError, "periods is -3"),
        (lambda: a.step(None, periods=0), flex3rpr.ArgumentError, "periods is 0"),
        (lambda: a.step(None, periods="x"), TypeError, "periods"),
        (lambda: a.step_forces(np.zeros(3)), TypeError, "of %d values expected" % a.nq),
        (lambda: a.step_forces(np.zeros(a.nq, dtype=np.int64)), TypeError, "int64"),
        (lambda: a.step_forces(np.zeros(2 * a.nq)[::2]), TypeError, "not contiguous"),
        (lambda: a.step_forces(list(np.zeros(a.nq))), TypeError, "list"),
        (lambda: a.set_state([2.0, 0, 0]), flex3rpr.ArgumentError, "pose[0] is 2: out of range -1..1"),
        (lambda: a.set_state([0, 0, 1e6]), flex3rpr.ArgumentError, "pose[2] is 1e+06"),
        (lambda: a.set_state([0, 0, 0], modal=[0, 0, 1.0, 0, 0, 0]), flex3rpr.ArgumentError,
         "modal[2] is 1: out of range -0.1..0.1"),
        (lambda: a.set_state([0, 0, 0], modal=[0, 0]), flex3rpr.ArgumentError,
         "modal: 2 values, the model has 6"),
        (lambda: a.set_state([0, 0, 0], [0, np.nan, 0]), flex3rpr.ArgumentError, "twist[1] is nan"),
    ]
    for call, kind, text in refusals:
        with pytest.raises(kind) as e:
            call()
        assert text in str(e.value)
        assert "nothing changed" in str(e.value)
        assert np.array_equal(a.state.vector, before), text
    assert a.t == b.t
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
    # every State step() returns stays as it was
    states = [a.step([1.0, 0, 0, 0, 0, 0]) for _ in range(3)]
    assert [round(s.t, 12) for s in states] == [0.008, 0.009, 0.01]
    assert np.array_equal(sb.pose, [sb.x_p, sb.y_p, sb.phi_p])
    assert sb["eta_1_1"] == sb.modal[0]


def test_periods_are_checked_when_the_sim_is_made():
    for period in (0, -1e-3, float("nan"), "x", 1e4):
        with pytest.raises(flex3rpr.ArgumentError) as e:
            flex3rpr.Sim(REST, period=period)
        assert "period is" in str(e.value)


def test_a_failed_step_leaves_the_sim_as_it_was():
    """A leg pulled in at the force limit with no stops collapses: the step raises, and state,
    extras, sensors and the next steps are those of a Sim that never took it."""
    scene = os.path.join(ROOT, "test", "scenes", "sensors_fixed_free.yaml")  # no end stops
    a, b = flex3rpr.Sim(scene), flex3rpr.Sim(scene)
    for s in (a, b):
        s.step([2.0, 0, 0, 0, 0.01, 0], periods=5)
    before, extras, sensors = a.state.vector.copy(), a.extras, a.sensors
    with pytest.raises(flex3rpr.Error) as e:
        a.step([-1000.0, 0, 0, 0, 0, 0], periods=500)
    assert "collapsed" in str(e.value)
    assert np.array_equal(a.state.vector, before) and np.array_equal(a.sensors, sensors)
    after = a.extras
    for key, value in extras.items():
        assert np.array_equal(after[key], value), key
    for k in range(5):
        assert np.array_equal(a.step([0.5 * k + 0.1, 0, 0, 0, 0, 0]).vector,
                              b.step([0.5 * k + 0.1, 0, 0, 0, 0, 0]).vector)
        assert np.array_equal(a.sensors, b.sensors)


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
    with pytest.raises(RuntimeError):  # the episode has ended: reset() first
        env.step(np.zeros(6))
    env.reset()
    env.step(np.zeros(6))
    env = flex3rpr.Flex3rprEnv(scene=REST, limit=1e-3, horizon=10000)
    env.reset(seed=0)
    for _ in range(5000):
        obs, reward, terminated, truncated, info = env.step([200.0, -200.0, 0, 0, 0, 0])
        if terminated:
            break
    assert terminated and info["reason"].startswith("limit")


def test_the_default_environment_works_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    env = flex3rpr.Flex3rprEnv()
    env.reset(seed=1)
    assert env.sim.state.phi_p == pytest.approx(0.3)  # rest_turned.yaml: off the singular home
    assert env.sim.extras["actuation_condition"] < 1e3
    assert env.action_limit == 200.0
    if env.action_space is not None:
        assert env.action_space.high[0] == 200.0
    assert flex3rpr.scene_path("rest.yaml").endswith(os.path.join("config", "scenes", "rest.yaml"))


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
    # rollouts keep the sensors' columns, the readings a Sim stepped alone gives
    out = flex3rpr.rollouts(scene, commands=np.tile([20.0, 0, 0, 0, 0, 0], (30, 1)), n=1,
                            periods=30, processes=1)
    for c, name in enumerate(a.sensor_names):
        assert np.array_equal(out[name][0, 1:], readings[:, c]), name


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


def test_a_closed_loop_measures_its_accuracy_as_it_runs():
    """With an accuracy request the Sim steps the check configuration on the same commands and
    reports the largest end-effector distance from it; the run itself is the unmeasured one's."""
    measured = flex3rpr.Sim(REST_TURNED, accuracy=1e-5)
    plain = flex3rpr.Sim(REST_TURNED, accuracy=1e-5, overrides={"accuracy.verify": False})
    assert plain.measured_error_m is None and plain.request_met is None
    assert flex3rpr.Sim(REST_TURNED).measured_error_m is None  # no request, no check
    assert measured.measured_error_m == 0.0 and measured.request_met
    errors = []
    target = np.array([0.126, 0.126, 0.126])
    for k in range(150):  # a step PD on the strokes towards a new target, a naive controller
        rho = measured.state.q[:3]
        rate = measured.state.v[:3]
        u = np.zeros(6)
        u[:3] = 400.0 * (target + (0.01 if k >= 20 else 0.0) - rho) - 20.0 * rate
        a, b = measured.step(u), plain.step(u)
        assert np.array_equal(a.vector, b.vector), "the check must not change the run"
        errors.append(measured.measured_error_m)
    assert all(np.isfinite(errors)) and errors[-1] > 0.0
    assert all(y >= x for x, y in zip(errors, errors[1:])), "the largest distance so far"
    assert measured.request_met == (errors[-1] <= 0.7 * 1e-5)
    # a modal state the richer basis cannot take ends the measurement, saying so
    measured.set_state(measured.state.pose, modal=np.full(measured.nq - 9, 1e-5))
    assert np.isnan(measured.measured_error_m) and "modal state" in measured.measurement_note
    measured.reset()
    assert measured.measured_error_m == 0.0 and measured.measurement_note == ""


def test_an_unmet_request_warns_once():
    sim = flex3rpr.Sim(REST_TURNED, accuracy=1e-9, overrides={"links.modes": 1})
    with pytest.warns(RuntimeWarning, match="not met: measured"):
        for k in range(40):
            sim.step([50.0 if k < 10 else 0.0, 0, 0, 0, 0, 0])
    assert sim.request_met is False and sim.measured_error_m > 0.7e-9
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # latched: no second warning until reset
        sim.step([0.0] * 6)
