"""The Python package against the command line: the same requests give the same answers (the same
C++ computes both, so numbers agree exactly or to the last digit of the CLI's output), and the same
bad inputs give the same messages. Run by ctest (tests/CMakeLists.txt) with PYTHONPATH at the
built package and WLX_BINARY the built `wlx`."""

import csv
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import wlx

WLX = os.environ["WLX_BINARY"]
README = Path(__file__).resolve().parents[2] / "README.md"


def cli(args, stdin=""):
    return subprocess.run([WLX, *args], input=stdin, capture_output=True, text=True, check=False)


def cli_json(args, request):
    done = cli(args, json.dumps(request))
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.fixture(scope="module", params=wlx.models())
def robot(request):
    return wlx.model(request.param)


def test_models_and_tables(robot):
    listed = cli(["models"]).stdout
    assert robot.name in listed
    assert len(robot.coordinates) == len(robot.units) > robot.input_count > 0
    assert all(math.isfinite(v) for v in robot.params.values())


def base_input(robot, axis):
    """The model's base position input along axis ("x" or "z"): the first input named <axis>_..."""
    return next(n for n in robot.inputs if n.startswith(axis + "_"))


def nominal(robot, name):
    return robot.ik()["s"][robot.coordinates.index(name)]


# Each model has its own names: the base's height and position inputs, its first parameter.
IK_REQUESTS = {
    "nominal": lambda robot: {},
    "base lowered 2 cm and pitched 3 deg": lambda robot: {
        base_input(robot, "z"): nominal(robot, base_input(robot, "z")) - 0.02, "pitch": {"deg": 3}},
    "first parameter 2% larger": lambda robot: {"params": {k: v * 1.02 for k, v in list(robot.params.items())[:1]}},
    "newton, base moved 2 cm": lambda robot: {
        "method": "newton", base_input(robot, "x"): nominal(robot, base_input(robot, "x")) + 0.02},
}


@pytest.mark.parametrize("request_name", list(IK_REQUESTS))
def test_ik_answers_what_wlx_ik_answers(robot, request_name):
    request_ = IK_REQUESTS[request_name](robot)
    expected = cli_json(["ik", "--model", robot.name], request_)
    got = robot.ik(request_)
    s = got.pop("s")
    assert got == expected  # the same dict: the CLI prints doubles round-trip exact
    for k in range(robot.input_count, len(robot.coordinates)):
        assert s[k] == expected[robot.coordinates[k]]


def test_ik_branches_give_other_solutions():
    robot = wlx.model("excavator")
    first = robot.ik({"branch": {"leg_l": 0}})
    other = robot.ik({"branch": {"leg_l": 1}})
    assert other["branch"]["leg_l"] == 1
    assert not np.allclose(first["s"], other["s"])
    assert other["closure_residual"] <= 1e-12
    assert other == {**cli_json(["ik"], {"branch": {"leg_l": 1}}), "s": other["s"]}


def test_fk_gives_what_wlx_fk_gives(robot):
    z = base_input(robot, "z")
    request = {z: nominal(robot, z) - 0.1, "roll": {"deg": 2}}
    expected = cli_json(["fk", "--json", "--model", robot.name], request)
    s = robot.ik(request)["s"]
    got = robot.fk(s)
    assert got["positions"].shape == (len(robot.frames), 3)
    for i, name in enumerate(robot.frames):
        frame = expected["frames"][name]
        np.testing.assert_array_equal(got["positions"][i], frame["position"])
        np.testing.assert_array_equal(got["rotations"][i], np.array(frame["rotation"]))


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.mark.parametrize("model_and_id", [("excavator", "NH-1"), ("excavator", "ID-1"), ("walker", None),
                                          ("wheeled_quadruped", "ID-Q2")])
def test_simulate_gives_the_csv_of_wlx_simulate(tmp_path, model_and_id):
    name, scenario = model_and_id
    robot = wlx.model(name)
    scenario = scenario or robot.scenarios[0]
    done = cli(["simulate", scenario, "--model", name, "--out", str(tmp_path)])
    assert done.returncode == 0, done.stderr
    header, table = read_csv(tmp_path / "trajectory.csv")
    run = robot.simulate(scenario)
    assert run["complete"] and run["stopped"] == ""
    for c, column in enumerate(header):
        np.testing.assert_array_equal(run[column], table[:, c], err_msg=column)


