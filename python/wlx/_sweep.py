"""Parameter sweeps on Dask: wlx.sweep(...) in Python, `wlx sweep SPEC.yaml` on the command line.

A sweep runs every variant (a set of parameter values) through every run (a scenario) and reduces
each run to a row of metrics. The variants are cut into batches; a batch is one Dask task (a
task costs about a millisecond to schedule, a run a few: batches make the overhead small, see
_batch_size). Each finished batch is written to its own CSV under a temporary name and renamed, so
a killed sweep restarted with the same spec skips the variants already written and ends with the
same table (results.csv, rows in variant and run order) as an uninterrupted one. README.md,
"Parameter sweeps", documents the spec, the metrics and the files.

This module runs a sweep from end to end and is its command line; its parts are in _sweep_spec
(the spec, checked: the plan), _sweep_metrics (a batch on a worker: the runs and their metrics),
_sweep_store (the output folder and restarts), _sweep_cluster (Dask, the batches, the progress),
_sweep_plots (the plots) and _sweep_errors (the messages).
"""

import contextlib
import json
import os
import signal
import sys

import numpy as np

from ._sweep_cluster import _batch_size, _batches, _client_for, _default_workers, _Progress
from ._sweep_errors import OutputError, SweepError, _error, _excerpt, _nearest, _one_line, _say
from ._sweep_metrics import METRICS, _columns, _energy, _failed, _reference, run_batch
from ._sweep_plots import _plots, _sensitivities
from ._sweep_spec import MAX_BATCH, MAX_WORKERS, _count, _plan, _yaml_loader, read_spec
from ._sweep_store import _concatenate, _csv_text, _resume, _write_atomically

# What this module offers: the sweep and its command line, and, from the modules that hold them,
# the parts that tests/python/test_sweep.py reaches as _sweep.<name>.
__all__ = ["sweep", "run_spec", "main", "read_spec", "run_batch", "METRICS", "SweepError", "OutputError",
           "_plan", "_yaml_loader", "_client_for", "_batches", "_energy", "_sensitivities"]


def sweep(model, parameters, runs, metrics=("peak_tau",), out=None, client=None, scheduler=None, workers=None,
          batch_size=None, progress=True):
    """Runs every variant of `parameters` through every run and returns the table as a dict of
    columns (lists): variant, the parameters, run, complete, stopped, t_end, the metrics (None where a
    run has no such value or did not complete). On Dask: `client` (a distributed.Client), else
    `scheduler` ("tcp://HOST:8786"), else a local cluster of `workers` processes (default: this
    machine's cores). With `out` (a folder) the rows are written as each batch finishes and a
    restart skips the variants written; results.csv, sweep.json and plots/ are written at the end.
    README.md, "Parameter sweeps", has the format of `parameters` and `runs` and the metrics."""
    return _sweep(model, parameters, runs, metrics, out, client, scheduler, workers, batch_size, progress, base_dir=None)


