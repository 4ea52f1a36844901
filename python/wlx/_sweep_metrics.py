"""What a worker does: run_batch runs a batch of variants through every run and reduces each run to
its row (variant, parameters, run, complete, stopped, t_end, then METRICS' columns); a run that did
not complete is a row saying why. Dask sends run_batch to the workers by name (this module and the
function's), so it and what it calls stay module-level functions; each worker process loads its
model once (_model_of)."""

import json
import os

import numpy as np

from ._sweep_errors import _one_line


# The metrics: name -> (unit, what it is). peak_tau and rms_tau also give one column per actuator.
METRICS = {
    "peak_tau": ("N m or N", "largest |tau| over the run, of all actuators (and peak_tau_<actuator> each)"),
    "rms_tau": ("N m or N", "largest RMS of tau over the samples, of all actuators (and rms_tau_<actuator> each)"),
    "peak_cond_J_beta": ("1", "largest cond(J_beta) over the run"),
    "min_clearance": ("m", "smallest clearance over the run"),
    "min_normal_force": ("N", "smallest normal force of the supporting contacts over the run (below 0: one would lift off)"),
    "min_friction_margin": ("N", "smallest friction margin mu f_n - f_t of the supporting contacts (below 0: one would slide)"),
    "min_tip_margin": ("rad", "smallest force-angle (tip-over) margin over the run (below 0: the machine tips)"),
    "energy": ("J", "the actuators' positive work, each actuator's own (none recovered), trapezoidal over the samples"),
    "reach_failure": ("1", "1 if the run stopped at a pose out of reach (its failure's kind \"out-of-reach\"), else 0"),
}


_MODELS = {}  # per worker process: the model, loaded once (a model file's plugin: from the cache)


def _model_of(reference):
    if reference not in _MODELS:
        import wlx

        kind, name = reference
        _MODELS[reference] = wlx.model(name) if kind == "builtin" else wlx.load(name)
    return _MODELS[reference]


def _reference(model):
    """The model as a task names it, for _model_of on a worker (a compiled model cannot be pickled)."""
    return ("file", os.path.abspath(model._path)) if model._path is not None else ("builtin", model.name)


def _columns(plan_names, runs_actuators, metrics):
    """The CSV's header."""
    header = ["variant", *plan_names, "run", "complete", "stopped", "t_end"]
    for m in metrics:
        header.append(m)
        if m in ("peak_tau", "rms_tau"):
            header += [f"{m}_{a}" for a in runs_actuators]
    return header


def _energy(run, actuators):
    """The actuators' positive work: the sum over actuators of the integral of max(tau_a q'_a, 0)
    (what each puts in; none recovered when another brakes). The rates q'_a are central differences
    of the sampled coordinates (second order in the step: runs write angles, not all rates); an
    actuator with no coordinate of its own (a wheel's spin) takes the run's total `power` instead,
    when it has one."""
    t = run["t"]
    if len(t) < 2:
        return 0.0
    if all(f"tau_{a}" in run and a in run for a in actuators):
        powers = [np.maximum(run[f"tau_{a}"] * np.gradient(run[a], t), 0.0) for a in actuators]
    elif "power" in run:
        powers = [np.maximum(run["power"], 0.0)]
    else:
        return None
    return float(sum(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(t)) for p in powers))


def _reduce(run, metrics, actuators):
    """One run's metric values, in the header's order (None: the run has no such quantity). The
    torques', condition's, clearance's and contacts' are the run's summary (m.simulate's "summary",
    computed where `wlx simulate` and the report compute theirs)."""
    out = []
    summary = run["summary"]
    for m in metrics:
        if m in ("peak_tau", "rms_tau"):
            if m not in summary or len(summary[m]) != len(actuators):
                out += [None] * (1 + len(actuators))
                continue
            each = [float(x) for x in summary[m]]
            out += [max(each), *each]
        elif m in ("peak_cond_J_beta", "min_clearance", "min_normal_force", "min_friction_margin", "min_tip_margin"):
            out.append(float(summary[m][0]) if m in summary else None)
        elif m == "energy":
            out.append(_energy(run, actuators))
        elif m == "reach_failure":
            out.append(0)
    return out


def _failed(metrics, actuators, kind):
    """The metric cells of a run that did not complete: empty, except reach_failure, 1 where the
    failure's kind (wlx.Error's `kind`, a run's "stop_kind") is a pose out of reach."""
    out = []
    for m in metrics:
        if m in ("peak_tau", "rms_tau"):
            out += [None] * (1 + len(actuators))
        elif m == "reach_failure":
            out.append(1 if kind == "out-of-reach" else 0)
        else:
            out.append(None)
    return out


def run_batch(reference, names, runs, metrics, indices, values):
    """Runs the variants `indices` (their parameter values `values`, SI) through every run; returns
    their rows. A variant that cannot run (bad parameters, a pose out of reach, a singular J_beta)
    is a row saying why: it never stops the batch."""
    from . import Error

    model = _model_of(reference)
    actuators = model.actuators
    rows = []
    for index, row_values in zip(indices, values):
        params = dict(zip(names, row_values))
        for label, source in runs:
            scenario = json.loads(source[5:]) if source.startswith("json:") else source
            try:
                run = model.simulate(scenario, params=params)
            except Error as e:  # wlx's own checks: bad parameters, a start out of reach, ...
                reason = _one_line(e)
                kind = getattr(e, "kind", "other")
                rows.append([index, *row_values, label, False, reason, 0.0, *_failed(metrics, actuators, kind)])
                continue
            except Exception as e:  # noqa: BLE001 - a variant never aborts the sweep; its row says what happened
                reason = _one_line(f"{type(e).__name__}: {e}")
                rows.append([index, *row_values, label, False, reason, 0.0, *_failed(metrics, actuators, "other")])
                continue
            t_end = float(run["t"][-1]) if len(run["t"]) else 0.0
            if run["complete"]:
                rows.append([index, *row_values, label, True, "", t_end, *_reduce(run, metrics, actuators)])
            else:
                reason = _one_line(run["stopped"])
                rows.append([index, *row_values, label, False, reason, t_end, *_failed(metrics, actuators, run["stop_kind"])])
    return rows