def test_errors_and_stopped_runs_say_what_kind_of_failure_they_are():
    # A program acts on the kind (the IK's status, the run's stop), never on the words.
    robot = wlx.model("excavator")
    with pytest.raises(wlx.Error, match="out of reach") as e:
        robot.ik({"z_C": 10.0})
    assert e.value.kind == "out-of-reach"
    with pytest.raises(wlx.Error, match="must be a number") as e:
        robot.ik({"z_C": "high"})
    assert e.value.kind == "other"
    # The body rises until the legs cannot reach the feet (3.5 m from the hip).
    run = robot.simulate({"rates": {"z_C": 1.0}, "duration": 4.0, "dt": 0.01, "dependent": ["y_C", "yaw"]})
    assert not run["complete"] and run["stop_kind"] == "out-of-reach" and "out of reach" in run["stopped"]
    # Both wheels on the ground under a level body: their sideways lines coincide.
    run = robot.simulate({"rates": {"roll": 0.1}, "duration": 0.1, "dt": 0.01, "dependent": ["y_C", "yaw"],
                          "initial": {"z_Wl": 0.0, "z_Wr": 0.0}})
    assert run["stop_kind"] == "singular" and "singular" in run["stopped"]
    assert robot.simulate("NH-1")["stop_kind"] == ""
    quadruped = wlx.model("wheeled_quadruped")
    base = {"dependent": ["y_lf", "y_rf", "y_lh", "y_rh"], "dt": 0.01, "duration": 2.0}
    # Lowering the body bends the knees beyond the URDF's -2.8 rad.
    run = quadruped.simulate({**base, "rates": {"z_B": -0.3}})
    assert run["stop_kind"] == "limit" and "outside its range" in run["stopped"]
    # Pitching up at 1 rad/s, limits let go: the machine tips over its hind wheels.
    run = quadruped.simulate({**base, "rates": {"pitch": 1.0}, "weighting": "contribution", "on_limit": "continue"})
    assert run["stop_kind"] == "contact" and "tips over" in run["stopped"]


def test_a_runs_summary_covers_every_sample_also_the_ones_not_kept():
    robot = wlx.model("excavator")
    full = robot.simulate("ID-1")
    thinned = robot.simulate("ID-1", every=7)
    assert len(thinned["t"]) < len(full["t"])
    for run in (full, thinned):  # the same C++ sums over the same samples: equal to the last bit
        summary = run["summary"]
        assert summary["peak_cond_J_beta"][0] == full["cond_J_beta"].max()
        assert summary["min_clearance"][0] == full["clearance"].min()
        peaks = [np.abs(full[f"tau_{a}"]).max() for a in robot.actuators]
        np.testing.assert_array_equal(summary["peak_tau"], peaks)
        # Squares summed in time order against NumPy's pairwise sum: n eps relative (n = 2001).
        rms = [np.sqrt(np.mean(full[f"tau_{a}"] ** 2)) for a in robot.actuators]
        np.testing.assert_allclose(summary["rms_tau"], rms, rtol=2001 * 2.2e-16, atol=0)
    # A kinematic run has no torques; no sample, no summary.
    assert set(robot.simulate("NH-1")["summary"]) == {"peak_cond_J_beta", "min_clearance"}


def test_simulate_takes_a_scenario_dict_like_a_file(tmp_path):
    robot = wlx.model("excavator")
    scenario = {"id": "mine", "rates": {"x_C": 1.0, "z_C": -0.5, "pitch": {"deg/s": 5}}, "dependent": ["y_C", "yaw"],
                "duration": 0.2}
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(scenario))
    from_dict, from_file = robot.simulate(scenario), robot.simulate(str(path))
    for column in ("t", "x_C", "yaw", "pitch", "theta_l3"):
        np.testing.assert_array_equal(from_dict[column], from_file[column])
    assert from_dict["t"][-1] == pytest.approx(0.2, abs=1e-12)


