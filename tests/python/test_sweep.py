"""Parameter sweeps (wlx.sweep, `wlx sweep SPEC.yaml`) on Dask: the same numbers as a plain loop
over m.simulate, rows for variants that cannot run, files that survive a kill, plots, and the
spec's mistakes as errors naming the field. Run by ctest as `python_sweep` (PYTHONPATH at the built
package, WLX_BINARY the built `wlx`). Small sweeps on 1-2 local workers: the speed figures are
tools/sweep_scaling.py's, not a test's."""

import csv
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import wlx
from wlx import _sweep

distributed = pytest.importorskip("distributed")  # tools/setup.sh installs python3-distributed

WLX = os.environ["WLX_BINARY"]
README = Path(__file__).resolve().parents[2] / "README.md"
# The README's design study: ID-1 shortened to 0.4 s (docs/excavator.md's run is 0.494 s).
ID1 = {"id": "ID-1", "rates": {"x_C": 3.0}, "dependent": ["y_C", "yaw"], "duration": 0.4, "weighting": 1}


@pytest.fixture(scope="module")
def robot():
    return wlx.model("excavator")


@pytest.fixture(scope="module")
def client():
    # One local cluster for the in-process tests, made as a sweep makes its own: two single-threaded
    # worker processes (the runs hold the GIL), every server on the loopback address.
    c, cluster = _sweep._client_for(None, None, 2)
    yield c
    c.close()
    cluster.close()


def listening_addresses(pids):
    """The local addresses of the TCP sockets in LISTEN state that these processes hold (from /proc:
    each socket's inode, found among the processes' open files, in /proc/net/tcp and tcp6)."""
    inodes = set()
    for pid in pids:
        try:
            fds = os.listdir(f"/proc/{pid}/fd")
        except OSError:
            continue
        for fd in fds:
            try:
                link = os.readlink(f"/proc/{pid}/fd/{fd}")
            except OSError:
                continue
            if link.startswith("socket:["):
                inodes.add(link[len("socket:["):-1])
    found = []
    for table in ("tcp", "tcp6"):
        with open(f"/proc/net/{table}") as f:
            for line in f.read().splitlines()[1:]:
                fields = line.split()
                if fields[3] == "0A" and fields[9] in inodes:  # 0A: LISTEN
                    found.append(fields[1].split(":")[0])
    return found


def descendants(pid):
    children = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry))
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += children.get(p, [])
    return out


def test_a_local_cluster_listens_on_the_loopback_address_only(client):
    addresses = listening_addresses(descendants(os.getpid()))
    # The scheduler, its HTTP routes, two workers and their nannies: each at least one socket.
    assert len(addresses) >= 5, addresses
    loopback = {"0100007F", "00000000000000000000000001000000"}  # 127.0.0.1 and ::1, as /proc/net writes them
    assert set(addresses) <= loopback, addresses


def peak_tau(run):
    return max(np.abs(run[c]).max() for c in run if c.startswith("tau_"))


def sweep_cli(args, cwd=None, **kwargs):
    return subprocess.run([WLX, "sweep", *args], capture_output=True, text=True, cwd=cwd, check=False, **kwargs)


def write_spec(path, spec):
    path.write_text(json.dumps(spec))  # JSON is YAML
    return path


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# ---------------------------------------------------------------- the numbers


def test_design_study_through_the_sweep_gives_the_plain_loops_numbers(robot, client, tmp_path):
    lengths = np.linspace(1.3, 2.2, 10)
    loop = [peak_tau(robot.simulate({**ID1, "params": {"legD": legD}})) for legD in lengths]
    table = wlx.sweep(robot, {"grid": {"legD": {"from": 1.3, "to": 2.2, "count": 10}}, "units": {"legD": "m"}}, [ID1],
                      ["peak_tau"], out=tmp_path / "study", client=client, progress=False)
    assert table["legD"] == list(lengths)
    assert table["peak_tau"] == loop  # the same C++ on the same inputs: equal to the last bit
    assert table["complete"] == [True] * 10 and table["stopped"] == [""] * 10
    assert table["t_end"] == [pytest.approx(0.4, abs=1e-12)] * 10
    # Written as read: the CSV's numbers round-trip exactly.
    rows = read_csv(tmp_path / "study" / "results.csv")
    assert [float(r["peak_tau"]) for r in rows] == loop
    # Each actuator's column: their largest is peak_tau.
    for k in range(10):
        assert max(table[f"peak_tau_{a}"][k] for a in robot.actuators) == table["peak_tau"][k]
    assert (tmp_path / "study" / "plots" / "peak_tau-vs-legD.png").stat().st_size > 10000


def test_the_readme_sweep_block_runs_on_a_local_cluster_and_prints_the_loops_numbers(robot, tmp_path):
    blocks = re.findall(r"<!-- ci: python -->\s*```python\n(.*?)```", README.read_text(), re.S)
    sweep_blocks = [b for b in blocks if "wlx.sweep(" in b]
    assert len(sweep_blocks) == 1
    done = subprocess.run([sys.executable, "-c", sweep_blocks[0]], cwd=tmp_path, capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "Agg"}, check=False)
    assert done.returncode == 0, done.stderr
    printed = [float(x) for x in re.findall(r"peak torque (\S+) N m", done.stdout)]
    loop = [peak_tau(robot.simulate({**ID1, "params": {"legD": legD}})) for legD in np.linspace(1.3, 2.2, 10)]
    assert printed == [float(f"{v:.0f}") for v in loop]  # the plain loop's lines, as it prints them
    assert (tmp_path / "legD_study" / "plots" / "peak_tau-vs-legD.png").stat().st_size > 10000


