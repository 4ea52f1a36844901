"""The plots of a finished sweep, from results.csv (plots/*.png), and the sensitivities of each
metric to each parameter (sensitivity.csv) where there are no curves or heat maps to draw."""

import csv
import math
import os
import re

import numpy as np

from ._sweep_metrics import METRICS
from ._sweep_store import _csv_text, _write_atomically



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