def test_simulate_keeps_every_kth_sample_and_refuses_a_run_beyond_its_memory_bound():
    robot = wlx.model("excavator")
    scenario = {"id": "mine", "rates": {"x_C": 1.0, "z_C": -0.5}, "dependent": ["y_C", "yaw"], "duration": 0.2}
    full, thinned = robot.simulate(scenario), robot.simulate(scenario, every=7)
    assert len(full["t"]) == 201 and len(thinned["t"]) == 29  # samples 0, 7, ..., 196
    for column in ("t", "x_C", "yaw", "theta_l3"):
        np.testing.assert_array_equal(thinned[column], full[column][::7], err_msg=column)
    # 5 10^7 samples of about a hundred columns: refused before anything runs or is allocated.
    long_run = dict(scenario, duration=5e4)
    with pytest.raises(wlx.Error, match=r"^every: the run would keep 50000001 samples .* more than 256 MiB"):
        robot.simulate(long_run)
    with pytest.raises(wlx.Error, match=r"^every: must be at least 1"):
        robot.simulate(scenario, every=0)
    with pytest.raises(TypeError):
        robot.simulate(scenario, every=2.5)


def test_inverse_dynamics_and_rates_match_the_simulation():
    # ID-1 at t = 0: the pose is the nominal one, u = [z_C', x_C', roll', pitch'] = [0, 3, 0, 0], u' = 0.
    robot = wlx.model("excavator")
    run = robot.simulate("ID-1")
    s = np.array([run[name][0] for name in robot.coordinates])
    dyn = robot.inverse_dynamics(s, [0.0, 3.0, 0.0, 0.0])
    taus = [c for c in run if c.startswith("tau_")]
    assert len(taus) == len(dyn["tau"]) == 8
    np.testing.assert_allclose(dyn["tau"], [run[c][0] for c in taus], rtol=1e-12, atol=1e-9)
    # The torques reproduce Q*: J_beta^T tau = Q*.
    np.testing.assert_allclose(dyn["J_beta"].T @ dyn["tau"], dyn["Qstar"], rtol=1e-10, atol=1e-6)
    sdot, cond = robot.dependent_rates(s, {"x_C": 3.0}, dependent=["y_C", "yaw"])
    for k, name in enumerate(robot.inputs):
        assert sdot[k] == pytest.approx(run[name + "_dot"][0], abs=1e-12)
    assert cond == pytest.approx(run["cond_J_beta"][0], rel=1e-12)


def test_forward_dynamics_inverts_the_inverse_dynamics_for_every_model():
    # The torques that the inverse dynamics gives for (s, u, u_dot), fed back, give u_dot again:
    # the same equations of motion solved the other way (cond(M) ~1e2 here, u_dot ~0.5).
    rng = np.random.default_rng(5)
    for name in ("excavator", "wheeled_quadruped"):
        robot = wlx.model(name)
        run = robot.simulate("ID-1" if name == "excavator" else "ID-Q1")  # inverse-dynamics runs: a pose they solve
        middle = len(run["t"]) // 2
        s = np.array([run[c][middle] for c in robot.coordinates])
        u = rng.uniform(-0.3, 0.3, len(robot.commanded))
        u_dot = rng.uniform(-0.5, 0.5, len(robot.commanded))
        try:
            dyn = robot.inverse_dynamics(s, u, u_dot)
        except wlx.Error as e:  # a pose where some speed moves no actuator: nothing to invert
            assert "move no actuator" in str(e)
            continue
        fwd = robot.forward_dynamics(s, u, dyn["tau"])
        np.testing.assert_allclose(fwd["u_dot"], u_dot, rtol=0, atol=1e-11)  # measured 2.6e-14 (quadruped)
        np.testing.assert_allclose(fwd["Qstar"], dyn["Qstar"], rtol=1e-9, atol=1e-9 * np.abs(dyn["Qstar"]).max())
    robot = wlx.model("excavator")
    s = np.array([robot.simulate("ID-1")[c][0] for c in robot.coordinates])
    with pytest.raises(wlx.Error, match=r"^tau: has 3 entries; the model has 8 actuators"):
        robot.forward_dynamics(s, [0.0, 3.0, 0.0, 0.0], [1.0, 2.0, 3.0])
    with pytest.raises(wlx.Error, match=r"^tau"):
        robot.forward_dynamics(s, [0.0, 3.0, 0.0, 0.0], [float("nan")] + [0.0] * 7)