def test_every_metric_against_its_definition(robot, client):
    run = {**ID1, "duration": 0.2}
    table = wlx.sweep(robot, {"list": [{"legD": 1.6}]}, [run], list(_sweep.METRICS), client=client, progress=False)
    r = robot.simulate(run, params={"legD": 1.6})
    taus = {a: r[f"tau_{a}"] for a in robot.actuators}
    rms = {a: float(np.sqrt(np.mean(x ** 2))) for a, x in taus.items()}
    # The run's summary sums the squares in time order, NumPy pairwise: rounding apart by at most
    # n eps relative over the n = 201 samples (2.2e-14).
    assert table["rms_tau"][0] == pytest.approx(max(rms.values()), rel=3e-14, abs=0)
    assert all(table[f"rms_tau_{a}"][0] == pytest.approx(rms[a], rel=3e-14, abs=0) for a in robot.actuators)
    assert table["peak_tau"] == [max(float(np.abs(x).max()) for x in taus.values())]
    assert table["peak_cond_J_beta"] == [r["cond_J_beta"].max()]
    assert table["min_clearance"] == [r["clearance"].min()]
    # Will it lift off, slip or tip: the CSV's columns, over the supporting contacts (those with a
    # friction margin); the same doubles, so equal to the last bit.
    supporting = [c for c in robot.contacts if f"friction_margin_{c}" in r]
    assert supporting
    assert table["min_normal_force"] == [min(r[f"f_n_{c}"].min() for c in supporting)]
    assert table["min_friction_margin"] == [min(r[f"friction_margin_{c}"].min() for c in supporting)]
    assert table["min_tip_margin"] == [r["margin_tip"].min()]
    assert table["reach_failure"] == [0]
    # Energy: each actuator's positive work, rates by central differences of its angle.
    work = 0.0
    for a in robot.actuators:
        p = np.maximum(taus[a] * np.gradient(r[a], r["t"]), 0.0)
        work += np.trapz(p, r["t"])
    assert table["energy"][0] == pytest.approx(work, rel=1e-12)
    assert table["energy"][0] > 1e3  # the knees lift the machine: work is done


def test_energy_rates_by_differences_agree_with_a_torque_driven_runs_power(robot):
    # The metric takes the actuators' rates as central differences of their sampled angles. A run
    # driven by torques writes the exact power, sum of tau q': inside the run the two agree to
    # 1e-4 of the peak power at the 1 ms step (second order in the step; the ends are one-sided).
    run = robot.simulate({"rates": {"x_C": 3.0}, "duration": 0.3, "dt": 0.001, "integrator": "dopri5",
                          "torques": {"run": "ID-1"}})
    estimated = sum(run[f"tau_{a}"] * np.gradient(run[a], run["t"]) for a in robot.actuators)
    assert np.abs(estimated - run["power"])[1:-1].max() < 1e-4 * np.abs(run["power"]).max()
    assert _sweep._energy(run, robot.actuators) > 0


# ---------------------------------------------------------------- rows that say why


def test_an_infeasible_variant_is_a_row_with_its_reason(robot, client, tmp_path):
    # legD = -1: a bad parameter; legD = 0.5: the feet out of reach at t = 0; 1.5: the nominal.
    table = wlx.sweep(robot, {"list": [{"legD": 1.5}, {"legD": -1.0}, {"legD": 0.5}]}, [{**ID1, "duration": 0.1}],
                      ["peak_tau", "reach_failure", "energy"], out=tmp_path / "s", client=client, progress=False)
    assert table["variant"] == [0, 1, 2]
    assert table["complete"] == [True, False, False]
    assert table["stopped"][0] == ""
    assert table["stopped"][1].startswith("params.legD: a length must be positive")
    assert "out of reach" in table["stopped"][2]
    assert table["reach_failure"] == [0, 0, 1]
    assert table["peak_tau"][1:] == [None, None] and table["energy"][1:] == [None, None]
    text = (tmp_path / "s" / "results.csv").read_text()
    assert "nan" not in text.lower()
    rows = read_csv(tmp_path / "s" / "results.csv")
    assert rows[1]["peak_tau"] == "" and rows[2]["stopped"] == table["stopped"][2]
    assert json.loads((tmp_path / "s" / "sweep.json").read_text())["complete_rows"] == 1


def test_names_with_commas_and_quotes_are_quoted_for_csv(robot, client, tmp_path):
    label = 'a, "quoted" run'
    table = wlx.sweep(robot, {"list": [{"legD": 1.5}]}, [{**ID1, "id": label, "duration": 0.05}], ["peak_tau"],
                      out=tmp_path / "q", client=client, progress=False)
    assert read_csv(tmp_path / "q" / "results.csv")[0]["run"] == label == table["run"][0]


# ---------------------------------------------------------------- samples, sensitivities, plots


def test_random_samples_are_seeded_and_the_sensitivities_find_the_parameter_that_matters(robot, client, tmp_path):
    parameters = {"random": {"samples": 24, "seed": 7, "distributions": {
        "m_M1": {"uniform": [4000.0, 7000.0]}, "cabin_height": {"normal": [0.5, 0.05]}}}}
    run = {**ID1, "duration": 0.05}
    a = wlx.sweep(robot, parameters, [run], ["peak_tau"], out=tmp_path / "r", client=client, progress=False)
    b = wlx.sweep(robot, parameters, [run], ["peak_tau"], client=client, progress=False)
    assert a == b
    rng = np.random.Generator(np.random.PCG64(7))  # the documented draw: parameter after parameter
    assert a["m_M1"] == list(rng.uniform(4000.0, 7000.0, 24)) and a["cabin_height"] == list(rng.normal(0.5, 0.05, 24))
    rows = {r["parameter"]: float(r["standardized_coefficient"]) for r in read_csv(tmp_path / "r" / "sensitivity.csv")}
    # The cabin's mass moves the peak torque almost linearly; the cabin box's height (drawing and
    # clearance only) not at all: its coefficient is the fit's spurious correlation, small.
    assert rows["m_M1"] > 0.99
    assert abs(rows["cabin_height"]) < 0.02
    assert (tmp_path / "r" / "plots" / "peak_tau-ID-1-sensitivity.png").stat().st_size > 5000


def test_standardized_coefficients_of_an_exactly_linear_metric():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(50, 3)) * [1.0, 10.0, 0.1]
    y = 2.0 * x[:, 0] - 0.5 * x[:, 1]  # the third has no effect
    s = _sweep._sensitivities(x, y)
    expected = np.array([2.0 * x[:, 0].std(), -0.5 * x[:, 1].std(), 0.0]) / y.std()
    assert np.allclose(s, expected, atol=1e-12)


