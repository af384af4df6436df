"""Plots of a study's answer (JSON, not a result file): a fit's record against its model with the
residual, an optimisation's evaluations with the best so far, and the pile studies' blow count
and stresses against the capacity, the stroke or the depth. Same canvas, sizes and formats as
`plots`."""

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
    "bearing_graph": "Blow count and stresses against the capacity or the ram's stroke",
    "drivability": "Blow count and stresses against the depth",
    "signal_match": "Force and waves at the head, measured and computed; the resistance along the pile; the "
    "static load test",
}
# quantity → how its axis reads, and the scale to that unit
_AXES = {
    "contact_force": ("contact force (kN)", 1e-3),
    "medium_force": ("medium force (kN)", 1e-3),
    "stress": ("stress (MPa), tension +", 1e-6),
    "struck_end_velocity": ("struck end velocity (m/s)", 1.0),
    "working_end_velocity": ("working end velocity (m/s)", 1.0),
}


def _new_figure(size: tuple[float, float] = FIGSIZE) -> Figure:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
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


def _column(rows: list[dict], name: str, scale: float = 1.0) -> np.ndarray:
    """A pile study's column, NaN where a row has none (refusal, a failed variant)."""
    return np.array([np.nan if row.get(name) is None else row[name] * scale for row in rows], dtype=float)


def _stresses(ax, along: np.ndarray, rows: list[dict], vertical: bool = False) -> None:
    """The rows' largest compressive and tensile stresses (MPa) against `along`."""
    for column, label, style in (
        ("max_compressive_stress", "compressive", {"color": "C3", "ls": "--"}),
        ("max_tensile_stress", "tensile", {"color": "C2", "ls": ":"}),
    ):
        stress = _column(rows, column, 1e-6)
        ax.plot(*((stress, along) if vertical else (along, stress)), marker=".", lw=1.2, label=label, **style)


def bearing_graph_figure(answer: dict, name: str = "case") -> Figure:
    """The blow count (left) and the largest stresses (right) against the capacity or the stroke."""
    fig = _new_figure()
    ax = fig.subplots()
    capacity = answer["variable"] == "ultimate_resistance"
    rows = answer["rows"]
    along = _column(rows, answer["variable"], 1e-3 if capacity else 1.0)
    ax.plot(along, _column(rows, "blow_count"), marker="o", ms=4, lw=1.6, color="C0", label="blow count")
    decorate(ax, "ultimate capacity (kN)" if capacity else "ram stroke (m)", "blow count (blows/m)")
    stresses = ax.twinx()
    _stresses(stresses, along, rows)
    stresses.set_ylabel("largest stress (MPa)")
    handles = [line for axis in (ax, stresses) for line in axis.get_lines()]
    ax.legend(handles, [line.get_label() for line in handles], loc="upper left")
    what = "Bearing graph" if capacity else "Inspector's chart"
    fig.suptitle(f"{what} of {name}: toe share {answer['toe_share']:.3g}", fontsize="medium")
    return fig


def drivability_figure(answer: dict, name: str = "case") -> Figure:
    """The blow count (and the restrike's) and the largest stresses against the depth, downward."""
    fig = _new_figure()
    counts, stresses = fig.subplots(1, 2, sharey=True)
    rows = answer["rows"]
    depth = _column(rows, "depth")
    counts.plot(_column(rows, "blow_count"), depth, marker="o", ms=3, lw=1.6, color="C0", label="driving")
    restrikes = [row["restrike"] or {} for row in rows]
    if any(restrikes):
        counts.plot(_column(restrikes, "blow_count"), depth, marker=".", lw=1.2, color="C1", label="restrike")
    counts.axvline(answer["refusal"], color="0.3", lw=0.8, ls="--", label="refusal")
    counts.invert_yaxis()
    counts.set_xlim(left=0.0)
    counts.legend(loc="best")
    decorate(counts, "blow count (blows/m)", "depth (m)")
    _stresses(stresses, depth, rows, vertical=True)
    stresses.legend(loc="best")
    decorate(stresses, "largest stress (MPa)", "")
    total = answer["total_blows"]
    title = f"Drivability of {name}"
    if total is not None:
        title += f": {total:.4g} blows to {answer['driven_to']:g} m, {answer['driving_time'] / 60:.3g} min"
    if answer["refusal_depth"] is not None:
        title += f"; refusal at {answer['refusal_depth']:g} m"
    fig.suptitle(title, fontsize="medium")
    return fig