def test_simulate_driven_by_torques_retraces_the_inverse_dynamics_run_for_every_model():
    # A dict scenario whose "torques" are an inverse-dynamics run's columns (what m.simulate gave),
    # cubic between the 1 ms rows, integrated by dopri5: the motion of that run again.
    for name, run_id in (("excavator", "ID-1"), ("walker", "ID-W1"), ("wheeled_quadruped", "ID-Q1")):
        robot = wlx.model(name)
        inverse = robot.simulate(run_id)
        assert inverse["complete"]
        spec = json.loads((Path(__file__).resolve().parents[2] / "scenarios" / name / (run_id + ".json")).read_text())
        torques = {"t": list(inverse["t"]), "interpolation": "cubic"}
        torques.update({"tau_" + a: list(inverse["tau_" + a]) for a in robot.actuators})
        forward = robot.simulate({"rates": spec["rates"], "duration": spec["duration"], "dt": spec["dt"],
                                  "integrator": "dopri5", "tolerance": 1e-12, "torques": torques})
        assert forward["complete"], forward["stopped"]
        for c in robot.coordinates:
            np.testing.assert_allclose(forward[c], inverse[c], rtol=0, atol=1e-8)  # the bound for a round trip
        assert forward["kinetic"].shape == inverse["t"].shape
    with pytest.raises(wlx.Error, match=r"^torques: has \"t\" but no column"):
        wlx.model("excavator").simulate({"duration": 0.01, "torques": {"t": [0, 0.01]}})


def test_simulate_driven_by_a_function_is_the_run_of_the_same_torques_as_a_table():
    # A function of time alone that interpolates a table linearly is the table's run (the same
    # torques at every stage): two paths into the same integration, equal to rounding. The times
    # it is asked at are the integrator's stages, inside [0, duration].
    robot = wlx.model("excavator")
    inverse = robot.simulate("ID-1")
    table = {"tau_" + a: inverse["tau_" + a] for a in robot.actuators}
    asked = []
    def torques(t, s, u):
        asked.append(t)
        assert s.shape == (len(robot.coordinates),) and u.shape == (len(robot.commanded),)
        return [np.interp(t, inverse["t"], table["tau_" + a]) for a in robot.actuators]
    scenario = {"rates": {"x_C": 3.0}, "duration": 0.494, "dt": 0.001}
    by_function = robot.simulate(scenario, torques=torques)
    by_table = robot.simulate({**scenario, "torques": {"t": list(inverse["t"]), **{k: list(v) for k, v in table.items()}}})
    assert by_function["complete"] and by_table["complete"]
    for c in robot.coordinates:
        np.testing.assert_allclose(by_function[c], by_table[c], rtol=0, atol=1e-12)
    assert len(asked) == by_function["evaluations"] and min(asked) == 0 and max(asked) == pytest.approx(0.494, abs=1e-12)


def test_simulate_torque_function_errors():
    robot = wlx.model("excavator")
    zero = lambda t, s, u: np.zeros(len(robot.actuators))
    with pytest.raises(wlx.Error, match=r"^torques: given twice"):
        robot.simulate({"duration": 0.01, "torques": {"run": "ID-1"}}, torques=zero)
    with pytest.raises(wlx.Error, match=r"^torques: a run is driven by its rates"):
        robot.simulate({"duration": 0.01, "weighting": 1, "dependent": ["y_C", "yaw"]}, torques=zero)
    with pytest.raises(TypeError, match=r"^torques: must be a function"):
        robot.simulate({"duration": 0.01}, torques=[0.0] * 8)
    with pytest.raises(TypeError, match=r"^torques: the function returned 3 numbers; the model has 8 actuators"):
        robot.simulate({"duration": 0.01}, torques=lambda t, s, u: [0.0, 0.0, 0.0])
    with pytest.raises(TypeError, match=r"^torques: the function must return 8 numbers"):
        robot.simulate({"duration": 0.01}, torques=lambda t, s, u: "torques")
    class Broken(Exception):
        pass
    def broken(t, s, u):
        raise Broken("the controller's own error")
    with pytest.raises(Broken, match="the controller's own error"):  # the caller's exception, unchanged
        robot.simulate({"duration": 0.01}, torques=broken)
    # A non-finite torque stops the run (its samples up to then are kept) and says why.
    run = robot.simulate({"duration": 0.01}, torques=lambda t, s, u: np.full(8, np.nan if t > 0.005 else 0.0))
    assert not run["complete"] and "non-finite torque" in run["stopped"] and run["t"][-1] <= 0.005 + 1e-12
    # A torque beyond a table's bound of 1e9 stops it the same way, naming the actuator, the value and
    # the bound (1e300 used to overflow the step and stop it with "-nan" for another cause).
    run = robot.simulate({"duration": 0.01}, torques=lambda t, s, u: np.full(8, 1e300 if t > 0.005 else 0.0))
    assert not run["complete"] and run["t"][-1] <= 0.005 + 1e-12, run["stopped"]
    assert "torques.psi_l2: the function gave 1e+300 at t = 0.00" in run["stopped"], run["stopped"]
    assert "beyond the bound of 1e+09" in run["stopped"] and "nan" not in run["stopped"], run["stopped"]