def test_two_parameters_on_a_grid_give_a_heat_map(robot, client, tmp_path):
    run = {**ID1, "duration": 0.05}
    table = wlx.sweep(robot, {"grid": {"m_M1": [4000.0, 5400.0, 7000.0], "legD": [1.4, 1.6]}}, [run], ["peak_tau"],
                      out=tmp_path / "h", client=client, progress=False)
    # The grid's order: the last parameter varies fastest.
    assert table["m_M1"] == [4000.0, 4000.0, 5400.0, 5400.0, 7000.0, 7000.0] and table["legD"] == [1.4, 1.6] * 3
    assert table["peak_tau"][5] == peak_tau(robot.simulate(run, params={"m_M1": 7000.0, "legD": 1.6}))
    png = tmp_path / "h" / "plots" / "peak_tau-ID-1-heatmap.png"
    import matplotlib.image

    image = matplotlib.image.imread(png)
    # Six cells of a colour map over a strongly varying metric: many distinct colours.
    assert len(np.unique(image[..., :3].reshape(-1, 3), axis=0)) > 50


# ---------------------------------------------------------------- the command line, kill and resume


# 24 variants of a 1 s run (about 10 ms each), one per task on one worker: a kill lands mid-way.
LONG = {"parameters": {"grid": {"legD": {"from": 1.3, "to": 2.2, "count": 24}}, "units": {"legD": "m"}},
        "runs": [{**ID1, "duration": 1.0}], "metrics": ["peak_tau", "energy"]}


def long_spec(tmp_path, out="out"):
    return write_spec(tmp_path / "spec.yaml", {"model": "excavator", **LONG, "out": out})