def _sweep(model, parameters, runs, metrics, out, client, scheduler, workers, batch_size, progress, base_dir, keep=True):
    """The sweep; keep=False (the command line) holds no rows in memory: they go to the batch
    files, and results.csv is those files concatenated."""
    from . import Model

    if not isinstance(model, Model):
        _error("model", f"expected a wlx.Model (wlx.model(name) or wlx.load(path)), got {_excerpt(model)}")
    plan = _plan(model, parameters, runs, metrics, base_dir)
    if workers is not None:
        workers = _count(workers, "workers", 1, MAX_WORKERS)
    if batch_size is not None:
        batch_size = _count(batch_size, "batch_size", 1, MAX_BATCH)
    if client is not None and scheduler is not None:
        _error("scheduler", "give client or scheduler, not both")
    if workers is not None and (client is not None or scheduler is not None):
        _error("workers", "sizes the local cluster: a running one (client, scheduler) has its own workers")
    header = _columns(plan.names, model.actuators, plan.metrics)
    n = len(plan.values)
    if out is not None:
        out = os.fspath(out)
    # A restart's batches already in `out`, checked: their variants do not run again.
    batches_dir, done, kept, files = _resume(out, plan, header, keep)
    pending = np.flatnonzero(~done).tolist()
    reference = _reference(model)
    started_client, cluster = None, None
    workers_n = workers or _default_workers()
    bar = _Progress(n, n - len(pending), "variants", progress)
    if progress and len(pending) < n:
        _say(f"sweep: resuming: {n - len(pending)} of {n} variants already written in {batches_dir}\n")
    order = {label: k for k, (label, _) in enumerate(plan.runs)}
    try:
        if pending:
            active, cluster = _client_for(client, scheduler, workers_n)
            started_client = active if client is None else None
            if client is not None or scheduler is not None:
                workers_n = max(1, len(active.nthreads()))
            size = _batch_size(plan, reference, pending, workers_n, batch_size)
            from distributed import as_completed
            from distributed.scheduler import KilledWorker

            bar.restart()  # the rate and the time left from here: the cluster's start is not the sweep's pace
            futures = {}
            for b in _batches(pending, size):
                f = active.submit(run_batch, reference, plan.names, plan.runs, plan.metrics, b, plan.values[b].tolist(), pure=False)
                futures[f] = b
            for future in as_completed(list(futures)):
                b = futures.pop(future)
                try:
                    rows = future.result()
                except KilledWorker as e:
                    # The batch took down every worker Dask tried it on (its allowed failures): a
                    # variant that crashes the process is a result, the batch's rows say so.
                    reason = _one_line(f"the batch's worker process died each time it ran it ({e})")
                    rows = [[i, *plan.values[i].tolist(), label, False, reason, 0.0, *_failed(plan.metrics, model.actuators, reason)]
                            for i in b for label, _ in plan.runs]
                except Exception as e:  # noqa: BLE001 - the cluster, not a variant: stop, resumable
                    _error("sweep", f"a task failed ({_one_line(f'{type(e).__name__}: {e}')}); the batches written are kept: "
                                    "run the same sweep again to resume")
                rows.sort(key=lambda r: (r[0], order[r[len(plan.names) + 1]]))
                if batches_dir is not None:
                    path = os.path.join(batches_dir, f"rows-{b[0]:07d}-{b[-1]:07d}.csv")
                    _write_atomically(path, _csv_text(header, rows))
                    files.append((b[0], b[-1], path))
                if keep:
                    for row in rows:
                        kept.setdefault(row[0], []).append(row)
                bar.add(len(b))
                if _interrupted:  # a signal whose KeyboardInterrupt was swallowed (raised inside a __del__)
                    raise KeyboardInterrupt(_interrupted[0])
        bar.add(0, final=True)
    finally:
        if started_client is not None:
            started_client.close()
        if cluster is not None:
            cluster.close()
    if out is not None:
        results = os.path.join(out, "results.csv")
        complete_rows, total_rows = _concatenate(sorted(files), header, results, len(plan.runs))
        manifest = {"model": model.name, "mode": plan.mode, "parameters": plan.names, "units": plan.units,
                    "grid_shape": list(plan.shape) if plan.shape else None, "runs": [label for label, _ in plan.runs],
                    "metrics": {m: METRICS[m][0] for m in plan.metrics}, "variants": n, "rows": total_rows,
                    "complete_rows": complete_rows}
        _write_atomically(os.path.join(out, "sweep.json"), json.dumps(manifest, indent=1) + "\n")
        _plots(out, plan, header, results)
    if not keep:
        return manifest if out is not None else None
    table = [row for i in range(n) for row in kept[i]]
    return {name: [row[k] for row in table] for k, name in enumerate(header)}



def run_spec(path, out=None, scheduler=None, workers=None, batch_size=None, progress=True):
    """`wlx sweep SPEC`: the spec file's sweep; relative names in it are relative to its folder."""
    import wlx

    spec = read_spec(path)
    base = os.path.dirname(os.path.abspath(path))
    model_name = spec.get("model", wlx.models()[0])  # the default model, as the command line's
    if not isinstance(model_name, str) or not model_name or not model_name.isprintable():
        _error("model", f"expected a built-in model's name or a model file, got {_excerpt(model_name)}")
    if model_name in wlx.models():
        model = wlx.model(model_name)
    else:
        file = model_name if os.path.isabs(model_name) else os.path.join(base, model_name)
        if not os.path.isfile(file):
            _error("model", f"{_excerpt(model_name)} is neither a built-in model ({', '.join(wlx.models())}) nor a file"
                            f"{_nearest(model_name, wlx.models())}")
        model = wlx.load(file)
    if out is None:
        given = spec.get("out", "sweep")
        if not isinstance(given, str) or not given or not given.isprintable():  # it is named in messages
            _error("out", f"expected a folder name (one printable line), got {_excerpt(given)}")
        out = given if os.path.isabs(given) else os.path.join(base, given)
    if batch_size is None and "batch_size" in spec:
        batch_size = spec["batch_size"]
    manifest = _sweep(model, spec["parameters"], spec["runs"], spec["metrics"], out, None, scheduler, workers, batch_size,
                      progress, base_dir=base, keep=False)
    return manifest, out


