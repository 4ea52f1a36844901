"""A sweep's spec, read and checked before anything runs: the parameters (a grid, a list or random
samples, their units), the runs, the metrics, and the bounds on each; _plan turns them into what the
sweep computes (_Plan). read_spec reads a spec file (YAML 1.2's numbers, no aliases, keys given
once). Every mistake is an error naming its field."""

import math
import os
import re

import numpy as np

from ._sweep_errors import _error, _excerpt, _key, _nearest, _one_line
from ._sweep_metrics import METRICS
from ._sweep_store import _read_bounded, _Refused


# Bounds on every input (README.md, "Parameter sweeps"): beyond them a sweep is an error, not a
# machine that runs out of memory or disk hours later.
MAX_VARIANTS = 1_000_000
MAX_RUNS = 100
MAX_ROWS = 20_000_000  # 10^6 variants x 12 runs and a margin; `wlx sweep` streams them to disk
MAX_BATCH = 10_000
MAX_WORKERS = 256
MAX_SPEC_BYTES = 1 << 20
MAX_SPEC_DEPTH = 100  # nesting of the spec's lists and mappings (a scenario inline is a few deep)


_MODES = ("grid", "list", "random")


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


# ---------------------------------------------------------------- the spec file


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