def test_a_killed_sweep_resumes_and_ends_with_the_uninterrupted_table(robot, client, tmp_path):
    # The uninterrupted table: the same engine in this process, on the shared cluster.
    reference = tmp_path / "reference"
    wlx.sweep(robot, LONG["parameters"], LONG["runs"], LONG["metrics"], out=reference, client=client, progress=False)

    work = tmp_path / "killed"
    work.mkdir()
    spec = long_spec(work)
    batches = work / "out" / "batches"
    # Its own process group: the sweep and its cluster's worker processes, killed together.
    p = subprocess.Popen([WLX, "sweep", str(spec), "--workers", "1", "--batch-size", "1"], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and p.poll() is None:
        if batches.is_dir() and len(list(batches.glob("rows-*.csv"))) >= 2:
            os.killpg(p.pid, signal.SIGKILL)
            break
        time.sleep(0.002)
    p.wait()
    assert p.returncode == -signal.SIGKILL, "the sweep ended before the test could kill it"
    written = {f.name: (f.stat().st_ino, f.stat().st_mtime_ns) for f in batches.glob("rows-*.csv")}
    assert 2 <= len(written) < 24
    assert not (work / "out" / "results.csv").exists()

    # Resumed with larger batches: they never span a variant already written (a file is one range).
    resumed = sweep_cli([str(spec), "--workers", "1", "--batch-size", "5"])
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming: {len(written)} of 24 variants already written" in resumed.stderr
    for name, stamp in written.items():  # skipped: not run or written again
        f = batches / name
        assert (f.stat().st_ino, f.stat().st_mtime_ns) == stamp
    assert not list(batches.glob(".*.tmp"))
    assert (work / "out" / "results.csv").read_bytes() == (reference / "results.csv").read_bytes()


def test_batches_never_span_a_written_variant():
    assert _sweep._batches([0, 1, 2, 5, 6, 9], 2) == [[0, 1], [2], [5, 6], [9]]
    assert _sweep._batches(list(range(7)), 3) == [[0, 1, 2], [3, 4, 5], [6]]
    assert _sweep._batches([], 4) == []


def test_sigterm_stops_with_143_and_the_written_batches_stay(tmp_path):
    spec = long_spec(tmp_path)
    batches = tmp_path / "out" / "batches"
    p = subprocess.Popen([WLX, "sweep", str(spec), "--workers", "1", "--batch-size", "1"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and p.poll() is None:
        if batches.is_dir() and list(batches.glob("rows-*.csv")):
            p.send_signal(signal.SIGTERM)  # wlx became python3 (exec): its pid is the sweep's
            break
        time.sleep(0.002)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143, err
    assert "interrupted: the batches written are complete" in err and "Traceback" not in err
    for f in batches.glob("rows-*.csv"):
        assert len(read_csv(f)) == 1  # whole files only


def test_a_restart_with_another_spec_in_the_same_folder_is_an_error(robot, client, tmp_path):
    wlx.sweep(robot, {"list": [{"legD": 1.5}]}, [{**ID1, "duration": 0.05}], ["peak_tau"], out=tmp_path / "o", client=client,
              progress=False)
    spec = write_spec(tmp_path / "a.yaml", {"parameters": {"list": [{"legD": 1.6}]}, "runs": [{**ID1, "duration": 0.05}],
                                            "metrics": ["peak_tau"], "out": "o"})
    done = sweep_cli([str(spec), "--workers", "1"])
    assert done.returncode == 2
    assert "out: " in done.stderr and "holds the rows of another sweep" in done.stderr


def test_batches_are_sized_as_documented(robot, client, tmp_path):
    # Auto: a variant costs milliseconds, so the balance rule decides: ceil(10 / (4 batches x 2
    # workers)) = 2 variants a batch, 5 files. batch_size 3: ceil(10 / 3) = 4 files.
    parameters, runs = {"grid": {"legD": {"from": 1.3, "to": 2.2, "count": 10}}}, [{**ID1, "duration": 0.05}]
    wlx.sweep(robot, parameters, runs, ["peak_tau"], out=tmp_path / "auto", client=client, progress=False)
    assert sorted(f.name for f in (tmp_path / "auto" / "batches").glob("rows-*.csv")) == \
        [f"rows-{k:07d}-{k + 1:07d}.csv" for k in (0, 2, 4, 6, 8)]
    wlx.sweep(robot, parameters, runs, ["peak_tau"], out=tmp_path / "three", client=client, batch_size=3, progress=False)
    assert sorted(f.name for f in (tmp_path / "three" / "batches").glob("rows-*.csv")) == \
        [f"rows-{a:07d}-{b:07d}.csv" for a, b in ((0, 2), (3, 5), (6, 8), (9, 9))]
    assert (tmp_path / "three" / "results.csv").read_bytes() == (tmp_path / "auto" / "results.csv").read_bytes()


def test_a_running_scheduler_takes_the_same_sweep(robot, tmp_path):
    # A cluster started apart (here in this process, its worker a thread): --scheduler on the
    # command line, scheduler= and client= in Python give the same table as the local cluster.
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                                       protocol="tcp", host="127.0.0.1", scheduler_port=0)
    try:
        spec = write_spec(tmp_path / "s.yaml", {"parameters": {"list": [{"legD": 1.4}, {"legD": 1.7}]},
                                                "runs": ["NH-1"], "metrics": ["peak_cond_J_beta"], "out": "remote"})
        done = sweep_cli([str(spec), "--scheduler", cluster.scheduler_address])
        assert done.returncode == 0, done.stderr
        by_address = wlx.sweep(robot, {"list": [{"legD": 1.4}, {"legD": 1.7}]}, ["NH-1"], ["peak_cond_J_beta"],
                               scheduler=cluster.scheduler_address, progress=False)
        with distributed.Client(cluster) as c:
            by_client = wlx.sweep(robot, {"list": [{"legD": 1.4}, {"legD": 1.7}]}, ["NH-1"], ["peak_cond_J_beta"],
                                  client=c, progress=False)
    finally:
        cluster.close()
    expected = [robot.simulate("NH-1", params={"legD": v})["cond_J_beta"].max() for v in (1.4, 1.7)]
    assert by_address["peak_cond_J_beta"] == by_client["peak_cond_J_beta"] == expected
    assert [float(r["peak_cond_J_beta"]) for r in read_csv(tmp_path / "remote" / "results.csv")] == expected


def test_a_run_from_a_file_beside_the_spec(robot, tmp_path):
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "short.json").write_text(json.dumps({**ID1, "duration": 0.05}))
    spec = write_spec(tmp_path / "s.yaml", {"parameters": {"list": [{"legD": 1.6}, {"legD": 1.7}]}, "runs": ["runs/short.json"],
                                            "metrics": ["peak_tau"], "batch_size": 1})
    done = sweep_cli([str(spec), "--workers", "1"], cwd="/")
    assert done.returncode == 0, done.stderr
    assert "2 rows (0 did not complete)" in done.stdout
    assert re.search(r"2/2 variants [\d.]+/s, \d+ s left", done.stderr)  # the progress bar's last line
    rows = read_csv(tmp_path / "sweep" / "results.csv")  # the default folder: sweep/ beside the spec
    assert [r["run"] for r in rows] == ["short", "short"]
    assert float(rows[1]["peak_tau"]) == peak_tau(robot.simulate({**ID1, "duration": 0.05}, params={"legD": 1.7}))
    assert len(list((tmp_path / "sweep" / "batches").glob("rows-*.csv"))) == 2  # the spec's batch_size


# ---------------------------------------------------------------- mistakes


BAD_SPECS = {
    "unknown parameter": ({"grid": {"legd": [1.5]}}, r"parameters\.grid\.legd: not a parameter of excavator; did you mean 'legD'\?"),
    "bad distribution": ({"random": {"samples": 3, "seed": 1, "distributions": {"legD": {"gauss": [1.5, 0.1]}}}},
                         r"parameters\.random\.distributions\.legD\.gauss: unknown distribution"),
    "negative count": ({"grid": {"legD": {"from": 1.3, "to": 2.2, "count": -3}}},
                       r"parameters\.grid\.legD\.count: must be between 1 and 1000000, got -3"),
    "zero samples": ({"random": {"samples": 0, "seed": 1, "distributions": {"legD": {"uniform": [1.3, 2.2]}}}},
                     r"parameters\.random\.samples: must be between 1 and 1000000, got 0"),
    "negative standard deviation": ({"random": {"samples": 3, "seed": 1, "distributions": {"legD": {"normal": [1.5, -0.1]}}}},
                                    r"parameters\.random\.distributions\.legD\.normal: the standard deviation must be positive"),
    "too many variants": ({"grid": {"legD": {"from": 1.3, "to": 2.2, "count": 1001}, "thighD": {"from": 1.8, "to": 2.2, "count": 1000}}},
                          r"parameters\.grid: 1001000 variants .* more than the bound of 1000000"),
    "a unit that is not the parameter's": ({"grid": {"legD": [1.5]}, "units": {"legD": "kg"}},
                                          r"parameters\.units\.legD: excavator's legD is in 'm', not 'kg'"),
    "a grid value given twice": ({"grid": {"legD": [1.5, 1.6, 1.5]}}, r"parameters\.grid\.legD: a value given twice"),
    "two modes": ({"grid": {"legD": [1.5]}, "list": [{"legD": 1.5}]}, r"parameters: give exactly one of grid, list or random"),
    "a value that is not a number": ({"list": [{"legD": "long"}]}, r"parameters\.list\[0\]\.legD: expected a number"),
    "a variant without the first's parameters": ({"list": [{"legD": 1.5}, {"thighD": 2.0}]},
                                                 r"parameters\.list\[1\]: every variant sets the same parameters as the first"),
}


@pytest.mark.parametrize("case", list(BAD_SPECS))
def test_a_bad_parameters_section_is_an_error_naming_the_field(robot, case, tmp_path):
    parameters, message = BAD_SPECS[case]
    with pytest.raises(wlx.Error, match=message):
        wlx.sweep(robot, parameters, [ID1], ["peak_tau"], progress=False)
    spec = write_spec(tmp_path / "s.yaml", {"parameters": parameters, "runs": [ID1], "metrics": ["peak_tau"]})
    done = sweep_cli([str(spec)])
    assert done.returncode == 2
    assert re.search(message, done.stderr) and "Traceback" not in done.stderr
    assert not (tmp_path / "sweep").exists()  # nothing written for a spec that cannot run


@pytest.mark.parametrize("spec, message", [
    ({"parameters": {"list": [{"legD": 1.5}]}, "runs": ["NH1"], "metrics": ["peak_tau"]},
     r"runs\[0\]: 'NH1' is neither a scenario id of excavator nor a file; did you mean 'NH-1'\?"),
    ({"parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1", "ID-1"], "metrics": ["peak_tau"]},
     r"runs\[1\]: a second run named 'ID-1'"),
    ({"parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1"], "metrics": ["peak_torque"]},
     r"metrics\[0\]: unknown metric 'peak_torque'; did you mean 'peak_tau'\?"),
    ({"parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1"], "metrics": ["peak_tau"], "batchsize": 3},
     r"batchsize: unknown key; did you mean 'batch_size'\?"),
    ({"parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1"], "metrics": ["peak_tau"], "batch_size": 0},
     r"batch_size: must be between 1 and 10000, got 0"),
    ({"model": "excavater", "parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1"], "metrics": ["peak_tau"]},
     r"model: 'excavater' is neither a built-in model .* nor a file; did you mean 'excavator'\?"),
    ({"parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1"]}, r"metrics: missing"),
])
def test_a_bad_spec_exits_2_naming_the_field(spec, message, tmp_path):
    done = sweep_cli([str(write_spec(tmp_path / "s.yaml", spec))])
    assert done.returncode == 2
    assert re.search(message, done.stderr), done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("args, message", [
    (["--workers", "0"], r"workers: must be between 1 and 256, got 0"),
    (["--batch-size", "-2"], r"batch_size: must be between 1 and 10000, got -2"),
    (["--scheduler", "localhost 8786"], r"scheduler: expected an address such as tcp://HOST:8786"),
    (["--workers", "two"], r"--workers: 'two' is not a valid value|Could not convert"),
])
def test_bad_options_exit_2(args, message, tmp_path):
    spec = write_spec(tmp_path / "s.yaml", {"parameters": {"list": [{"legD": 1.5}]}, "runs": ["ID-1"], "metrics": ["peak_tau"]})
    done = sweep_cli([str(spec), *args])
    assert done.returncode == 2
    assert re.search(message, done.stderr), done.stderr