def test_a_torque_table_whose_rows_are_closer_than_a_step_can_resolve_is_an_error_naming_it():
    robot = wlx.model("excavator")
    table = {"t": [0.0, 1e-300, 0.005, 0.01], "interpolation": "cubic",
             **{"tau_" + a: [0.0, 1.0, 2.0, 0.0] for a in robot.actuators}}
    with pytest.raises(wlx.Error, match=r"^torques\.t: rows 0 and 1 are 1e-300 s apart: a table's rows must be at least 1e-09 s apart"):
        robot.simulate({"duration": 0.01, "torques": table})


def test_ctrl_c_stops_a_long_run_at_once():
    # A run of 2 x 10^6 steps (about 20 s); SIGINT a second in: Python's KeyboardInterrupt ends it
    # within a fraction of a second, not when the C++ loop would have finished.
    script = ("import time, wlx\n"
              "robot = wlx.model('excavator')\n"
              "print('running', flush=True)\n"
              "start = time.monotonic()\n"
              "try:\n"
              "    robot.simulate({'rates': {'x_C': 0.0}, 'dependent': ['y_C', 'yaw'], 'duration': 2000.0, 'dt': 0.001}, every=100000)\n"
              "except KeyboardInterrupt:\n"
              "    print('interrupted', flush=True)\n")
    env = dict(os.environ)
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, env=env)
    assert child.stdout.readline() == "running\n"
    time.sleep(1.0)
    child.send_signal(signal.SIGINT)
    sent = time.monotonic()
    out, _ = child.communicate(timeout=30)
    stopped_after = time.monotonic() - sent
    assert out == "interrupted\n", out
    assert stopped_after < 1.0, stopped_after  # the run had about 19 s to go


BAD_IK = [
    {"legD": 1},
    {"params": {"legD": -1}},
    {"z_C": "high"},
    {"pitch": {"deg": "x"}},
    {"x_Fl": 40.0},
    {"method": "newton", "start": {"psi_l2": "x"}},
    {"branch": {"leg_l": 7}},
]


@pytest.mark.parametrize("request_", BAD_IK, ids=lambda r: json.dumps(r))
def test_errors_are_wlx_errors_with_the_cli_message(request_):
    robot = wlx.model("excavator")
    done = cli(["ik"], json.dumps(request_))
    assert done.returncode == 2
    message = done.stderr.strip().removeprefix("wlx: error: ")
    with pytest.raises(wlx.Error) as caught:
        robot.ik(request_)
    assert str(caught.value) == message
    assert isinstance(caught.value, ValueError)


def test_array_arguments_are_checked():
    robot = wlx.model("excavator")
    with pytest.raises(wlx.Error, match=r"^s: has 3 entries"):
        robot.fk([0.0, 1.0, 2.0])
    s = robot.ik()["s"]
    s[2] = float("nan")
    with pytest.raises(wlx.Error, match="not a finite number"):
        robot.fk(s)
    with pytest.raises(wlx.Error, match=r"^model: unknown model"):
        wlx.model("tractor")


