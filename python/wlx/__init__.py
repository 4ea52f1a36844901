"""wlx from Python: a model's kinematics, inverse kinematics, wheel rates, inverse and forward
dynamics and simulations, computed by the same C++ as the `wlx` command (same inputs, same checks,
same error messages), with NumPy arrays out. The built-in models by name, or any model file:

    import wlx
    robot = wlx.model("excavator")          # or wlx.load("my_robot.yaml"): compiled on first use
    s = robot.ik({"z_C": 1.8, "params": {"legD": 1.7}})["s"]
    run = robot.simulate("NH-1")            # or a scenario dict, as in scenarios/*.json
    run["t"], run["x_C"], run["tau_psi_l2"]

Values follow the command line's grammar: SI numbers, or {"deg": x} / {"deg/s": x} for angles.
Errors raise wlx.Error (a ValueError) with the command line's message, which names the field.
"""

import json as _json


def _import_failure(error):
    """Why the package cannot load here, when this interpreter is not the one it was built for: the
    python3 first on PATH may be another (a pyenv or virtual environment's, without the build's NumPy,
    or of another version, which cannot load the compiled module: "No module named 'wlx._wlx'").
    None when it is that interpreter (the original error says it all) or the build did not say."""
    import os
    import sys

    try:
        from ._built_for import executable, version  # written by CMake at configure time
    except ImportError:
        return None
    running = sys.executable or "this interpreter"
    this_version = "%d.%d" % sys.version_info[:2]
    in_venv = sys.prefix != sys.base_prefix
    if os.path.realpath(running) == os.path.realpath(executable) and this_version == version and not in_venv:
        return None
    where = f"{running} (Python {sys.version.split()[0]}{', a virtual environment' if in_venv else ''})"
    return ImportError(
        f"wlx: this package was built for the Python at {executable} (Python {version}), with that "
        f"interpreter's NumPy; it is imported by {where}, where it cannot load: {error}. Run it with "
        f"{executable}, or build wlx for this interpreter (cmake -DPython3_EXECUTABLE={running}, with "
        f"NumPy and pybind11 installed for it).")


try:
    import numpy as _np

    from . import _wlx
    from ._wlx import Error
except ImportError as _error:
    _explained = _import_failure(_error)
    if _explained is None:
        raise
    raise _explained from _error

__all__ = ["Error", "Model", "load", "model", "models", "sweep"]


def models():
    """The names of the built-in models."""
    return list(_wlx.models)


def model(name="excavator"):
    """The built-in model of that name."""
    if name not in _wlx.models:
        raise Error(f"model: unknown model {name!r}; the built-in ones: {', '.join(_wlx.models)}")
    return Model(_wlx.model(name))


def load(path):
    """The model of a model file (a YAML model file, or one that names its URDF), as `wlx
    --model-file` loads it: on first use wlx-gen generates its headers and the C++ compiler builds
    them into a plugin (about half a minute; progress on stderr), cached by the file's content
    (in $WLX_CACHE_DIR, else $XDG_CACHE_HOME/wlx, else ~/.cache/wlx); later loads take
    milliseconds. A mistake in the file raises wlx.Error with wlx-gen's message
    (file:line:column: field: reason)."""
    import os as _os

    model = Model(_wlx.load(_os.fspath(path)))
    model._path = _os.fspath(path)
    return model


def _to_json(value, field):
    try:
        return _json.dumps(value, allow_nan=False)
    except (TypeError, ValueError) as e:  # NaN, infinities, objects JSON has no form for
        raise Error(f"{field}: {e}") from None


def _params_json(params):
    return _to_json(params or {}, "params")