def test_spec_files_are_read_strictly(tmp_path):
    twice = tmp_path / "twice.yaml"
    twice.write_text("parameters: {list: [{legD: 1.5}]}\nruns: [ID-1]\nmetrics: [peak_tau]\nruns: [ID-2]\n")
    done = sweep_cli([str(twice)])
    assert done.returncode == 2 and re.search(r"twice\.yaml:4: runs: given twice in one mapping", done.stderr), done.stderr
    done = sweep_cli([str(tmp_path)])
    assert done.returncode == 2 and "not a regular file" in done.stderr
    big = tmp_path / "big.yaml"
    big.write_text("#" * (1 << 20) + "\n")
    done = sweep_cli([str(big)])
    assert done.returncode == 2 and "larger than 1048576 bytes" in done.stderr
    # The model's options are the spec's: given to wlx they are an error, not ignored.
    done = subprocess.run([WLX, "--model", "walker", "sweep", str(twice)], capture_output=True, text=True, check=False)
    assert done.returncode == 2 and "--model, --model-file, --scenarios and --params do not apply" in done.stderr
    done = sweep_cli([])
    assert done.returncode == 2 and "SPEC: missing" in done.stderr


# The spec reader as a fuzz target (no libFuzzer for Python here): seeded random mutations of
# valid specs, each read and planned as `wlx sweep` would before any run. Every text is either a
# plan or a wlx.Error naming its field; any other exception, or a message of more than a few
# lines, fails. 3000 mutants in a few seconds; the seed fixes them, so a failure replays.
SPEC_SEEDS = [
    "model: excavator\nparameters: {grid: {legD: [1.4, 1.6], thighD: {from: 1.8, to: 2.2, count: 3}}}\n"
    "runs: [NH-1, {id: T, rates: {x_C: 0.2}, dependent: [y_C, yaw], duration: 0.1}]\nmetrics: [peak_tau, min_clearance]\n",
    "parameters:\n  list:\n    - {legD: 1.5e0, cxd: 3}\n    - {legD: 15e-1, cxd: 3.1}\nruns: [ID-1]\nmetrics: [peak_cond_J_beta]\nbatch_size: 4\n",
    "parameters: {random: {samples: 5, seed: 7, distributions: {legD: {uniform: [1.4, 1.6]}, m_M1: {normal: [5400, 270]}}}}\n"
    "runs: [NH-2]\nmetrics: [peak_tau]\nout: here\n",
]
MUTATIONS = [":", "-", "[", "]", "{", "}", ",", "#", "&a", "*a", "!!int ", "!!float ", "'", '"', "\n", "  ", "1e308", "-0",
             ".nan", ".inf", "~", "null", "?", "|", ">", "%", "@", "\t", "\x00", "\u2028", "1" * 40, "legD", "runs"]


def test_the_spec_reader_takes_any_text_to_a_plan_or_an_error_naming_its_field(robot, tmp_path):
    import random

    rng = random.Random(20261205)
    path = tmp_path / "spec.yaml"
    outcomes = {"plan": 0, "error": 0}
    for k in range(3000):
        text = rng.choice(SPEC_SEEDS)
        for _ in range(rng.randint(1, 4)):
            at = rng.randrange(len(text) + 1)
            cut = rng.choice([0, 0, 1, rng.randint(1, 12)])
            text = text[:at] + (rng.choice(MUTATIONS) if rng.random() < 0.8 else "") + text[at + cut:]
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        try:
            spec = _sweep.read_spec(str(path))
            _sweep._plan(robot, spec["parameters"], spec["runs"], spec["metrics"], str(tmp_path))
            outcomes["plan"] += 1
        except wlx.Error as e:
            message = str(e)
            assert message and message.count("\n") <= 2 and len(message) <= 2000, (k, text, message)
            outcomes["error"] += 1
        except Exception as e:  # noqa: BLE001 - the point: nothing else may escape
            raise AssertionError(f"mutant {k}: {type(e).__name__}: {e}\n--- spec ---\n{text}") from e
    assert outcomes["plan"] > 100 and outcomes["error"] > 1000, outcomes  # both paths taken, often