@pytest.mark.parametrize("name", wlx.models())
def test_arrays_of_states_give_what_one_state_at_a_time_gives(name):
    # fk and inverse_dynamics over N x n arrays (one call, no JSON per state) against the same
    # computations state by state (fk's one-state call goes through the same C++; inverse_dynamics'
    # through the JSON path of the command line): equal to the last bit.
    robot = wlx.model(name)
    rng = np.random.default_rng(11)
    s0 = robot.ik()["s"]
    states = s0 + 1e-3 * rng.standard_normal((25, len(s0)))
    batch = robot.fk(states)
    assert batch["positions"].shape == (25, len(robot.frames), 3)
    assert batch["rotations"].shape == (25, len(robot.frames), 3, 3)
    for k in (0, 7, 24):
        one = robot.fk(states[k])
        np.testing.assert_array_equal(batch["positions"][k], one["positions"])
        np.testing.assert_array_equal(batch["rotations"][k], one["rotations"])
    if not robot.commanded:
        return
    # Poses the closure holds (the IK's), commanded speeds and their rates at random.
    poses = np.array([robot.ik({robot.inputs[0]: s0[0] + 0.01 * k})["s"] for k in range(6)])
    u = 0.2 * rng.standard_normal((6, len(robot.commanded)))
    u_dot = 0.5 * rng.standard_normal((6, len(robot.commanded)))
    for weighting in (1, 2):
        many = robot.inverse_dynamics(poses, u, u_dot, weighting=weighting)
        assert many["tau"].shape == (6, len(robot.actuators)) and many["Qstar"].shape == (6, len(robot.commanded))
        for k in range(6):
            one = robot.inverse_dynamics(poses[k], u[k], u_dot[k], weighting=weighting)
            np.testing.assert_array_equal(many["tau"][k], one["tau"])
            np.testing.assert_array_equal(many["Qstar"][k], one["Qstar"])


def test_a_bad_row_of_an_array_of_states_is_named_by_its_row():
    robot = wlx.model("excavator")
    s0 = robot.ik()["s"]
    states = np.tile(s0, (4, 1))
    states[2, robot.coordinates.index("x_C")] = float("nan")
    with pytest.raises(wlx.Error, match=r"^s\[2\]\.x_C: is not a finite number"):
        robot.fk(states)
    with pytest.raises(wlx.Error, match=r"^s: has rows of 3 entries; the model has 32 coordinates"):
        robot.fk(np.zeros((4, 3)))
    u = np.zeros((4, 4))
    u[1, 1] = float("inf")
    with pytest.raises(wlx.Error, match=r"^u\[1\]\.x_C: is not a finite number"):
        robot.inverse_dynamics(np.tile(s0, (4, 1)), u)
    with pytest.raises(wlx.Error, match=r"^weighting: the contacts' distribution solves an optimisation per state"):
        robot.inverse_dynamics(np.tile(s0, (4, 1)), np.zeros((4, 4)), weighting="contacts")
    with pytest.raises(wlx.Error, match=r"^u: s, u and u_dot must have as many rows"):
        robot.inverse_dynamics(np.tile(s0, (4, 1)), np.zeros((3, 4)))


def test_fk_with_parameters_gives_what_wlx_fk_gives_with_them(tmp_path):
    # Another parameter set gets a workspace of its own (and the model's own stays as it was).
    robot = wlx.model("excavator")
    params = {"thighD": 2.4}
    (tmp_path / "p.json").write_text(json.dumps(params))
    expected = cli_json(["fk", "--json", "--params", str(tmp_path / "p.json")], {})
    s = robot.ik({"params": params})["s"]
    got = robot.fk(s, params=params)
    for i, name in enumerate(robot.frames):
        np.testing.assert_array_equal(got["positions"][i], expected["frames"][name]["position"])
    default = robot.fk(s)
    assert np.abs(default["positions"] - got["positions"]).max() > 0.1


def readme_python_blocks():
    # The README's Python examples: each python block after "<!-- ci: python -->", as it stands.
    # The one through wlx.sweep is tests/python/test_sweep.py's.
    blocks = re.findall(r"<!-- ci: python -->\s*```python\n(.*?)```", README.read_text(), re.S)
    blocks = [b for b in blocks if "wlx.sweep(" not in b]
    assert len(blocks) == 2, "README.md: expected the design study and the closed loop after <!-- ci: python -->"
    return blocks


