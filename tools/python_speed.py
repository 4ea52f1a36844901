#!/usr/bin/env python3
"""The Python binding's cost beside C++'s, measured side by side in one run (these machines are
noisy: read the ratios). For the excavator and the wheeled quadruped:
  - m.fk(s), one state a call: the time per call (issue target: at most 3 us);
  - m.fk(S) over 1000 states in one call, against 1000 calls of the generated FK in C++ over
    1000 states of the same spread (wlx_bench's <model>/fk_1000_states: the same frames and
    rotations, each output kept);
  - m.inverse_dynamics(S, U) over 1000 states, against 1000 inverse-dynamics steps in C++
    (wlx_bench's <model>/inverse_dynamics_step, which also runs the closed-form IK).
Usage: tools/python_speed.py [--build DIR]. Needs the build's Python package and wlx_bench ."""
import argparse
import json
import os
import subprocess
import sys
import timeit

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def cxx_medians(build, models):
    """Per model, wlx_bench's median ns (5 repetitions) of its FK of all frames (the "MuJoCo peer"
    row's wlx side) and of its inverse-dynamics step (the "every model" row)."""
    pattern = "^(" + "|".join(f"{m}/(fk_1000_states|inverse_dynamics_step)" for m in models) + ")$"
    out = subprocess.run([os.path.join(build, "wlx_bench"), "--json", f"--benchmark_filter={pattern}"],
                         capture_output=True, text=True, check=True).stdout
    rows = json.loads(out)
    medians = {}
    for m in models:
        for row in rows:
            if row["operation"] == f"{m}: fk_1000_states":
                medians[f"{m}/fk_1000_states"] = row["ns"] / 1000
            elif row["operation"] == f"{m}: inverse_dynamics_step":
                medians[f"{m}/inverse_dynamics_step"] = row["ns"]
    return medians


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=os.path.join(ROOT, "build"))
    args = parser.parse_args()
    sys.path.insert(0, os.path.join(args.build, "python"))
    import numpy as np
    import wlx

    models = ["excavator", "wheeled_quadruped"]
    cxx = cxx_medians(args.build, models)
    rng = np.random.default_rng(1)
    for name in models:
        m = wlx.model(name)
        s = m.ik()["s"]
        states = s + 1e-3 * rng.standard_normal((1000, len(s)))
        poses = np.tile(s, (1000, 1))
        u = np.full((1000, len(m.commanded)), 0.2)
        one = min(timeit.repeat(lambda: m.fk(s), number=20000, repeat=5)) / 20000 * 1e9
        batch = min(timeit.repeat(lambda: m.fk(states), number=20, repeat=5)) / 20 * 1e9
        dyn = min(timeit.repeat(lambda: m.inverse_dynamics(poses, u), number=5, repeat=5)) / 5 * 1e9
        fk_cxx, id_cxx = cxx[f"{name}/fk_1000_states"] * 1000, cxx[f"{name}/inverse_dynamics_step"] * 1000
        print(f"{name}: m.fk(s) {one / 1e3:.2f} us a call; m.fk over 1000 states {batch / 1e6:.3f} ms against C++ "
              f"{fk_cxx / 1e6:.3f} ms ({batch / fk_cxx:.2f}x); m.inverse_dynamics over 1000 states {dyn / 1e6:.2f} ms against "
              f"C++ {id_cxx / 1e6:.2f} ms ({dyn / id_cxx:.2f}x)")


if __name__ == "__main__":
    main()