_interrupted = []  # the signals that asked the command line to stop (main)


def main(argv=None):
    """The command line: python3 -m wlx sweep SPEC [--out DIR] [--scheduler ADDRESS] [--workers N]
    [--batch-size N] (what `wlx sweep` runs). Exit 0 done, 2 a bad spec or option, 74 an output that
    could not be written, 130 / 143 / 129 interrupted (the batches written are complete)."""
    import argparse

    class Parser(argparse.ArgumentParser):
        def error(self, message):  # the house's exit code for a bad option: 2, one line
            sys.stderr.write(f"wlx sweep: error: {message}\n")
            raise SystemExit(2)

    parser = Parser(prog="wlx sweep", description="a parameter sweep on Dask (README.md, \"Parameter sweeps\")")
    parser.add_argument("spec", metavar="SPEC", help="the sweep's spec file (YAML)")
    parser.add_argument("--out", help="output folder (default: the spec's `out`, else sweep/ beside the spec)")
    parser.add_argument("--scheduler", help="a running Dask scheduler, tcp://HOST:8786 (default: a local cluster)")
    parser.add_argument("--workers", type=int, help="the local cluster's worker processes (default: this machine's cores)")
    parser.add_argument("--batch-size", type=int, help="variants per task (default: sized to about 2 s a task)")
    args = parser.parse_args(argv)

    def stop(signum, frame):
        # Remembered too: the exception may land in a finalizer, which Python ignores; the sweep's
        # loop checks the flag after each batch.
        _interrupted.append(signum)
        raise KeyboardInterrupt(signum)

    for number in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(number, stop)
    default_hook = sys.unraisablehook

    def unraisable(report):  # the swallowed interrupt is not an error to print (the flag acts on it)
        if not isinstance(report.exc_value, KeyboardInterrupt):
            default_hook(report)

    sys.unraisablehook = unraisable
    try:
        manifest, out = run_spec(args.spec, args.out, args.scheduler, args.workers, args.batch_size)
    except KeyboardInterrupt as e:
        signum = _interrupted[0] if _interrupted else (e.args[0] if e.args else None)
        code = {signal.SIGTERM: 143, signal.SIGHUP: 129}.get(signum, 130)
        _say("\nwlx sweep: interrupted: the batches written are complete; run the same command again to resume\n")
        return code
    except OutputError as e:
        _say(f"wlx sweep: error: {e}\n")
        return 74
    except ValueError as e:  # wlx.Error and the spec's errors: they name the field
        _say(f"wlx sweep: error: {e}\n")
        return 2
    stopped = manifest["rows"] - manifest["complete_rows"]
    return _print(f"{manifest['rows']} rows ({stopped} did not complete) in {os.path.join(out, 'results.csv')}\n")


def _print(text):
    """`text` to stdout, flushed: 0, or 74 with the reason when it cannot be written (a full disk,
    a closed pipe: Python ignores SIGPIPE, so the write fails with EPIPE instead of killing the
    process without a word), as the C++ commands end (cli/shell/output_checks.cpp)."""
    import errno

    try:
        if sys.stdout is None:  # started with stdout closed
            raise OSError(errno.EBADF, os.strerror(errno.EBADF))
        sys.stdout.write(text)
        sys.stdout.flush()
        return 0
    except OSError as e:
        _say(f"wlx sweep: error: stdout: writing the output failed ({e.strerror or e}); the output is incomplete\n")
    # What stays in stdout's buffer would fail again when Python exits (a second message and exit
    # 120): it goes to /dev/null instead.
    with contextlib.suppress(OSError, AttributeError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 74