class Model:
    """One model: its tables (names, units, parameters) and its computations."""

    def __init__(self, handle):
        self._m = handle
        self._path = None
        info = handle.info
        self.name = info["name"]
        self.description = info["description"]
        self.coordinates = list(info["coordinates"])  # s = [inputs, dependent joints]
        self.units = list(info["units"])
        self.input_count = info["input_count"]
        self.inputs = self.coordinates[: self.input_count]
        self.frames = list(info["frames"])
        self.params = dict(info["params"])  # defaults, SI units
        self.param_units = dict(info["param_units"])  # each parameter's unit (m, kg, rad, ...)
        self.scenarios = list(info["scenarios"])
        self.commanded = list(info["commanded"])  # u: the commanded speeds, in inverse_dynamics' order
        self.actuators = list(info["actuators"])  # tau's order: joints, and wheel drives (spin_<wheel>)
        # The contacts with the ground (contact_force's rows; f_n_<name> in simulate's columns).
        self.contacts = list(info.get("contacts", []))
        # The model at its own parameters with its working memory, made once: fk() and a batch of
        # inverse_dynamics() go through it without JSON; other parameters get theirs, a few kept.
        self._workspace = handle.workspace("{}")
        self._workspaces = {}

    def _workspace_for(self, params):
        if not params:
            return self._workspace
        key = _params_json(params)
        w = self._workspaces.get(key)
        if w is None:
            if len(self._workspaces) >= 8:  # bounded: the oldest goes
                self._workspaces.pop(next(iter(self._workspaces)))
            w = self._workspaces[key] = self._m.workspace(key)
        return w

    def __repr__(self):
        return f"wlx.load({self._path!r})" if self._path is not None else f"wlx.model({self.name!r})"

    def ik(self, request=None, **values):
        """Inverse kinematics: `wlx ik`'s request (inputs by name, "params", "method": "closed-form"
        or "newton", "branch": {limb: n}, "start"), as a dict and/or keywords. Returns `wlx ik`'s
        answer as a dict, plus "s": all coordinates as an array."""
        req = dict(request or {})
        req.update(values)
        s, answer = self._m.ik(_to_json(req, "request"))
        out = _json.loads(answer)
        out["s"] = s
        return out

    def fk(self, s, params=None):
        """Frame origins and orientations in K0 at coordinates s (all of them, e.g. ik()["s"]):
        {"positions": (frames x 3), "rotations": (frames x 3 x 3), "frames": names}. s may also be
        an array of states, one a row (N x coordinates): then positions are N x frames x 3 and
        rotations N x frames x 3 x 3, computed in one call."""
        positions, rotations = self._m.fk_many(self._workspace_for(params), s)
        return {"positions": positions, "rotations": rotations, "frames": self.frames}

    def dependent_rates(self, s, rates, dependent=None, params=None):
        """All coordinate rates s' from the input rates (a dict by name or an array of the inputs'
        rates); `dependent`: the input pair the wheels make dependent (default: the model's).
        Returns (sdot, cond_J_beta)."""
        if isinstance(rates, dict):
            r = _np.zeros(self.input_count)
            for k, v in rates.items():
                if k not in self.inputs:
                    raise Error(f"rates.{k}: not an input of {self.name}")
                r[self.inputs.index(k)] = v
            rates = r
        return self._m.dependent_rates(_np.asarray(s, dtype=float), _np.asarray(rates, dtype=float),
                                       list(dependent or []), _params_json(params))

    def inverse_dynamics(self, s, u, u_dot=None, params=None, weighting="model-weights"):
        """Q* and the actuator torques at s for the commanded speeds u and their rates u_dot
        (default 0), in the order of `commanded` (the model file's dynamics section); tau is in the
        order of `actuators`; `weighting` as in scenario files ("model-weights": the model file's,
        "contribution", "contacts": the torques that keep the machine on its contacts, the thesis'
        1, 2, 3 for the same, {"diag": [...]}, {"matrix": [[...]]}). For a model
        with contacts also "contact_force" and "contact_point" (one row per contact, in the order
        of `contacts`, K0, N and m), "friction_margin" (mu f_n - |f_t|, N) and "margins" (static
        and zero-moment-point margins in m, the force-angle margin in rad).

        s, u and u_dot may also be arrays of rows, one state a row (N x coordinates, N x commanded):
        then the result is {"tau": N x actuators, "Qstar": N x commanded}, computed in one call
        (any weighting but "contacts", which solves an
        optimisation per state, so goes state by state)."""
        s = _np.asarray(s, dtype=float)
        if u_dot is None:
            u_dot = _np.zeros(_np.shape(u))
        if s.ndim == 2:
            tau, qstar = self._m.inverse_dynamics_many(self._workspace_for(params), s, _np.asarray(u, dtype=float),
                                                       _np.asarray(u_dot, dtype=float), _to_json(weighting, "weighting"))
            return {"tau": tau, "Qstar": qstar}
        return self._m.inverse_dynamics(_np.asarray(s, dtype=float), _np.asarray(u, dtype=float),
                                        _np.asarray(u_dot, dtype=float), _params_json(params), _to_json(weighting, "weighting"))

    def forward_dynamics(self, s, u, tau, params=None):
        """The converse of inverse_dynamics: the accelerations u_dot of the commanded speeds u at s
        under the actuator torques tau (in the order of `actuators`), the closure and the rolling
        rows held. Returns a dict: u_dot, sddot (all coordinates), sdot, Qstar (= J_beta^T tau), M."""
        return self._m.forward_dynamics(_np.asarray(s, dtype=float), _np.asarray(u, dtype=float),
                                        _np.asarray(tau, dtype=float), _params_json(params))

    def simulate(self, scenario, every=1, torques=None, params=None):
        """Runs a scenario: an embedded id ("NH-1"), a path to a JSON file, or a dict in the scenario
        format; `params` ({name: value}) override the scenario's own parameters, key by key (as a
        sweep's variant does). Returns the CSV's columns as arrays by name (every `every`-th sample, from t = 0),
        plus "complete", "stopped" (why a run ended early), "stop_kind" (what kind of failure ended
        it, as wlx.Error's `kind`: "out-of-reach", "singular", "contact", "limit" or "other"; "" for a
        complete run), "summary" (over every sample, kept or not, as `wlx simulate` prints it and
        the report and a sweep use it: "peak_cond_J_beta", "min_clearance" with a clearance box, and
        for a run with torques "peak_tau" and "rms_tau" per actuator, in `actuators` order; empty
        without samples) and "evaluations". A run whose kept
        samples would take more than 256 MiB is refused (ValueError naming `every`): keep fewer, or
        stream it to a file with `wlx simulate`.

        torques: a function f(t, s, u) -> tau (in the order of `actuators`) that drives the run
        (forward dynamics, as a scenario's "torques" does): a controller in the loop. It is called
        at every evaluation of the equations of motion (each stage of an integrator step) with the
        time, all coordinates and the commanded speeds; the scenario then has neither "torques" nor
        "weighting", and its "rates" are the commanded speeds at t = 0."""
        if isinstance(scenario, dict):
            text = _to_json(scenario, "scenario")
        else:
            text = _to_json(str(scenario), "scenario")
        if isinstance(every, bool) or not isinstance(every, int):
            raise TypeError("every: must be an integer")
        if torques is not None and not callable(torques):
            raise TypeError("torques: must be a function f(t, s, u) -> tau, or None")
        result = self._m.simulate(text, _params_json(params), every, torques)
        out = dict(result["columns"])
        for k in ("id", "complete", "stopped", "stop_kind", "summary", "evaluations"):
            out[k] = result[k]
        return out


from ._sweep import sweep  # noqa: E402 - after Model, which it uses
