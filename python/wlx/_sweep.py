"""Parameter sweeps on Dask: wlx.sweep(...) in Python, `wlx sweep SPEC.yaml` on the command line.

A sweep runs every variant (a set of parameter values) through every run (a scenario) and reduces
each run to a row of metrics. The variants are cut into batches; a batch is one Dask task (a
task costs about a millisecond to schedule, a run a few: batches make the overhead small, see
_batch_size). Each finished batch is written to its own CSV under a temporary name and renamed, so
a killed sweep restarted with the same spec skips the variants already written and ends with the
same table (results.csv, rows in variant and run order) as an uninterrupted one. README.md,
"Parameter sweeps", documents the spec, the metrics and the files.
"""

import contextlib
import csv
import io
import json
import math
import os
import re
import reprlib
import signal
import stat
import sys
import time

import numpy as np

# Bounds on every input (README.md, "Parameter sweeps"): beyond them a sweep is an error, not a
# machine that runs out of memory or disk hours later.
MAX_VARIANTS = 1_000_000
MAX_RUNS = 100
MAX_ROWS = 20_000_000  # 10^6 variants x 12 runs and a margin; `wlx sweep` streams them to disk
MAX_BATCH = 10_000
MAX_WORKERS = 256
MAX_SPEC_BYTES = 1 << 20
MAX_SPEC_DEPTH = 100  # nesting of the spec's lists and mappings (a scenario inline is a few deep)
# A batch file is read (on resume) only up to its header and this much a row: a row as written
# is at most about 6 KB (a run's name of 200 characters and a reason of 500, quoted, in UTF-8)
# and 25 bytes a number.
MAX_ROW_BYTES, MAX_CELL_BYTES = 8192, 32
# Text from the input in an error message: at most this many characters of it.
MAX_EXCERPT = 60
# A batch should take about this long on a worker: hundreds of times a task's overhead (a few ms
# through a local scheduler and back, README.md's scaling table), so scheduling costs well under
# 1%; a 10^6-variant sweep stays at tens of thousands of tasks and batch files; a kill loses at
# most this much work per worker, and the progress bar still moves.
TARGET_BATCH_SECONDS = 2.0
# ...and each worker should get at least this many batches, so that a slow batch does not leave
# the others idle at the end.
MIN_BATCHES_PER_WORKER = 4

# The metrics: name -> (unit, what it is). peak_tau and rms_tau also give one column per actuator.
METRICS = {
    "peak_tau": ("N m or N", "largest |tau| over the run, of all actuators (and peak_tau_<actuator> each)"),
    "rms_tau": ("N m or N", "largest RMS of tau over the samples, of all actuators (and rms_tau_<actuator> each)"),
    "peak_cond_J_beta": ("1", "largest cond(J_beta) over the run"),
    "min_clearance": ("m", "smallest clearance over the run"),
    "energy": ("J", "the actuators' positive work, each actuator's own (none recovered), trapezoidal over the samples"),
    "reach_failure": ("1", "1 if the run stopped at a pose out of reach (its failure's kind \"out-of-reach\"), else 0"),
}
_MODES = ("grid", "list", "random")


class SweepError(ValueError):
    """A mistake in a sweep's spec or arguments: the message names the field and the reason."""


def _error(field, reason):
    # wlx.Error when the package is there (a ValueError either way), so callers catch one type.
    try:
        from . import Error
    except ImportError:  # pragma: no cover - only without the compiled module
        raise SweepError(f"{field}: {reason}") from None
    raise Error(f"{field}: {reason}") from None


_REPR = reprlib.Repr()  # bounded work on any value: a deep or shared structure is not written out whole
_REPR.maxlevel, _REPR.maxstring, _REPR.maxother = 3, MAX_EXCERPT, MAX_EXCERPT


def _excerpt(value):
    try:
        text = _REPR.repr(value)
    except Exception:  # noqa: BLE001 - a value without a repr (an int of more than 4300 digits)
        text = f"a {type(value).__name__}"
    return text if len(text) <= MAX_EXCERPT else text[:MAX_EXCERPT - 3] + "..."


def _key(name):
    """A key or name from the input as it goes into an error's field: as given when it is a short
    printable name, else its excerpt (quoted, escaped and cut: no control characters reach the
    terminal, no megabyte of key the message)."""
    return name if isinstance(name, str) and 0 < len(name) <= MAX_EXCERPT and name.isprintable() else _excerpt(name)