def test_a_worker_that_cannot_load_the_model_stops_the_sweep_resumably(client, tmp_path):
    # As when a model file is not at the same path on the workers: the task fails, not a variant.
    # The sweep stops with the reason (exit 2 on the command line); nothing is written as a row.
    elsewhere = wlx.model("excavator")
    elsewhere._path = str(tmp_path / "not-on-the-workers.yaml")
    with pytest.raises(wlx.Error, match=r"^sweep: a task failed \(Error: load: .*cannot open it .*run the same sweep again to resume"):
        wlx.sweep(elsewhere, {"list": [{"legD": 1.5}]}, [{**ID1, "duration": 0.05}], ["peak_tau"], out=tmp_path / "o",
                  client=client, batch_size=1, progress=False)
    assert not list((tmp_path / "o" / "batches").iterdir())


def test_an_angle_given_in_degrees_is_swept_in_radians():
    # The quadruped's sensor mount angles are its parameters in rad.
    quadruped = wlx.model("wheeled_quadruped")
    assert quadruped.param_units["imu_joint_roll"] == "rad"
    plan = _sweep._plan(quadruped, {"grid": {"imu_joint_roll": [0.0, 5.0, 90.0]}, "units": {"imu_joint_roll": "deg"}},
                        [quadruped.scenarios[0]], ["peak_tau"])
    assert plan.values[:, 0].tolist() == [0.0, np.pi / 36, np.pi / 2]
    with pytest.raises(wlx.Error, match=r"^parameters\.units\.imu_joint_roll: wheeled_quadruped's imu_joint_roll is in 'rad', not 'grad' \(or 'deg'\)"):
        _sweep._plan(quadruped, {"grid": {"imu_joint_roll": [5.0]}, "units": {"imu_joint_roll": "grad"}}, ["NH-Q1"], ["peak_tau"])


def test_python_m_wlx_needs_the_sweep_subcommand():
    done = subprocess.run([sys.executable, "-m", "wlx"], capture_output=True, text=True, check=False)
    assert done.returncode == 2 and "usage: python3 -m wlx sweep SPEC" in done.stderr


def test_python_arguments_are_checked(robot):
    with pytest.raises(wlx.Error, match=r"^model: expected a wlx\.Model"):
        wlx.sweep("excavator", {"list": [{"legD": 1.5}]}, ["ID-1"])
    with pytest.raises(wlx.Error, match=r"^scheduler: give client or scheduler, not both"):
        wlx.sweep(robot, {"list": [{"legD": 1.5}]}, ["ID-1"], client=object(), scheduler="tcp://x:1")
    with pytest.raises(wlx.Error, match=r"^workers: sizes the local cluster"):
        wlx.sweep(robot, {"list": [{"legD": 1.5}]}, ["ID-1"], client=object(), workers=2)
    with pytest.raises(wlx.Error, match=r"^runs\[0\]\.id: must be a string"):
        wlx.sweep(robot, {"list": [{"legD": 1.5}]}, [{"id": 3}])


# ---------------------------------------------------------------- hostile input: batch files, spec files, stdout, plots


# 4 variants x 2 runs in batches of 2 variants: rows-0000000-0000001.csv and rows-0000002-0000003.csv.
SMALL = {"parameters": {"grid": {"legD": [1.4, 1.5, 1.6, 1.7]}},
         "runs": [{**ID1, "duration": 0.05}, {**ID1, "id": "ID-1b", "duration": 0.1}],
         "metrics": ["peak_tau", "reach_failure"]}
FIRST, SECOND = "rows-0000000-0000001.csv", "rows-0000002-0000003.csv"


@pytest.fixture(scope="module")
def small_reference(robot, client, tmp_path_factory):
    """The uninterrupted sweep's folder and table."""
    folder = tmp_path_factory.mktemp("small") / "reference"
    table = wlx.sweep(robot, SMALL["parameters"], SMALL["runs"], SMALL["metrics"], out=folder, client=client, batch_size=2,
                      progress=False)
    assert sorted(f.name for f in (folder / "batches").iterdir()) == [FIRST, SECOND]
    return folder, table


def copy_of(reference, folder):
    shutil.copytree(reference, folder)
    (folder / "results.csv").unlink()  # the resumed sweep writes its own
    return folder


def edit_cell(path, row, column, text):
    rows = list(csv.reader(path.open(newline="")))
    rows[row][rows[0].index(column)] = text
    with path.open("w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def duplicate_last_row(path):
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines) + lines[-1])


# (batch file, how it is spoilt, what the message says)
SPOILT_BATCHES = {
    "a NaN edited in": (SECOND, lambda f: edit_cell(f, 2, "peak_tau", "nan"),
                        r"row 2, peak_tau: 'nan' is not a finite number as the sweep writes one"),
    "an infinite t_end": (FIRST, lambda f: edit_cell(f, 1, "t_end", "inf"),
                          r"row 1, t_end: 'inf' is not a finite number as the sweep writes one"),
    "emptied": (FIRST, lambda f: f.write_bytes(b""), r"empty"),
    "a row duplicated": (SECOND, duplicate_last_row, r"more than its 4 rows \(2 variants x 2 runs\)"),
    "only its header": (FIRST, lambda f: f.write_text(f.read_text().splitlines(keepends=True)[0]),
                        r"0 rows, not its 4 \(2 variants x 2 runs\)"),
    "a row of another variant": (SECOND, lambda f: edit_cell(f, 3, "variant", "2"), r"row 3, variant: '2' where this sweep has '3'"),
    "another variant's value": (FIRST, lambda f: edit_cell(f, 1, "legD", "1.5"), r"row 1, legD: '1.5' where this sweep has '1.4'"),
    "grown to a gigabyte": (FIRST, lambda f: os.truncate(f, 1 << 30), r"larger than \d+ bytes"),
}


