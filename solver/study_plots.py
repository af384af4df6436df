"""Plots of a study's answer (JSON, not a result file): a fit's record against its model with the
residual, and an optimisation's evaluations with the best so far. Same canvas, sizes and formats
as `plots`."""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np

from .plots import DPI, DRAWING, FIGSIZE, decorate, save, time_unit

if TYPE_CHECKING:
    from matplotlib.figure import Figure

STUDY_PLOTS = {
    "fit": "Record against the fitted model, and the residual",
    "convergence": "Every evaluation of the objective, and the best so far",
}
# quantity → how its axis reads, and the scale to that unit
_AXES = {
    "contact_force": ("contact force (kN)", 1e-3),
    "medium_force": ("medium force (kN)", 1e-3),
    "stress": ("stress (MPa), tension +", 1e-6),
    "struck_end_velocity": ("struck end velocity (m/s)", 1.0),
    "working_end_velocity": ("working end velocity (m/s)", 1.0),
}


def _new_figure() -> Figure:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=FIGSIZE, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def fit_figure(fit: dict, name: str = "case") -> Figure:
    """The record (dots) and the fitted model (line) above, the residual below."""
    fig = _new_figure()
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1))
    t = np.asarray(fit["series"]["time"])
    record, model = np.asarray(fit["series"]["record"]), np.asarray(fit["series"]["model"])
    scale_t, unit_t = time_unit(t[-1])
    quantity = fit["record"]["quantity"]
    label, scale = _AXES[quantity]
    if quantity == "stress":
        label = f"stress at x = {fit['record']['x']:g} m (MPa), tension +"
    top.plot(t * scale_t, record * scale, ".", ms=2, color="0.55", label="record")
    top.plot(t * scale_t, model * scale, lw=1.4, color="C0", label="fitted model")
    top.legend(loc="best")
    decorate(top, "", label)
    bottom.plot(t * scale_t, (record - model) * scale, lw=0.8, color="C3")
    bottom.axhline(0.0, color="0.3", lw=0.6)
    offset = fit["record"].get("time_offset") or 0.0
    clock = (
        f"time ({unit_t})"
        if offset == 0.0
        else (f"time on the record's clock ({unit_t}): the impact at {-offset * scale_t:.4g} {unit_t}")
    )
    decorate(bottom, clock, "record − model")
    fitted = [
        f"{path} = {p['value']:.4g}" + (f" ± {p['standard_error']:.2g}" if p["standard_error"] is not None else "")
        for path, p in fit["parameters"].items()
    ]
    fig.suptitle(f"Fit of {name}: nrmse {fit['nrmse']:.3g}\n" + _lines(fitted, TITLE_WIDTH), fontsize="medium")
    return fig


TITLE_WIDTH = 100  # characters of a title's line: the figure's width at its font


def _lines(items: list[str], width: int) -> str:
    """`items` joined by commas, a new line before one that would pass `width`."""
    lines = [items[0]]
    for item in items[1:]:
        if len(lines[-1]) + 2 + len(item) > width:
            lines[-1] += ","
            lines.append(item)
        else:
            lines[-1] += ", " + item
    return "\n".join(lines)


def convergence_figure(answer: dict, name: str = "case") -> Figure:
    """The objective at every evaluation (feasible: dots; breaking a limit or failed: crosses) and
    the best feasible so far."""
    fig = _new_figure()
    ax = fig.subplots()
    ((goal, quantity),) = answer["objective"].items()
    values = np.array(
        [np.nan if e["quantities"].get(quantity) is None else e["quantities"][quantity] for e in answer["history"]],
        dtype=float,
    )
    feasible = np.array([e["feasible"] for e in answer["history"]], dtype=bool)
    runs = np.arange(1, len(values) + 1)
    ax.plot(runs[feasible], values[feasible], ".", ms=3, color="C0", label="within the limits")
    if (~feasible).any():
        ax.plot(runs[~feasible], values[~feasible], "x", ms=3, color="C3", label="breaks a limit")
    kept = np.where(feasible, values, np.nan)
    pick = np.fmax.accumulate if goal == "maximize" else np.fmin.accumulate
    ax.plot(
        runs,
        pick(np.where(np.isnan(kept), -np.inf if goal == "maximize" else np.inf, kept)),
        lw=1.4,
        color="k",
        label="best so far",
    )
    ax.legend(loc="best")
    decorate(ax, "evaluation", quantity)
    best = answer.get("quantities") or {}
    title = f"{goal.capitalize()} {quantity} of {name}"
    if best.get(quantity) is not None:
        title += f": {best[quantity]:.5g} (checked under the tolerance)"
    fig.suptitle(title, fontsize="medium")
    return fig


def render_study(answer: dict, plot: str, fmt: str, name: str = "case") -> bytes:
    """Plot `plot` ('fit' or 'convergence') of a study's answer as PNG or SVG bytes."""
    draw = {"fit": fit_figure, "convergence": convergence_figure}[plot]
    buffer = io.BytesIO()
    with DRAWING:
        save(draw(answer, name), fmt, buffer)
    return buffer.getvalue()