def signal_match_figure(match: dict, name: str = "case") -> Figure:
    """A signal match on four panels: the force at the gauges, measured (dots) and computed (line),
    the 2L/c after the velocity's peak shaded; the waves down and up, (F ± Z·v)/2, measured and
    computed; each part's fitted resistance as a bar over its span along the pile (the toe's just
    below the end), with 3 standard errors; and the static load test of the fitted soil."""
    fig = _new_figure((FIGSIZE[0], 2 * FIGSIZE[1]))
    (force, waves), (bars, load) = fig.subplots(2, 2)
    series, curves = match["series"], match["waves"]
    t = np.asarray(series["time"])
    scale_t, unit_t = time_unit(t[-1])
    start, end = match["match_quality"]["window_time"]
    force.axvspan(start * scale_t, end * scale_t, color="0.92", label="2L/c window")
    force.plot(t * scale_t, np.asarray(series["record"]) * 1e-3, ".", ms=2, color="0.45", label="measured")
    force.plot(t * scale_t, np.asarray(series["model"]) * 1e-3, lw=1.3, color="C0", label="computed")
    force.legend(loc="best", fontsize="small")
    decorate(force, f"time ({unit_t})", "force at the gauges (kN)")
    for direction, color in (("down", "C1"), ("up", "C2")):
        waves.plot(t * scale_t, np.asarray(curves["measured"][direction]) * 1e-3, ".", ms=2, color=color, alpha=0.5)
        waves.plot(
            t * scale_t,
            np.asarray(curves["computed"][direction]) * 1e-3,
            lw=1.3,
            color=color,
            label=f"wave {direction}",
        )
    waves.legend(loc="best", fontsize="small", title="dots measured, lines computed", title_fontsize="small")
    decorate(waves, f"time ({unit_t})", "(F ± Z·v)/2 (kN)")
    rows = match["resistance_distribution"]
    length = rows[-1]["to"]
    for row in rows:
        toe = row["part"] == "toe"
        top, width = (length, length / 30) if toe else (row["from"], row["to"] - row["from"])
        error = None if row["standard_error"] is None else 3e-3 * row["standard_error"]
        kn = row["resistance"] * 1e-3
        bars.barh(top, kn, height=width, align="edge", xerr=error, color="C3" if toe else "C0", capsize=3)
        bars.annotate(f" {row['part']}: {kn:.4g} kN", (0.0, top + width / 2), va="center", fontsize="small")
    bars.set_ylim(length * 1.05, 0.0)
    bars.set_xlim(left=0.0)
    decorate(bars, "fitted resistance (kN), ± 3 standard errors", "below the gauges (m)")
    test = match["static_load_test"]
    load.plot(np.asarray(test["load"]) * 1e-3, np.asarray(test["settlement"]) * 1e3, marker=".", lw=1.4, color="k")
    load.invert_yaxis()
    decorate(load, "load at the head (kN)", "settlement (mm)")
    capacity = match["capacity"]
    error = capacity["standard_error"]
    fig.suptitle(
        f"Signal match of {name}: capacity {capacity['value'] * 1e-3:.5g}"
        + (f" ± {error * 1e-3:.2g}" if error is not None else " (not determined)")
        + f" kN, match quality {match['match_quality']['value']:.3g}",
        fontsize="medium",
    )
    return fig


def render_study(answer: dict, plot: str, fmt: str, name: str = "case") -> bytes:
    """Plot `plot` (a name of `STUDY_PLOTS`) of a study's answer as PNG or SVG bytes."""
    draw = {
        "fit": fit_figure,
        "convergence": convergence_figure,
        "bearing_graph": bearing_graph_figure,
        "drivability": drivability_figure,
        "signal_match": signal_match_figure,
    }[plot]
    buffer = io.BytesIO()
    with DRAWING:
        save(draw(answer, name), fmt, buffer)
    return buffer.getvalue()