@pytest.mark.parametrize("case", list(SPOILT_BATCHES))
def test_a_resume_runs_a_spoilt_batch_again_and_ends_with_the_uninterrupted_table(robot, client, small_reference, case,
                                                                                  tmp_path, capsys):
    reference, reference_table = small_reference
    name, spoil, reason = SPOILT_BATCHES[case]
    work = copy_of(reference, tmp_path / "work")
    spoil(work / "batches" / name)
    table = wlx.sweep(robot, SMALL["parameters"], SMALL["runs"], SMALL["metrics"], out=work, client=client, batch_size=2,
                      progress=False)
    err = capsys.readouterr().err
    first, last = (0, 1) if name == FIRST else (2, 3)
    assert re.search("^" + re.escape(f"sweep: {work / 'batches' / name}: ") + reason +
                     re.escape(f"; its variants {first}..{last} run again") + "$", err, re.M), err
    assert (work / "results.csv").read_bytes() == (reference / "results.csv").read_bytes()
    assert (work / "batches" / name).read_bytes() == (reference / "batches" / name).read_bytes()
    assert table == reference_table


def test_the_command_line_runs_a_batch_with_a_nan_again(small_reference, tmp_path):
    reference, _ = small_reference
    copy_of(reference, tmp_path / "out")
    edit_cell(tmp_path / "out" / "batches" / SECOND, 4, "peak_tau_psi_l2", "NaN")
    spec = write_spec(tmp_path / "s.yaml", {"model": "excavator", **SMALL, "out": "out"})
    done = sweep_cli([str(spec), "--workers", "1", "--batch-size", "2"], timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"{tmp_path / 'out' / 'batches' / SECOND}: row 4, peak_tau_psi_l2: 'NaN' is not a finite number" in done.stderr
    assert "resuming: 2 of 4 variants already written" in done.stderr
    assert (tmp_path / "out" / "results.csv").read_bytes() == (reference / "results.csv").read_bytes()


def fifo(path):
    os.mkfifo(path)


def dev_zero(path):
    path.symlink_to("/dev/zero")


@pytest.mark.parametrize("target", [f"batches/{FIRST}", "spec.json"])
@pytest.mark.parametrize("make, kind", [(fifo, "a FIFO"), (dev_zero, "a character device")])
def test_a_batch_or_identity_file_that_is_not_a_regular_file_is_refused_at_once(robot, small_reference, target, make, kind, tmp_path):
    reference, _ = small_reference
    copy_of(reference, tmp_path / "out")
    path = tmp_path / "out" / target
    path.unlink()
    make(path)
    spec = write_spec(tmp_path / "s.yaml", {"model": "excavator", **SMALL, "out": "out"})
    started = time.monotonic()
    done = sweep_cli([str(spec), "--workers", "1", "--batch-size", "2"], timeout=120)  # a hang or a read without end: the timeout
    assert done.returncode == 2, done.stderr
    assert f"out: {path}: not a regular file ({kind})" in done.stderr and "Traceback" not in done.stderr
    assert time.monotonic() - started < 60  # refused before any cluster starts: seconds
    assert path.is_symlink() or path.is_fifo()  # not removed: the sweep did not put it there
    with pytest.raises(wlx.Error, match=re.escape(f"out: {path}: not a regular file ({kind})")):
        wlx.sweep(robot, SMALL["parameters"], SMALL["runs"], SMALL["metrics"], out=tmp_path / "out", batch_size=2, progress=False)


@pytest.mark.parametrize("make, kind", [(fifo, "a FIFO"), (dev_zero, "a character device")])
def test_a_spec_that_is_a_fifo_or_a_device_is_refused_at_once(make, kind, tmp_path):
    spec = tmp_path / "s.yaml"
    make(spec)
    done = sweep_cli([str(spec)], timeout=60)
    assert done.returncode == 2
    assert done.stderr == f"wlx sweep: error: {spec}: not a regular file ({kind})\n"


def test_aliases_in_a_spec_are_refused_quickly_with_a_short_message(tmp_path):
    # "Billion laughs": 9 nested lists of 9 aliases each, 9^9 strings to whatever walks the result.
    lines = ["parameters: {list: [{legD: 1.5}]}", "metrics: [peak_tau]", "runs:", "  - - &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    lines += [f"    - &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]" for k in range(1, 9)]
    spec = tmp_path / "laughs.yaml"
    spec.write_text("\n".join(lines) + "\n")
    assert spec.stat().st_size < 1024
    started = time.monotonic()
    done = sweep_cli([str(spec)], timeout=60)
    assert done.returncode == 2
    assert done.stderr == f"wlx sweep: error: {spec}:5: an alias (*name) is not allowed in a sweep spec: write the value out\n"
    assert time.monotonic() - started < 30
    # Nested without end: refused at its depth, not a Python RecursionError.
    deep = tmp_path / "deep.yaml"
    deep.write_text("runs: " + "[" * 5000 + "\n")
    done = sweep_cli([str(deep)], timeout=60)
    assert done.returncode == 2 and re.fullmatch(r"wlx sweep: error: .*deep\.yaml:1: nested more than 100 deep\n", done.stderr), done.stderr


def test_error_messages_quote_and_cut_the_inputs_text(robot):
    # From Python a structure may share its parts (as aliases would): 9^9 leaves, not written out.
    laughs = ["lol"] * 9
    for _ in range(8):
        laughs = [laughs] * 9
    started = time.monotonic()
    with pytest.raises(wlx.Error) as e:
        wlx.sweep(robot, {"list": [{"legD": 1.5}]}, [laughs], progress=False)
    assert time.monotonic() - started < 5
    assert str(e.value).startswith("runs[0]: expected a scenario id, a file or a scenario mapping, got [[[")
    assert len(str(e.value)) < 150
    # A name with a terminal's escape sequence and a megabyte of name: quoted, escaped and cut.
    with pytest.raises(wlx.Error) as e:
        wlx.sweep(robot, {"grid": {"\x1b[2Jleg": [1.5]}}, ["ID-1"], progress=False)
    assert str(e.value).startswith(r"parameters.grid.'\x1b[2Jleg': not a parameter of excavator")
    with pytest.raises(wlx.Error) as e:
        wlx.sweep(robot, {"grid": {"legD": [1.5]}}, ["x" * 1_000_000], progress=False)
    assert re.fullmatch(r"runs\[0\]: 'x+\.\.\.x+' is neither a scenario id of excavator nor a file", str(e.value))
    assert len(str(e.value)) < 150
    with pytest.raises(wlx.Error, match=r"^parameters\.list\[0\]\.legD: must be a finite number, got 1000000000000"):
        wlx.sweep(robot, {"list": [{"legD": 10 ** 400}]}, ["ID-1"], progress=False)


def test_spec_numbers_are_read_as_yaml_1_2_reads_them():
    import yaml

    values = yaml.load("[1e-3, 15e-1, .5, -2.5E+3, +7, 3, '1e-3', 010, 0x1f, 0o17, 1:30, 2.]", Loader=_sweep._yaml_loader())
    assert values == [0.001, 1.5, 0.5, -2500.0, 7, 3, "1e-3", 10, 31, 15, "1:30", 2.0]
    assert [type(v) for v in values] == [float, float, float, float, int, int, str, int, int, int, str, float]


def test_a_spec_with_exponents_sweeps_those_numbers(robot, tmp_path):
    spec = tmp_path / "e.yaml"
    spec.write_text("parameters: {grid: {legD: [15e-1, 16E-1, .17e1], m_M1: [54e2]}}\n"
                    "runs: [{id: ID-1, rates: {x_C: 3e0}, dependent: [y_C, yaw], duration: 5e-2, weighting: 1}]\n"
                    "metrics: [peak_tau]\n")
    done = sweep_cli([str(spec), "--workers", "1"], timeout=300)
    assert done.returncode == 0, done.stderr
    rows = read_csv(tmp_path / "sweep" / "results.csv")
    assert [(r["legD"], r["m_M1"]) for r in rows] == [("1.5", "5400.0"), ("1.6", "5400.0"), ("1.7", "5400.0")]
    run = {**ID1, "duration": 0.05}
    assert float(rows[1]["peak_tau"]) == peak_tau(robot.simulate(run, params={"legD": 1.6, "m_M1": 5400.0}))


def one_variant_spec(tmp_path):
    return write_spec(tmp_path / "s.yaml", {"parameters": {"list": [{"legD": 1.5}]}, "runs": [{**ID1, "duration": 0.05}],
                                            "metrics": ["peak_tau"]})


def test_a_full_stdout_exits_74_naming_stdout(tmp_path):
    spec = one_variant_spec(tmp_path)
    with open("/dev/full", "w") as full:
        done = subprocess.run([WLX, "sweep", str(spec), "--workers", "1"], stdout=full, stderr=subprocess.PIPE, text=True,
                              timeout=300, check=False)
    assert done.returncode == 74, done.stderr
    assert done.stderr.endswith("\nwlx sweep: error: stdout: writing the output failed (No space left on device); "
                                "the output is incomplete\n"), done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
    assert len(read_csv(tmp_path / "sweep" / "results.csv")) == 1  # the files are written; only stdout failed


def test_a_closed_pipe_on_stdout_exits_74_naming_stdout(tmp_path):
    # `wlx sweep SPEC | head -c1` where head is gone before the sweep's one line: the reading end
    # is closed at once (the line comes at the end, so a reader of one byte would get it whole).
    spec = one_variant_spec(tmp_path)
    read, write = os.pipe()
    p = subprocess.Popen([WLX, "sweep", str(spec), "--workers", "1"], stdout=write, stderr=subprocess.PIPE, text=True)
    os.close(write)
    os.close(read)
    _, err = p.communicate(timeout=300)
    assert p.returncode == 74, err  # not -SIGPIPE: killed without a word
    assert err.endswith("\nwlx sweep: error: stdout: writing the output failed (Broken pipe); the output is incomplete\n"), err
    assert "Traceback" not in err and "Exception ignored" not in err


def test_run_ids_reach_the_plots_as_plain_text(robot, client, tmp_path, monkeypatch):
    # Each figure is also written as SVG with its text as text: the ids must be there as given
    # (mathtext would draw a$x^2$b as "ab" and a superscript, and c\$d$e without its backslash).
    import matplotlib.figure

    svgs = []
    savefig = matplotlib.figure.Figure.savefig

    def also_svg(fig, fname, **kwargs):
        savefig(fig, fname, **kwargs)
        text = io.StringIO()
        with matplotlib.rc_context({"svg.fonttype": "none"}):
            savefig(fig, text, format="svg")
        svgs.append(text.getvalue())

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", also_svg)
    ids = ["a$x^2$b", "c\\$d$e"]
    runs = [{**ID1, "id": i, "duration": 0.05} for i in ids]
    wlx.sweep(robot, {"list": [{"legD": 1.5}, {"legD": 1.6}]}, runs, ["peak_tau"], out=tmp_path / "line", client=client,
              progress=False)
    assert (tmp_path / "line" / "plots" / "peak_tau-vs-legD.png").stat().st_size > 10000
    assert len(svgs) == 1 and all(f">{i}</text>" in svgs[0] for i in ids)  # the legend's entries
    wlx.sweep(robot, {"grid": {"legD": [1.5, 1.6], "m_M1": [5000.0, 6000.0]}}, runs, ["peak_tau"], out=tmp_path / "heat",
              client=client, progress=False)
    for safe, i in zip(("a_x_2_b", "c__d_e"), ids):
        assert (tmp_path / "heat" / "plots" / f"peak_tau-{safe}-heatmap.png").stat().st_size > 5000
    assert len(svgs) == 3 and [f">peak_tau, run {i}</text>" in svg for svg, i in zip(svgs[1:], ids)] == [True, True]