def run_block(block, cwd):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, "-c", block], cwd=cwd, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_readme_python_example_runs(tmp_path):
    stdout = run_block(readme_python_blocks()[0], tmp_path)
    assert (tmp_path / "legD_sweep.png").stat().st_size > 10000
    assert "legD" in stdout


def test_readme_closed_loop_example_meets_its_bound(tmp_path):
    # The block asserts its own bound (5 mm from t = 0.5 s); here its printed figures are read too.
    stdout = run_block(readme_python_blocks()[1], tmp_path)
    start, late = map(float, re.search(r"error (\S+) mm at t = 0, (\S+) mm from t = 0.5 s", stdout).groups())
    assert start == pytest.approx(30, abs=0.5)  # the perturbed start: 30 mm in x_C
    assert late < 5


def test_nan_and_out_of_bound_arguments_are_errors_not_nan_results():
    # Before: a NaN rate or u, or a coordinate of 1e308, returned NaN torques and rates.
    robot = wlx.model("excavator")
    s = robot.ik()["s"]
    with pytest.raises(wlx.Error, match=r"^rates\.x_C: is not a finite number"):
        robot.dependent_rates(s, {"x_C": float("nan")}, dependent=["y_C", "yaw"])
    # u and u_dot are named by their commanded coordinates (z_C, x_C, roll, pitch here).
    with pytest.raises(wlx.Error, match=r"^u\.x_C: is not a finite number"):
        robot.inverse_dynamics(s, [0.0, float("nan"), 0.0, 0.0])
    with pytest.raises(wlx.Error, match=r"^u_dot\.z_C: is not a finite number"):
        robot.inverse_dynamics(s, [0.0, 3.0, 0.0, 0.0], u_dot=[float("inf"), 0.0, 0.0, 0.0])
    # The CLI's bounds: a commanded speed 100 m/s or rad/s, its rate 1e4, a torque 1e9.
    with pytest.raises(wlx.Error, match=r"^u\.roll: .*bound"):
        robot.inverse_dynamics(s, [0.0, 0.0, 101.0, 0.0])
    with pytest.raises(wlx.Error, match=r"^u_dot\.pitch: is beyond the bound of 1e4 rad/s\^2"):
        robot.inverse_dynamics(s, [0.0, 0.0, 0.0, 0.0], u_dot=[0.0, 0.0, 0.0, 2e4])
    with pytest.raises(wlx.Error, match=r"^u\.x_C: .*bound"):
        robot.forward_dynamics(s, [0.0, -1e3, 0.0, 0.0], np.zeros(8))
    with pytest.raises(wlx.Error, match=r"^tau\.theta_r6: is beyond the bound of 1e9"):
        robot.forward_dynamics(s, np.zeros(4), [0, 0, 0, 0, 0, 0, 0, 2e9])
    with pytest.raises(wlx.Error, match=r"^tau\.psi_l2: is not a finite number"):
        robot.forward_dynamics(s, np.zeros(4), [float("nan"), 0, 0, 0, 0, 0, 0, 0])
    huge = np.array(s, dtype=float)
    huge[robot.coordinates.index("x_C")] = 1e308
    with pytest.raises(wlx.Error, match=r"^s\.x_C: "):
        robot.inverse_dynamics(huge, [0.0, 3.0, 0.0, 0.0])
    # The CLI's bounds on rates apply too (100 m/s).
    with pytest.raises(wlx.Error, match=r"^rates\.x_C: "):
        robot.dependent_rates(s, {"x_C": 1e6}, dependent=["y_C", "yaw"])


