#!/usr/bin/env python3
"""Measures one parameter sweep (wlx.sweep) on a local Dask cluster of 1 and of 2 worker processes,
against the plain loop in one process, and Dask's per-task overhead (README.md, "Parameter sweeps",
the scaling table). Run from the source tree with the built package:

    PYTHONPATH=build/python python3 tools/sweep_scaling.py [--variants N] [--repeat R] [--json]

The sweep: the README's design study (ID-1 shortened to 0.4 s, peak torque) over N values of legD.
Each cluster is started and warmed (every worker has loaded the model) before it is timed; the
figures are the median of R sweeps. Timings, not checks: nothing here is asserted.
"""
import argparse
import json
import os
import platform
import statistics
import sys
import time

import numpy as np

import wlx

RUN = {"id": "ID-1", "rates": {"x_C": 3.0}, "dependent": ["y_C", "yaw"], "duration": 0.4, "weighting": 1}


def noop(x):
    return x


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--variants", type=int, default=400, help="variants of legD in the sweep (default 400)")
    parser.add_argument("--repeat", type=int, default=3, help="sweeps timed per configuration, the median kept (default 3)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a Markdown table")
    args = parser.parse_args()
    if not 1 <= args.variants <= 100000 or not 1 <= args.repeat <= 20:
        parser.error("--variants must be 1..100000 and --repeat 1..20")
    import distributed

    load_before = os.getloadavg()[0]
    robot = wlx.model("excavator")
    parameters = {"grid": {"legD": {"from": 1.3, "to": 2.2, "count": args.variants}}}
    figures = {}

    times = []
    for _ in range(args.repeat):
        started = time.perf_counter()
        loop = [max(np.abs(r[c]).max() for c in r if c.startswith("tau_"))
                for r in (robot.simulate(RUN, params={"legD": v}) for v in np.linspace(1.3, 2.2, args.variants))]
        times.append(time.perf_counter() - started)
    figures["loop_s"] = statistics.median(times)

    for workers in (1, 2):
        started = time.perf_counter()
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = distributed.Client(cluster)
        figures[f"startup_{workers}_s"] = time.perf_counter() - started
        wlx.sweep(robot, {"grid": {"legD": [1.4, 1.5, 1.6, 1.7]}}, [RUN], ["peak_tau"], client=client,
                  batch_size=1, progress=False)  # warm: each worker loads the model
        times = []
        for _ in range(args.repeat):
            started = time.perf_counter()
            table = wlx.sweep(robot, parameters, [RUN], ["peak_tau"], client=client, progress=False)
            times.append(time.perf_counter() - started)
        assert table["peak_tau"] == loop  # the same numbers, or the timing means nothing
        figures[f"sweep_{workers}_s"] = statistics.median(times)
        if workers == 1:
            # Per task: N empty tasks through the scheduler and back (submit, run, result), and
            # the sweep at one variant a task against the automatic batches.
            n = 1000
            times = []
            for _ in range(args.repeat):
                started = time.perf_counter()
                client.gather(client.map(noop, range(n), pure=False))
                times.append(time.perf_counter() - started)
            figures["empty_task_ms"] = statistics.median(times) / n * 1e3
            times = []
            for _ in range(args.repeat):
                started = time.perf_counter()
                wlx.sweep(robot, parameters, [RUN], ["peak_tau"], client=client, batch_size=1, progress=False)
                times.append(time.perf_counter() - started)
            figures["sweep_1_batch1_s"] = statistics.median(times)
        client.close()
        cluster.close()
    n = args.variants
    figures["load_average"] = [load_before, os.getloadavg()[0]]  # other work on the machine, before and after
    figures["variants"] = n
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
    except OSError:
        pass
    figures["machine"] = f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"
    figures["date"] = time.strftime("%Y-%m-%d")
    if args.json:
        print(json.dumps(figures, indent=1))
        return 0
    per = lambda s: f"{s / n * 1e3:.2f}"  # noqa: E731
    print(f"Measured {figures['date']} on {figures['machine']} by `tools/sweep_scaling.py --variants {n}` "
          f"(median of {args.repeat}; each cluster started and warmed first; 1-minute load average "
          f"{figures['load_average'][0]:.2f} before, {figures['load_average'][1]:.2f} after).\n")
    print("| the sweep of N = %d variants (ID-1, 0.4 s, peak torque) | wall time, s | ms per variant | speedup over the loop |" % n)
    print("|---|---:|---:|---:|")
    print(f"| plain loop over `m.simulate` in one process | {figures['loop_s']:.2f} | {per(figures['loop_s'])} | 1.0x |")
    for w in (1, 2):
        s = figures[f"sweep_{w}_s"]
        print(f"| `wlx.sweep`, local cluster of {w} worker{'s' if w > 1 else ''} (automatic batches) | {s:.2f} | {per(s)} | "
              f"{figures['loop_s'] / s:.2f}x |")
    s = figures["sweep_1_batch1_s"]
    print(f"| `wlx.sweep`, 1 worker, one variant a task (`batch_size=1`) | {s:.2f} | {per(s)} | {figures['loop_s'] / s:.2f}x |")
    print(f"\nAn empty task through the scheduler and back: {figures['empty_task_ms']:.2f} ms; starting a local "
          f"cluster: {figures['startup_1_s']:.1f} s (1 worker), {figures['startup_2_s']:.1f} s (2 workers).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