def _nearest(name, names):
    import difflib

    if not isinstance(name, str) or len(name) > 200:  # no "did you mean" for a value that is not a short name
        return ""
    close = difflib.get_close_matches(name, list(names), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def _number(value, field):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _error(field, f"expected a number, got {_excerpt(value)}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond a double's range
        number = math.inf
    if not math.isfinite(number):
        _error(field, f"must be a finite number, got {_excerpt(value)}")
    return number


def _count(value, field, low, high):
    if isinstance(value, bool) or not isinstance(value, int):
        _error(field, f"expected a whole number, got {_excerpt(value)}")
    if not low <= value <= high:
        _error(field, f"must be between {low} and {high}, got {_excerpt(value)}")
    return value


def _keys(mapping, field, allowed, required=()):
    if not isinstance(mapping, dict):
        _error(field, f"expected a mapping, got {_excerpt(mapping)}")
    for k in mapping:
        if k not in allowed:
            _error(f"{field}.{_key(k)}" if field else _key(k), f"unknown key{_nearest(k, allowed)} (known: {', '.join(allowed)})")
    for k in required:
        if k not in mapping:
            _error(f"{field}.{k}" if field else k, "missing")


# ---------------------------------------------------------------- the plan: variants and runs


class _Plan:
    """What a sweep computes: the parameter names and units, the variants (rows of values, SI),
    the runs (label, scenario), the metrics; and, for a grid, its shape."""

    def __init__(self, model, names, units, values, mode, shape, runs, metrics):
        self.model, self.names, self.units, self.values = model, names, units, values
        self.mode, self.shape, self.runs, self.metrics = mode, shape, runs, metrics

    def identity(self):
        """What must match for a restart to reuse written rows: everything that changes a row (the
        values by their SHA-256, exact to the bit)."""
        import hashlib

        path = os.path.abspath(self.model._path) if self.model._path is not None else None
        return {"model": self.model.name, "model_file": path, "names": self.names, "variants": len(self.values),
                "values_sha256": hashlib.sha256(np.ascontiguousarray(self.values, dtype="<f8").tobytes()).hexdigest(),
                "runs": [[label, source] for label, source in self.runs], "metrics": self.metrics}


def _parameter_values(model, parameters):
    """The variants of a `parameters` mapping: (names, SI values as a variants x names array, mode,
    grid shape or None, units by name)."""
    _keys(parameters, "parameters", _MODES + ("units",))
    modes = [m for m in _MODES if m in parameters]
    if len(modes) != 1:
        _error("parameters", f"give exactly one of grid, list or random, got {modes or 'none'}")
    mode = modes[0]
    spec = parameters[mode]
    field = f"parameters.{mode}"
    known = model.params

    def check_name(name, where):
        if not isinstance(name, str) or name not in known:
            _error(where, f"not a parameter of {model.name}{_nearest(name, known)}")

    shape = None
    if mode == "grid":
        if not isinstance(spec, dict) or not spec:
            _error(field, "expected a mapping {parameter: values} with at least one parameter")
        names, axes = [], []
        for name, axis in spec.items():
            where = f"{field}.{_key(name)}"
            check_name(name, where)
            if isinstance(axis, list):
                if not axis:
                    _error(where, "an empty list of values")
                if len(axis) > MAX_VARIANTS:
                    _error(where, f"more than {MAX_VARIANTS} values")
                points = [_number(v, f"{where}[{k}]") for k, v in enumerate(axis)]
            elif isinstance(axis, dict):
                _keys(axis, where, ("from", "to", "count"), ("from", "to", "count"))
                count = _count(axis["count"], f"{where}.count", 1, MAX_VARIANTS)
                points = list(np.linspace(_number(axis["from"], f"{where}.from"), _number(axis["to"], f"{where}.to"), count))
            else:
                _error(where, f"expected a list of values or {{from, to, count}}, got {_excerpt(axis)}")
            if len(set(points)) != len(points):
                _error(where, "a value given twice (a grid's axis lists each value once)")
            names.append(name)
            axes.append(points)
        total = math.prod(len(a) for a in axes)
        if total > MAX_VARIANTS:
            _error(field, f"{total} variants (the product of the axes' lengths) is more than the bound of {MAX_VARIANTS}")
        shape = tuple(len(a) for a in axes)
        mesh = np.meshgrid(*[np.array(a, dtype=float) for a in axes], indexing="ij")  # the last parameter varies fastest
        values = np.stack([m.ravel() for m in mesh], axis=1)
    elif mode == "list":
        if not isinstance(spec, list) or not spec:
            _error(field, "expected a non-empty list of variants, each {parameter: value}")
        if len(spec) > MAX_VARIANTS:
            _error(field, f"{len(spec)} variants is more than the bound of {MAX_VARIANTS}")
        if not isinstance(spec[0], dict) or not spec[0]:
            _error(f"{field}[0]", f"expected a mapping {{parameter: value}}, got {_excerpt(spec[0])}")
        names = list(spec[0])
        for name in names:
            check_name(name, f"{field}[0].{_key(name)}")
        rows = []
        for k, variant in enumerate(spec):
            if not isinstance(variant, dict):
                _error(f"{field}[{k}]", f"expected a mapping {{parameter: value}}, got {_excerpt(variant)}")
            for name in variant:
                if not isinstance(name, str):  # a number or null as a key: named before any comparison of keys
                    _error(f"{field}[{k}].{_key(name)}", "a parameter's name is text")
            if set(variant) != set(names):
                missing, extra = sorted(set(names) - set(variant)), sorted(set(variant) - set(names))
                _error(f"{field}[{k}]", "every variant sets the same parameters as the first"
                       + (f"; missing {', '.join(missing)}" if missing else "") + (f"; not in the first: {', '.join(map(_key, extra))}" if extra else ""))
            rows.append([_number(variant[n], f"{field}[{k}].{n}") for n in names])
        values = np.array(rows, dtype=float)
    else:
        _keys(spec, field, ("samples", "seed", "distributions"), ("samples", "seed", "distributions"))
        samples = _count(spec["samples"], f"{field}.samples", 1, MAX_VARIANTS)
        seed = _count(spec["seed"], f"{field}.seed", 0, 2**63 - 1)
        dists = spec["distributions"]
        if not isinstance(dists, dict) or not dists:
            _error(f"{field}.distributions", "expected a mapping {parameter: {uniform: [low, high]} or {normal: [mean, sd]}}")
        # One generator for the whole sweep, drawn parameter after parameter in the spec's order:
        # the same spec and seed give the same variants on any machine (NumPy's PCG64).
        rng = np.random.Generator(np.random.PCG64(seed))
        names, columns = [], []
        for name, dist in dists.items():
            where = f"{field}.distributions.{_key(name)}"
            check_name(name, where)
            if not isinstance(dist, dict) or len(dist) != 1:
                _error(where, "expected one of {uniform: [low, high]} or {normal: [mean, sd]}")
            kind, args = next(iter(dist.items()))
            if kind not in ("uniform", "normal"):
                _error(f"{where}.{_key(kind)}", f"unknown distribution{_nearest(kind, ('uniform', 'normal'))} (known: uniform, normal)")
            if not isinstance(args, list) or len(args) != 2:
                _error(f"{where}.{kind}", f"expected two numbers, got {_excerpt(args)}")
            a, b = (_number(v, f"{where}.{kind}[{k}]") for k, v in enumerate(args))
            if kind == "uniform":
                if not a < b:
                    _error(f"{where}.uniform", f"low ({a}) must be below high ({b})")
                columns.append(rng.uniform(a, b, samples))
            else:
                if not b > 0:
                    _error(f"{where}.normal", f"the standard deviation must be positive, got {b}")
                columns.append(rng.normal(a, b, samples))
            names.append(name)
        values = np.stack(columns, axis=1)
    if not np.all(np.isfinite(values)):  # a linspace or a draw of huge bounds
        _error(field, "the values are not all finite numbers")

    units = {n: model.param_units.get(n, "") for n in names}
    given = parameters.get("units", {})
    if not isinstance(given, dict):
        _error("parameters.units", f"expected a mapping {{parameter: unit}}, got {_excerpt(given)}")
    for name, unit in given.items():
        where = f"parameters.units.{_key(name)}"
        if name not in names:
            _error(where, f"not a swept parameter{_nearest(name, names)}")
        if unit == units[name]:
            continue
        if unit == "deg" and units[name] == "rad":  # angles may be given in degrees, as in scenario files
            values[:, names.index(name)] = np.radians(values[:, names.index(name)])
            continue
        _error(where, f"{model.name}'s {name} is in {units[name]!r}, not {_excerpt(unit)}" + (" (or 'deg')" if units[name] == "rad" else ""))
    return names, units, values, mode, shape


def _runs(model, runs, base_dir):
    """The runs as (label, source): source a scenario id, an absolute file path, or a JSON text."""
    if isinstance(runs, (str, dict)):
        runs = [runs]
    if not isinstance(runs, list) or not runs:
        _error("runs", "expected a non-empty list of scenario ids, files or scenarios")
    if len(runs) > MAX_RUNS:
        _error("runs", f"{len(runs)} runs is more than the bound of {MAX_RUNS}")
    out, labels = [], set()
    for k, run in enumerate(runs):
        where = f"runs[{k}]"
        if isinstance(run, str):
            path = run if os.path.isabs(run) or base_dir is None else os.path.join(base_dir, run)
            if run in model.scenarios:
                label, source = run, run
            elif os.path.isfile(path):
                label, source = os.path.splitext(os.path.basename(run))[0], os.path.abspath(path)
            else:
                _error(where, f"{_excerpt(run)} is neither a scenario id of {model.name} nor a file{_nearest(run, model.scenarios)}")
        elif isinstance(run, dict):
            label = run.get("id", f"run{k + 1}")
            if not isinstance(label, str):
                _error(f"{where}.id", f"must be a string, got {_excerpt(label)}")
            from . import _to_json

            source = "json:" + _to_json(run, where)
        else:
            _error(where, f"expected a scenario id, a file or a scenario mapping, got {_excerpt(run)}")
        if not label or any(not c.isprintable() for c in label) or len(label) > 200:
            _error(where, f"its name {_excerpt(label)} is not one printable line of at most 200 characters")
        if label in labels:
            _error(where, f"a second run named {label!r} (give each its own \"id\")")
        labels.add(label)
        out.append((label, source))
    return out


def _metrics(metrics):
    if isinstance(metrics, str):
        metrics = [metrics]
    if not isinstance(metrics, (list, tuple)) or not metrics:
        _error("metrics", f"expected a non-empty list of metric names ({', '.join(METRICS)})")
    out = []
    for k, m in enumerate(metrics):
        if not isinstance(m, str) or m not in METRICS:  # a mapping or list is not hashable: never `in` a tuple of names
            _error(f"metrics[{k}]", f"unknown metric {_excerpt(m)}{_nearest(m, METRICS)} (known: {', '.join(METRICS)})")
        if m in out:
            _error(f"metrics[{k}]", f"{m} given twice")
        out.append(m)
    return out


def _plan(model, parameters, runs, metrics, base_dir=None):
    names, units, values, mode, shape = _parameter_values(model, parameters)
    plan = _Plan(model, names, units, values, mode, shape, _runs(model, runs, base_dir), _metrics(metrics))
    rows = len(values) * len(plan.runs)
    if rows > MAX_ROWS:
        _error("runs", f"{len(values)} variants x {len(plan.runs)} runs = {rows} rows, more than the bound of {MAX_ROWS}")
    return plan


# ---------------------------------------------------------------- one batch, on a worker

_MODELS = {}  # per worker process: the model, loaded once (a model file's plugin: from the cache)


def _model_of(reference):
    if reference not in _MODELS:
        import wlx

        kind, name = reference
        _MODELS[reference] = wlx.model(name) if kind == "builtin" else wlx.load(name)
    return _MODELS[reference]


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
    torques', condition's and clearance's are the run's summary (m.simulate's "summary", computed
    where `wlx simulate` and the report compute theirs)."""
    out = []
    summary = run["summary"]
    for m in metrics:
        if m in ("peak_tau", "rms_tau"):
            if m not in summary or len(summary[m]) != len(actuators):
                out += [None] * (1 + len(actuators))
                continue
            each = [float(x) for x in summary[m]]
            out += [max(each), *each]
        elif m in ("peak_cond_J_beta", "min_clearance"):
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


def _one_line(text, limit=500):
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


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


# ---------------------------------------------------------------- files


def _cell(value):
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)  # round-trip exact: a restarted sweep writes the same bytes
    return str(value)


def _csv_text(header, rows):
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")  # quotes what needs quoting (commas, quotes, newlines)
    if header is not None:
        writer.writerow(header)
    writer.writerows([[_cell(v) for v in row] for row in rows])
    return buffer.getvalue()


@contextlib.contextmanager
def _atomic_output(path):
    """A text file written under a temporary name beside `path`, synced and renamed to it when the
    block ends: a file under its own name is never cut. A failed write removes the temporary and
    raises OutputError naming `path`; any other error in the block removes it too."""
    temp = os.path.join(os.path.dirname(path), f".{os.path.basename(path)}.{os.getpid()}.tmp")
    try:
        with open(temp, "w", encoding="utf-8", newline="") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(temp, path)
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        if isinstance(e, OSError):
            raise OutputError(f"{path}: writing failed: {e.strerror or e}") from None
        raise


def _write_atomically(path, text):
    with _atomic_output(path) as f:
        f.write(text)


class OutputError(OSError):
    """An output that could not be written (full disk, no permission): exit 74 on the command line."""


def _remove(path):
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass
    except OSError as e:
        raise OutputError(f"{path}: cannot remove it: {e.strerror or e}") from None


def _say(text):
    try:
        sys.stderr.write(text)
        sys.stderr.flush()
    except (OSError, AttributeError, ValueError):  # a closed stderr never stops a sweep
        pass


# A batch's file: its variants are first..last, every one of them (batches never span a gap).
_BATCH_FILE = re.compile(r"^rows-(\d+)-(\d+)\.csv$")


def _parse_cell(text, column):
    if column in ("run", "stopped"):
        return text
    if column == "complete":
        return text == "true"
    if column == "variant":
        return int(text)
    return float(text) if text != "" else None


class _Refused(Exception):
    """An input file that is not read, or not taken: the reason."""


def _kind(mode):
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "of another kind"


def _open_regular(path, limit=None):
    """`path` opened for reading (binary) if it is a regular file (through links) of at most
    `limit` bytes, else _Refused with the reason. A FIFO, a device (/dev/zero) or a folder is
    refused before anything is read from it, so nothing waits for a writer or reads without end:
    checked by stat, then opened non-blocking and checked again (it may have been swapped)."""
    try:
        if not stat.S_ISREG(mode := os.stat(path).st_mode):
            raise _Refused(f"not a regular file ({_kind(mode)})")
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as e:
        raise _Refused(f"cannot read: {e.strerror or e}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _Refused(f"not a regular file ({_kind(st.st_mode)})")
        if limit is not None and st.st_size > limit:
            raise _Refused(f"larger than {limit} bytes")
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def _read_bounded(path, limit):
    """A regular file's bytes, at most `limit` (_Refused beyond, also when it grows while read)."""
    with _open_regular(path, limit) as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise _Refused(f"larger than {limit} bytes")
    return data


def _csv_rows(f, limit):
    """A CSV file's rows (UTF-8), read line by line and at most `limit` bytes in all (_Refused
    beyond: a line without end is not read whole). UnicodeDecodeError and csv.Error as they come."""

    def lines():
        left = limit
        while line := f.readline(left + 1):
            left -= len(line)
            if left < 0:
                raise _Refused(f"larger than {limit} bytes")
            yield line.decode("utf-8")  # a line ends at b"\n", never inside a UTF-8 sequence

    return csv.reader(lines())


def _batch_limit(header, rows):
    return len(_csv_text(header, [])) + rows * (MAX_ROW_BYTES + MAX_CELL_BYTES * len(header))


def _is_number(text):
    """A finite number in its round-trip form (Python's repr), as the sweep writes one."""
    try:
        value = float(text)
    except ValueError:
        return False
    return math.isfinite(value) and repr(value) == text


def _check_batch(path, first, last, plan, header, keep):
    """A batch file found on resume, checked against what this sweep writes there: the header, one
    row per variant first..last and run in that order, each row's variant id and parameter values
    to the bit and its run's name, `complete` true or false (a complete row stopped for no
    reason), a reason of one line, every number finite and round-trip exact, reach_failure 0 or 1,
    and no row more. Returns the rows, parsed (keep), else None; _Refused with the first problem.
    (A number edited to another finite one in its exact form is not found: the file has no
    checksum.)"""
    variants = plan.values[first:last + 1].tolist()
    rows = (last - first + 1) * len(plan.runs)
    p = len(plan.names)
    kept = [] if keep else None
    count = 0
    try:
        with _open_regular(path, _batch_limit(header, rows)) as f:
            reader = _csv_rows(f, _batch_limit(header, rows))
            if next(reader, None) != header:
                raise _Refused("its header is not this sweep's columns" if f.tell() else "empty")
            for k, row in enumerate(reader):
                count = k + 1
                where = f"row {k + 1}"
                if k >= rows:
                    raise _Refused(f"more than its {rows} rows ({last - first + 1} variants x {len(plan.runs)} runs)")
                if len(row) != len(header):
                    raise _Refused(f"{where}: {len(row)} cells, not {len(header)}")
                v, r = divmod(k, len(plan.runs))
                expected = [str(first + v), *map(_cell, variants[v]), plan.runs[r][0]]
                for column, (cell, want) in enumerate(zip(row, expected)):
                    if cell != want:
                        raise _Refused(f"{where}, {header[column]}: {_excerpt(cell)} where this sweep has {_excerpt(want)}")
                complete, stopped = row[p + 2], row[p + 3]
                if complete not in ("true", "false") or (complete == "true" and stopped) or len(stopped) > 500:
                    raise _Refused(f"{where}: complete {_excerpt(complete)}, stopped {_excerpt(stopped)} is not a row "
                                   "the sweep writes")
                for column in range(p + 4, len(header)):
                    cell = row[column]
                    if header[column] == "reach_failure":
                        good = cell in ("0", "1")
                    else:
                        good = _is_number(cell) or (cell == "" and column > p + 4)  # t_end is always there
                    if not good:
                        raise _Refused(f"{where}, {header[column]}: {_excerpt(cell)} is not a finite number as the sweep writes one")
                if keep:
                    kept.append([_parse_cell(c, h) for c, h in zip(row, header)])
    except UnicodeDecodeError:
        raise _Refused("not UTF-8 text") from None
    except csv.Error as e:
        raise _Refused(f"not CSV as the sweep writes it ({_one_line(e, 200)})") from None
    if count < rows:
        raise _Refused(f"{count} rows, not its {rows} ({last - first + 1} variants x {len(plan.runs)} runs)")
    return kept


# ---------------------------------------------------------------- progress


class _Progress:
    """count done, rate and time left on stderr: in place on a terminal, else a line at most every
    10 s (a log file is not flooded)."""

    def __init__(self, total, done, unit, enabled):
        self.total, self.done, self.unit, self.enabled = total, done, unit, enabled
        self.start_done, self.started, self.last = done, time.monotonic(), 0.0
        self.tty = enabled and sys.stderr.isatty()

    def restart(self):
        self.start_done, self.started = self.done, time.monotonic()

    def add(self, n, final=False):
        self.done += n
        now = time.monotonic()
        if not self.enabled or (not final and now - self.last < (0.2 if self.tty else 10.0)):
            return
        self.last = now
        elapsed = max(now - self.started, 1e-9)
        rate = (self.done - self.start_done) / elapsed
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        bar = "#" * filled + "-" * (width - filled)
        eta = "--" if not math.isfinite(left) else (f"{left:.0f} s" if left < 120 else f"{left / 60:.1f} min")
        line = f"sweep [{bar}] {self.done}/{self.total} {self.unit} {rate:.1f}/s, {eta} left"
        try:
            sys.stderr.write(("\r" + line + ("\n" if final else "")) if self.tty else line + "\n")
            sys.stderr.flush()
        except OSError:  # a closed stderr never stops a sweep
            pass


# ---------------------------------------------------------------- the sweep


def _batch_size(plan, reference, pending, workers, given):
    """Variants per task: `given`, else sized so that a batch takes about TARGET_BATCH_SECONDS on
    a worker (timed on one variant here) and each worker gets at least MIN_BATCHES_PER_WORKER."""
    if given is not None:
        return given
    if not pending:
        return 1
    index = pending[0]
    started = time.perf_counter()
    run_batch(reference, plan.names, plan.runs, plan.metrics, [index], plan.values[index:index + 1].tolist())
    per_variant = max(time.perf_counter() - started, 1e-6)
    by_time = max(1, int(TARGET_BATCH_SECONDS / per_variant))
    by_balance = max(1, math.ceil(len(pending) / (MIN_BATCHES_PER_WORKER * max(workers, 1))))
    return max(1, min(by_time, by_balance, MAX_BATCH))


def _reference(model):
    return ("file", os.path.abspath(model._path)) if model._path is not None else ("builtin", model.name)


def _client_for(client, scheduler, workers):
    """(client, cluster we started or None). A local cluster: one single-threaded worker process per
    core (the runs hold the GIL, so threads would not run in parallel)."""
    if client is not None:
        return client, None
    import logging

    from distributed import Client, LocalCluster

    if scheduler is not None:
        if not isinstance(scheduler, str) or not re.fullmatch(r"(tcp|tls|ucx)://[^\s/]+(:\d+)?", scheduler):
            _error("scheduler", f"expected an address such as tcp://HOST:8786, got {_excerpt(scheduler)}")
        try:
            return Client(scheduler, timeout="10s"), None
        except (OSError, TimeoutError) as e:
            _error("scheduler", f"cannot reach {scheduler}: {e}")
    # Every server of a local cluster (the scheduler, its HTTP routes, each worker and its nanny)
    # listens on the loopback address only: dashboard_address=None alone leaves the scheduler's
    # HTTP server (/info, /json, /metrics) on 0.0.0.0:8787.
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address="127.0.0.1:0", worker_dashboard_address="127.0.0.1:0",
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def _default_workers():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


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


def _batches(pending, size):
    """Runs of consecutive pending variants, cut into batches of at most `size`: a batch never
    spans a variant already written, so every batch file covers one range and results.csv is the
    files concatenated in order."""
    out, start = [], 0
    for k in range(1, len(pending) + 1):
        if k == len(pending) or pending[k] != pending[k - 1] + 1:
            run = pending[start:k]
            out += [run[j:j + size] for j in range(0, len(run), size)]
            start = k
    return out


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
    done = np.zeros(n, dtype=bool)
    kept = {}  # variant -> its rows (keep=True)
    files = []  # (first, last, path) of every batch file
    batches_dir = None
    if out is not None:
        out = os.fspath(out)
        batches_dir = os.path.join(out, "batches")
        try:
            os.makedirs(batches_dir, exist_ok=True)
        except OSError as e:
            raise OutputError(f"{out}: cannot create the folder: {e.strerror or e}") from None
        identity = json.dumps(plan.identity(), sort_keys=True)
        identity_path = os.path.join(out, "spec.json")
        if os.path.lexists(identity_path):
            try:  # read no more than this sweep's own identity and a byte: more is another sweep's
                with _open_regular(identity_path) as f:
                    same = f.read(len(identity.encode()) + 1) == identity.encode()
            except _Refused as e:
                _error("out", f"{identity_path}: {e}")
            if not same:
                _error("out", f"{out} holds the rows of another sweep (another model, parameters, runs or metrics): "
                              "remove it or give another folder")
        else:
            _write_atomically(identity_path, identity)
        for name in sorted(os.listdir(batches_dir)):
            path = os.path.join(batches_dir, name)
            m = _BATCH_FILE.match(name)
            if name.startswith(".") and name.endswith(".tmp"):
                _remove(path)  # a batch being written when the sweep was killed: it runs again
            elif m:
                first, last = int(m[1]), int(m[2])
                if not 0 <= first <= last < n or done[first:last + 1].any():
                    _error("out", f"{path}: not a batch of this sweep (variants {first}..{last} of {n})")
                # Not a file the sweep wrote there (a FIFO, a device, a folder): not read, and not
                # removed either: someone put it there.
                try:
                    mode = os.stat(path).st_mode
                except OSError as e:
                    _error("out", f"{path}: cannot read: {e.strerror or e}")
                if not stat.S_ISREG(mode):
                    _error("out", f"{path}: not a regular file ({_kind(mode)}): remove it and run the same sweep again")
                # Its rows are taken only as this sweep would write them; a file cut, edited or
                # holding a row more runs again (README.md, "Killed, then resumed").
                try:
                    rows = _check_batch(path, first, last, plan, header, keep)
                except _Refused as e:
                    _say(f"sweep: {path}: {e}; its variants {first}..{last} run again\n")
                    _remove(path)
                    continue
                if keep:
                    for row in rows:
                        kept.setdefault(row[0], []).append(row)
                done[first:last + 1] = True
                files.append((first, last, path))
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


def _concatenate(files, header, path, runs):
    """results.csv: the batch files' rows in variant order (each file holds one range, in order),
    streamed to a temporary name and renamed. Returns (rows that completed, rows)."""
    complete_column = header.index("complete")
    complete = total = 0
    with _atomic_output(path) as out:
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(header)
        for first, last, batch in files:  # each checked on resume, or written by this sweep
            try:
                with _open_regular(batch) as f:
                    reader = _csv_rows(f, _batch_limit(header, (last - first + 1) * runs))
                    next(reader)
                    for row in reader:
                        writer.writerow(row)
                        total += 1
                        complete += row[complete_column] == "true"
            except _Refused as e:
                _error("out", f"{batch}: {e}")
    return complete, total


# ---------------------------------------------------------------- plots


def _label(name, unit):
    return f"{name} ({unit})" if unit and unit != "1" else name


def _plain(text):
    """Text from a spec or a model file (a run's id, a parameter's name or unit) as matplotlib
    draws it literally: an even number of '$' would make it mathtext (an id such as a$x^2$b drawn
    as math, or a$\\frac$b an error naming neither the run nor the field). Each '$' escaped is a
    dollar sign again, and outside mathtext a backslash is one."""
    return str(text).replace("$", r"\$")


def _sensitivities(x, y):
    """Standardized coefficients of the least-squares linear fit y ~ x (each column of x and y
    scaled to unit standard deviation): the change of y, in its standard deviations, per standard
    deviation of each parameter, the others held. A constant column gives 0."""
    sx, sy = x.std(axis=0), y.std()
    if sy == 0 or len(y) < x.shape[1] + 2:
        return np.zeros(x.shape[1])
    z = np.where(sx > 0, (x - x.mean(axis=0)) / np.where(sx > 0, sx, 1), 0.0)
    a = np.column_stack([np.ones(len(y)), z])
    coefficients, *_ = np.linalg.lstsq(a, (y - y.mean()) / sy, rcond=None)
    return coefficients[1:]


def _plot_data(plan, header, results):
    """From results.csv, streamed: per run, the parameters and metrics of its complete rows (8
    bytes a value), and how many rows of it did not complete."""
    from array import array

    col = {h: k for k, h in enumerate(header)}
    data = {label: {"x": [array("d") for _ in plan.names], "y": {m: array("d") for m in plan.metrics}, "left_out": 0}
            for label, _ in plan.runs}
    with open(results, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        next(reader)
        for row in reader:
            d = data[row[col["run"]]]
            if row[col["complete"]] != "true":
                d["left_out"] += 1
                continue
            for k in range(len(plan.names)):
                d["x"][k].append(float(row[1 + k]))
            for m in plan.metrics:
                cell = row[col[m]]
                d["y"][m].append(float(cell) if cell else math.nan)  # a run without that quantity: not drawn
    return data


def _plots(out, plan, header, results):
    """One parameter: each metric against it (a line per run). Two on a grid: a heat map per metric
    and run. Random samples (or a grid of more than two, or a list): the standardized sensitivities
    of each metric to each parameter (also in sensitivity.csv). Rows that did not complete are left
    out (the title says how many)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with plt.rc_context({"text.usetex": False}):  # a matplotlibrc's LaTeX would read the text as TeX
        return _draw(out, plan, header, results, plt)


def _draw(out, plan, header, results, plt):
    plots = os.path.join(out, "plots")
    os.makedirs(plots, exist_ok=True)
    p = len(plan.names)
    data = _plot_data(plan, header, results)
    written = []

    def save(fig, name):
        path = os.path.join(plots, name)
        temp = os.path.join(plots, f".{name}.{os.getpid()}.tmp.png")
        fig.savefig(temp, dpi=100)
        plt.close(fig)
        os.replace(temp, path)
        written.append(path)

    def axis_label(k):
        return _plain(_label(plan.names[k], plan.units[plan.names[k]]))

    sensitivity_rows = []
    for metric in plan.metrics:
        unit = METRICS[metric][0]
        if plan.mode != "random" and p == 1:
            fig, ax = plt.subplots(figsize=(6, 4))
            drawn = False
            for label, _ in plan.runs:
                x, y = np.asarray(data[label]["x"][0]), np.asarray(data[label]["y"][metric])
                keep = np.isfinite(y)
                if keep.any():
                    order = np.argsort(x[keep], kind="stable")
                    left_out = data[label]["left_out"]
                    ax.plot(x[keep][order], y[keep][order], "o-",
                            label=_plain(label) + (f" ({left_out} variants did not complete)" if left_out else ""))
                    drawn = True
            if drawn:
                ax.set_xlabel(axis_label(0))
                ax.set_ylabel(_label(metric, unit))
                ax.legend(fontsize=8)
                fig.tight_layout()
                save(fig, f"{metric}-vs-{plan.names[0]}.png")
            else:
                plt.close(fig)
            continue
        for label, _ in plan.runs:
            x = np.column_stack([np.asarray(c) for c in data[label]["x"]]) if p else np.zeros((0, 0))
            y = np.asarray(data[label]["y"][metric])
            keep = np.isfinite(y)
            if not keep.any():
                continue
            x, y = x[keep], y[keep]
            left_out = data[label]["left_out"]
            note = f" ({left_out} variants did not complete)" if left_out else ""
            safe = re.sub(r"[^A-Za-z0-9_.+-]", "_", label)
            if plan.mode == "grid" and p == 2:
                a0, a1 = np.unique(plan.values[:, 0]), np.unique(plan.values[:, 1])
                grid = np.full((len(a0), len(a1)), np.nan)  # a cell without a value stays blank
                grid[np.searchsorted(a0, x[:, 0]), np.searchsorted(a1, x[:, 1])] = y
                fig, ax = plt.subplots(figsize=(6, 4.5))
                mesh = ax.pcolormesh(_edges(a1), _edges(a0), grid, shading="flat", cmap="viridis")
                fig.colorbar(mesh, ax=ax, label=_label(metric, unit))
                ax.set_xlabel(axis_label(1))
                ax.set_ylabel(axis_label(0))
                ax.set_title(f"{metric}, run {_plain(label)}{note}", fontsize=9)
                save(fig, f"{metric}-{safe}-heatmap.png")
            else:
                coefficients = _sensitivities(x, y)
                sensitivity_rows += [[metric, label, name, float(v)] for name, v in zip(plan.names, coefficients)]
                fig, ax = plt.subplots(figsize=(max(4, 0.8 * p + 2), 3.5))
                ax.bar([_plain(n) for n in plan.names], coefficients, color=["tab:blue" if v >= 0 else "tab:red" for v in coefficients])
                ax.axhline(0, color="black", linewidth=0.5)
                ax.set_ylabel(f"standardized effect on {metric}")
                ax.set_title(f"{metric}, run {_plain(label)}: linear fit over {len(y)} variants{note}", fontsize=9)
                fig.tight_layout()
                save(fig, f"{metric}-{safe}-sensitivity.png")
    if sensitivity_rows:
        _write_atomically(os.path.join(out, "sensitivity.csv"),
                          _csv_text(["metric", "run", "parameter", "standardized_coefficient"], sensitivity_rows))
    return written


def _edges(centres):
    """Cell edges around sorted centres (a heat map's cells), half-way between neighbours."""
    c = np.asarray(centres, dtype=float)
    if len(c) == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = (c[1:] + c[:-1]) / 2
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


# ---------------------------------------------------------------- the spec file and the command line


# Numbers as YAML 1.2 (its core schema) reads them, as model files do (yaml-cpp): 1e-3, 15e-1,
# .5 and -2.5E+3 are floats (YAML 1.1, PyYAML's, wants a dot and a signed exponent: 1e-3 would be
# a string), 010 is ten (not octal eight), 1:30 a string (not ninety). Whole numbers stay ints.
_YAML12_INT = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_YAML12_FLOAT = re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
                           r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$")


def _yaml_loader():
    import yaml

    int_tag, float_tag = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"

    class Loader(yaml.SafeLoader):
        """YAML with a key given twice in one mapping an error (PyYAML would keep the last), no
        aliases (*name: a 1 KB file of aliases of aliases is a structure of billions of nodes to
        whatever walks it), at most MAX_SPEC_DEPTH deep, and YAML 1.2's numbers."""

        depth = 0

        def compose_node(self, parent, index):
            if self.check_event(yaml.events.AliasEvent):
                raise yaml.composer.ComposerError(None, None, "an alias (*name) is not allowed in a sweep spec: write the value out",
                                                  self.peek_event().start_mark)
            self.depth += 1
            try:
                if self.depth > MAX_SPEC_DEPTH:
                    raise yaml.composer.ComposerError(None, None, f"nested more than {MAX_SPEC_DEPTH} deep", self.peek_event().start_mark)
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

    Loader.yaml_implicit_resolvers = {first: [(tag, rx) for tag, rx in resolvers if tag not in (int_tag, float_tag)]
                                      for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}
    Loader.add_implicit_resolver(int_tag, _YAML12_INT, list("-+0123456789"))
    Loader.add_implicit_resolver(float_tag, _YAML12_FLOAT, list("-+0123456789."))

    def construct_mapping(loader, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = loader.construct_object(key_node, deep=deep)
            if not isinstance(key, (str, int, float)):
                raise yaml.constructor.ConstructorError(None, None, "a key must be a name", key_node.start_mark)
            if key in seen:
                raise yaml.constructor.ConstructorError(None, None, f"{_key(key)}: given twice in one mapping", key_node.start_mark)
            seen.add(key)
        return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)

    def construct_number(loader, node):
        text = loader.construct_scalar(node)
        try:
            if node.tag == int_tag:
                return int(text, 0) if text[:2] in ("0o", "0x") else int(text)  # "010": ten
            special = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan}
            return special[text.lower()] if text.lower() in special else float(text)
        except (ValueError, TypeError):  # an explicit !!int or !!float on other text; more than 4300 digits
            reason = "more than 4300 digits" if len(text) > 4300 else f"not a number as {node.tag[18:]}: {_excerpt(text)}"
            raise yaml.constructor.ConstructorError(None, None, reason, node.start_mark) from None

    Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, construct_mapping)
    Loader.add_constructor(int_tag, construct_number)
    Loader.add_constructor(float_tag, construct_number)
    return Loader


def read_spec(path):
    """The spec file as a mapping (bounded, a regular file only, keys given once, no aliases)."""
    import yaml

    try:
        data = _read_bounded(path, MAX_SPEC_BYTES)
    except _Refused as e:
        _error(path, str(e))
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        _error(path, f"not UTF-8 text (byte {e.start})")
    try:
        spec = yaml.load(text, Loader=_yaml_loader())
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None) or getattr(e, "context_mark", None)
        where = f"{path}:{mark.line + 1}" if mark is not None else path
        _error(where, _one_line(getattr(e, "problem", None) or e, 200))
    if not isinstance(spec, dict):
        _error(path, "a sweep spec is a mapping (model, parameters, runs, metrics, out, batch_size)")
    _keys(spec, "", ("model", "parameters", "runs", "metrics", "out", "batch_size"), ("parameters", "runs", "metrics"))
    return spec


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