def test_the_wheeled_quadruped_commands_ten_speeds_with_sixteen_actuators():
    # Sizes come from the model: u has one entry per commanded speed, tau one per actuator (the
    # twelve joints and the four wheel drives, named by the URDF's continuous joints).
    robot = wlx.model("wheeled_quadruped")
    assert len(robot.commanded) == 10
    assert robot.actuators[:3] == ["haa_lf", "hfe_lf", "kfe_lf"]
    assert robot.actuators[12:] == ["wheel_joint_lf", "wheel_joint_rf", "wheel_joint_lh", "wheel_joint_rh"]
    s = robot.ik()["s"]
    u = np.zeros(10)
    u[robot.commanded.index("x_B")] = 0.5
    for leg in ("lf", "rf", "lh", "rh"):
        u[robot.commanded.index("x_" + leg)] = 0.5
    dyn = robot.inverse_dynamics(s, u)
    assert dyn["tau"].shape == (16,)
    # The torques produce Q* (least-norm solve of J_beta^T tau = Q*).
    residual = np.abs(dyn["J_beta"].T @ dyn["tau"] - dyn["Qstar"]).max()
    assert residual <= 1e-9 * np.abs(dyn["Qstar"]).max()
    # Rolling forward at a fixed shape moves the wheel drives only: 0.5 m/s on 0.1 m wheels.
    rates = dyn["J_beta"] @ u
    assert np.abs(rates[:12]).max() <= 1e-12
    assert np.allclose(rates[12:], 5.0, rtol=0, atol=1e-12)
    with pytest.raises(wlx.Error, match=r"^u: has 4 entries; the model commands 10 speeds"):
        robot.inverse_dynamics(s, [0.0, 3.0, 0.0, 0.0])


def test_contact_forces_carry_the_weight_and_weighting_3_keeps_the_contacts():
    # At rest on the nominal pose the ground carries the machine's weight (the sum of the bodies'
    # masses times g, from the model's own parameters, not from wlx's forces); weighting 3's smallest
    # margin (the smaller of a contact's normal force and friction margin) is at least weighting 1's.
    m = wlx.model("excavator")
    s = m.ik()["s"]
    u = np.zeros(len(m.commanded))
    masses = sum(v for k, v in m.params.items() if k.startswith("m_"))
    weight = masses * m.params["g"]
    smallest = {}
    for w in (1, 3):
        r = m.inverse_dynamics(s, u, weighting=w)
        f = r["contact_force"]
        assert f.shape == (len(m.contacts), 3)
        assert m.contacts == ["Fl", "Fr", "Wl", "Wr"]
        assert abs(f[:, 2].sum() - weight) <= 1e-9 * weight
        assert abs(f[:, 0].sum()) <= 1e-9 * weight and abs(f[:, 1].sum()) <= 1e-9 * weight
        smallest[w] = min(f[:, 2].min(), r["friction_margin"].min())
        assert r["margins"].shape == (3,) and r["margins"][2] > 0  # standing: no tipping
    assert smallest[3] >= smallest[1] - 1e-9 * weight


def test_simulate_columns_name_the_contacts():
    m = wlx.model("excavator")
    run = m.simulate({"id": "ID-3", "rates": {"z_C": -3.0}, "dependent": ["y_C", "yaw"], "duration": 0.05,
                      "weighting": 3})
    assert run["complete"]
    for c in m.contacts:
        assert (run["f_n_" + c] > 0).all()
    assert (run["momentum_residual"] <= 1e-9).all()
    assert (run["margin_tip"] > 0).all()


def test_another_interpreter_is_told_which_one_the_package_was_built_for(tmp_path):
    """The python3 first on a user's PATH may not be the interpreter the build used (a pyenv or a
    virtual environment's, without its NumPy; issue 43): import wlx there fails with an ImportError
    that names the build's interpreter (ctest runs this file with it: sys.executable) and this one,
    not only NumPy's or the compiled module's obscure error."""
    package_dir = str(Path(wlx.__file__).resolve().parents[1])
    venv = tmp_path / "venv"  # another interpreter, without the system's site-packages (so no NumPy)
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, capture_output=True)
    other = venv / "bin" / "python3"
    env = {**os.environ, "PYTHONPATH": package_dir}
    done = subprocess.run([str(other), "-c", "import wlx"], capture_output=True, text=True, env=env, check=False)
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: wlx: this package was built for the Python at "), done.stderr
    assert f"built for the Python at {sys.executable} (Python {sys.version_info[0]}.{sys.version_info[1]})" in last
    assert str(other) in last and "a virtual environment" in last
    assert "No module named 'numpy'" in last  # the original error is kept, after the explanation
    # The build's own interpreter, NumPy made unimportable: the original error, nothing claimed
    # about another interpreter.
    done = subprocess.run([sys.executable, "-c", "import sys; sys.modules['numpy'] = None; import wlx"],
                          capture_output=True, text=True, env=env, check=False)
    assert done.returncode != 0
    assert "built for" not in done.stderr and "numpy" in done.stderr.splitlines()[-1]
