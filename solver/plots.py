"""Plots of one result file: forces, displacements, probe stresses, stress along the tool, its
space–time map, the energy budget, the medium's force against the penetration and the blows table.

Each plot is one drawing function in `_TABLE`, with what it needs from the result (`_NEEDS`).
Figures are `matplotlib.figure.Figure` on the Agg canvas, never pyplot, whose global figure
registry is no place for a server's threads. Large datasets are read with strides, so that a
plot reads a bounded number of values however much the run kept.

What a plot shows of a result (`forces`, `displacements`, `energy_budget`, ...) and why a result
cannot make it (`problem`) are also what the interactive plots' data shows (`series`).
"""

from __future__ import annotations

import io
import json
import math
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import h5py
import numpy as np

from .io import FORMAT

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

FORMATS = {"png": "image/png", "svg": "image/svg+xml"}  # format -> media type
FIGSIZE = (9.0, 5.0)  # inches
DPI = 120  # a PNG is FIGSIZE × DPI pixels
MAX_CURVE_POINTS = 20_000  # samples read of a history; the peak force is marked from the summary
MAX_FILL_POINTS = 2_000  # samples of the stacked energy terms: a fill is never simplified, and an
# SVG of eight fills of 20 000 points each is 5 MB
MAX_MAP_SIDE = 1000  # times and stations read for the space–time map
DEFAULT_TIMES = 5  # curves of stress along the tool when no times are given
MAX_TIMES = 12  # curves of stress along the tool at the most: more is a tangle, not a plot
ALONG_THE_TOOL = "x along the tool (m), struck end at 0"
# matplotlib's font cache is shared by every figure and is not thread-safe.
DRAWING = threading.Lock()


class NotAResult(ValueError):
    """The file is not a percussim result."""


class UnknownPlot(ValueError):
    """No plot has this name."""


class NotAvailable(ValueError):
    """This result cannot make this plot; the message says what to change."""


def time_unit(end: float) -> tuple[float, str]:
    """(scale, unit) of times up to `end` (s): µs below 2 ms, so that a scale reads 0 … 2000 at
    worst, never 0 … 0.002."""
    return (1e6, "µs") if end < 2e-3 else (1e3, "ms")


def _in_unit(t: float, scale: float, unit: str) -> str:
    """`t` (s) to 3 significant digits, without an exponent: "1000 µs", not "1e+03 µs"."""
    return f"{np.format_float_positional(t * scale, precision=3, fractional=False, trim='-')} {unit}"


def strides(rows: int, most: int) -> list[slice]:
    """Every k-th of `rows` rows, k = ⌈rows / most⌉, and the last when the stride misses it, so
    that a curve ends where the run does: one selection, or two. Stepped slices, not lists of
    rows: h5py reads each as one hyperslab, about 10× faster."""
    step = max(1, math.ceil(rows / most))
    every = slice(None, None, step)
    return [every] if (rows - 1) % step == 0 else [every, slice(rows - 1, rows)]


def take(dataset: h5py.Dataset, selections: list[slice]) -> np.ndarray:
    """The rows of `dataset` that `selections` (`strides`) select, in order."""
    parts = [dataset[rows] for rows in selections]
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


@dataclass
class Source:
    """An open result: its datasets, case and summary, and the time unit of its axes."""

    h5: h5py.File
    case: dict
    summary: dict

    def __post_init__(self) -> None:
        self.rows = len(self.h5["time"])
        self.end = float(self.h5["time"][-1])
        self.t_scale, self.t_unit = time_unit(self.end)

    def history(self, path: str, points: int | None = None) -> np.ndarray:
        """A history read with the stride that keeps about `points` (MAX_CURVE_POINTS) samples,
        the last one always among them, so that a curve ends where the run does."""
        return take(self.h5[path], strides(self.rows, points or MAX_CURVE_POINTS))

    def time(self, points: int | None = None) -> np.ndarray:
        return self.history("time", points) * self.t_scale

    def t_label(self) -> str:
        return f"time t ({self.t_unit})"

    def in_unit(self, t: float) -> str:
        return _in_unit(t, self.t_scale, self.t_unit)


@contextmanager
def open_result(path: str | Path) -> Iterator[Source]:
    """The result at `path`, open; `NotAResult` if it is not one."""
    try:
        h5 = h5py.File(path, "r")
    except FileNotFoundError:
        raise  # a missing file is not a wrong one
    except OSError as error:
        raise NotAResult(f"{path} is not a percussim result: not an HDF5 file ({error})") from None
    with h5:
        if h5.attrs.get("format") != FORMAT:
            raise NotAResult(f"{path} is not a percussim result: an HDF5 file without format = {FORMAT!r}")
        yield Source(h5, json.loads(h5.attrs["case"]), json.loads(h5["summary"][()]))


def decorate(ax: Axes, xlabel: str, ylabel: str) -> None:
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.margins(x=0)


def forces(case: dict) -> list[tuple[str, str, str]]:
    """(key, dataset, label) of the forces a result of `case` shows: the contact force F_c(t), the
    medium's force if it has a medium, the external force R(t) on the striker if it has one."""
    shown = [("contact_force", "contact/force", "contact force")]
    if case.get("medium"):
        shown.append(("medium_force", "medium/force", "medium force"))
    if case.get("force"):
        shown.append(("external_force", "external/force", "external force on the striker"))
    return shown


_FORCE_STYLES = {
    "contact_force": {"color": "C0", "lw": 1.4},
    "medium_force": {"color": "C1", "lw": 1.1},
    "external_force": {"color": "C2", "lw": 1.1, "ls": "--"},
}


def _force(fig: Figure, src: Source, times) -> None:
    """Contact force F_c(t), medium force and external force R(t), contact intervals shaded."""
    ax = fig.subplots()
    t = src.time()
    for key, path, label in forces(src.case):
        ax.plot(t, src.history(path) / 1e3, label=label, **_FORCE_STYLES[key])
    spans = [
        (c["start"] * src.t_scale, ((c["end"] if c["end"] is not None else src.end) - c["start"]) * src.t_scale)
        for c in src.summary["contacts"]
    ]
    if spans:
        # One collection for every interval: a run may have thousands.
        ax.broken_barh(spans, (0, 1), transform=ax.get_xaxis_transform(), color="C0", alpha=0.08, label="in contact")
    peak = src.summary["peak_contact_force"]
    if peak["value"] > 0:
        ax.plot(peak["time"] * src.t_scale, peak["value"] / 1e3, "o", color="C0", ms=5)
        ax.annotate(
            f"peak {peak['value'] / 1e3:.4g} kN at {src.in_unit(peak['time'])}",
            (peak["time"] * src.t_scale, peak["value"] / 1e3),
            xytext=(8, -4),
            textcoords="offset points",
            va="top",
            fontsize=9,
        )
    ax.axhline(0, color="0.5", lw=0.6)
    decorate(ax, src.t_label(), "force (kN), compression > 0")
    ax.legend(loc="upper right", fontsize=9)


def displacements(case: dict) -> list[tuple[str, str, str]]:
    """(key, dataset, label) of the displacements: the striker's y(t) (none where a history drives
    the struck end), the struck end's u_0(t) and the working end's u_N(t)."""
    ends = [
        ("struck_end", "tool/struck_end_displacement", "struck end of the tool"),
        ("working_end", "tool/working_end_displacement", "working end of the tool"),
    ]
    if not case.get("striker"):
        return ends
    # an elastic striker's recorded displacement is its impact face's
    striker = "striker's impact face" if case["striker"].get("length") else "striker"
    return [("striker", "striker/displacement", striker), *ends]


def _displacements(fig: Figure, src: Source, times) -> None:
    """Displacements of the striker y(t), the struck end u_0(t) and the working end u_N(t)."""
    ax = fig.subplots()
    t = src.time()
    for (_, path, label), style in zip(displacements(src.case), ("-", "--", "-.")):
        ax.plot(t, src.history(path) * 1e3, ls=style, lw=1.3, label=label)
    decorate(ax, src.t_label(), "displacement (mm), toward the medium > 0")
    ax.legend(fontsize=9)


def probe_label(x: float) -> str:
    """The probe at `x` (m), as its curve is named."""
    return f"x = {x:.4g} m"


def _probes(fig: Figure, src: Source, times) -> None:
    """Stress σ(x_k, t) at each probe station x_k."""
    ax = fig.subplots()
    t = src.time()
    stress = src.history("probes/stress") / 1e6
    for k, x in enumerate(src.h5["probes/x"][()]):
        ax.plot(t, stress[:, k], lw=1.1, label=probe_label(x))
    ax.axhline(0, color="0.5", lw=0.6)
    decorate(ax, src.t_label(), "stress σ (MPa), compression < 0")
    ax.legend(title="probe", fontsize=9)


def _nearest(frame_times: np.ndarray, times) -> list[int]:
    """The frames nearest `times`, in order, each once."""
    return sorted({int(np.abs(frame_times - t).argmin()) for t in times})


def _default_frames(src: Source, frame_times: np.ndarray) -> list[int]:
    """Frames spread over the first contact and the wave's transit L/a, a = √(E/ρ).

    The frame at the contact's start is left out (the tool is still at rest then). When the
    frames are too sparse for that, the first frames after the start.
    """
    tool = src.case["tool"]
    transit = tool["length"] / math.sqrt(tool["youngs_modulus"] / tool["density"])
    contacts = src.summary["contacts"]
    start = contacts[0]["start"] if contacts else 0.0
    stop = contacts[0]["end"] if contacts and contacts[0]["end"] is not None else frame_times[-1]
    span = max(stop - start, transit)
    after = np.flatnonzero(frame_times > start)
    if len(after) == 0:
        return [len(frame_times) - 1]
    frames = _nearest(frame_times[after], [start + span * k / DEFAULT_TIMES for k in range(1, DEFAULT_TIMES + 1)])
    if len(frames) < min(DEFAULT_TIMES, len(after)):
        frames = range(min(DEFAULT_TIMES, len(after)))
    return [int(after[k]) for k in frames]


def parse_times(text: str) -> list[float]:
    """`T1,T2,...`, times in s, for `stress_along`; a ValueError says what is wrong."""
    try:
        times = [float(t) for t in text.split(",")]
    except ValueError:
        raise ValueError(f"expected times in s, T1,T2,... (e.g. 5e-5,1e-4), not {text!r}") from None
    if not all(math.isfinite(t) for t in times):
        raise ValueError(f"times must be finite numbers of seconds, not {text!r}")
    if len(times) > MAX_TIMES:
        raise ValueError(f"{len(times)} times are more than the {MAX_TIMES} curves one plot shows")
    return times


def _frames(src: Source, times: Sequence[float] | None) -> list[int]:
    """The stored field frames to draw: nearest `times` (s), or spread over the first wave."""
    frame_times = src.h5["fields/time"][()]
    if times is None:
        return _default_frames(src, frame_times)
    for t in times:
        if not frame_times[0] <= t <= frame_times[-1]:
            raise ValueError(f"time {t:g} s is outside the run's fields ({frame_times[0]:g} … {frame_times[-1]:g} s)")
    return _nearest(frame_times, times)


def _stress_along(fig: Figure, src: Source, times) -> None:
    """Stress σ(x, t_j) along the tool at chosen times t_j."""
    ax = fig.subplots()
    x = src.h5["fields/x"][()]
    frames = _frames(src, times)
    stress = src.h5["fields/stress"][frames] / 1e6
    shown = src.h5["fields/time"][frames]
    # The legend's unit is the times' own: the first wave is a few µs into a run of ms.
    scale, unit = time_unit(shown[-1])
    for row, t in zip(stress, shown):
        ax.plot(x, row, lw=1.3, label=f"t = {_in_unit(t, scale, unit)}")
    ax.axhline(0, color="0.5", lw=0.6)
    decorate(ax, ALONG_THE_TOOL, "stress σ (MPa), compression < 0")
    ax.legend(fontsize=9)


def _spacetime(fig: Figure, src: Source, times) -> None:
    """Stress σ(x, t) over the tool and the run, on a colour scale centred on zero."""
    ax = fig.subplots()
    stress = src.h5["fields/stress"]
    rows = max(1, math.ceil(stress.shape[0] / MAX_MAP_SIDE))
    cols = max(1, math.ceil(stress.shape[1] / MAX_MAP_SIDE))
    values = stress[::rows, ::cols].T / 1e6  # x upward, t to the right
    x = src.h5["fields/x"][::cols]
    t = src.h5["fields/time"][::rows] * src.t_scale
    bound = float(np.abs(values).max()) or 1.0
    image = ax.imshow(
        values,
        origin="lower",
        aspect="auto",
        cmap="RdBu_r",
        vmin=-bound,
        vmax=bound,
        extent=(t[0], t[-1], x[0], x[-1]),
        interpolation="nearest",
    )
    fig.colorbar(image, ax=ax, label="stress σ (MPa), compression < 0")
    ax.set_xlabel(src.t_label())
    ax.set_ylabel(ALONG_THE_TOOL)


ENERGY_TERMS = {  # /energy/<name> -> label, in the order they are stacked (those the result has)
    "striker_kinetic": "striker kinetic",
    "striker_strain": "striker strain",  # an elastic striker's
    "tool_kinetic": "tool kinetic",
    "tool_strain": "tool strain",
    "contact_potential": "contact potential",
    "medium_potential": "medium potential",
    "medium_plastic": "medium plastic (permanent penetration)",  # a medium that yields
    "to_shaft": "soil along the tool's side (stored, slipped, damped)",  # a shaft's
    "anvil_kinetic": "anvil kinetic",
    "striker_withdrawn": "withdrawn with the striker between blows",
    "dissipated_between_blows": "spent as the tool came to rest between blows",  # a hammer at work
    "dissipated_contact": "dissipated in the contact",
    "dissipated_medium": "dissipated in the medium",
}


INPUT = "input: initial + external work"
NUMERICAL = "lost by the scheme (numerical)"


def energy_terms(h5: h5py.File) -> dict[str, str]:
    """The terms of ENERGY_TERMS this result (an open file) has: name -> label."""
    return {name: label for name, label in ENERGY_TERMS.items() if f"energy/{name}" in h5}


@dataclass(frozen=True)
class EnergyBudget:
    """The energy audit at some samples: each term of `energy_terms`, the input (½·m1·W1² + the
    external work) and what is left of it, the scheme's own dissipation (`numerical`)."""

    terms: list[np.ndarray]
    supplied: np.ndarray
    numerical: np.ndarray


def energy_budget(src: Source, read: Callable[[str], np.ndarray]) -> EnergyBudget:
    """The energy audit at the samples `read(dataset)` reads."""
    # The summary's, so that an elastic striker's mass ρ∫S dx is not computed again here; blow
    # after blow, the strikers launched after the first bring theirs as they are launched.
    supplied = src.summary["energy"]["initial"] + read("energy/external_work")
    if "energy/launched" in src.h5:
        supplied += read("energy/launched") - src.h5["energy/launched"][-1]
    terms = [read(f"energy/{name}") for name in energy_terms(src.h5)]
    return EnergyBudget(terms, supplied, supplied - np.sum(terms, axis=0))


def _energy(fig: Figure, src: Source, times) -> None:
    """The energy audit over time: stored and dissipated terms stacked against the input
    ½·m1·W1² + the external work; what is left is the scheme's own dissipation."""
    ax = fig.subplots()
    t = src.time(MAX_FILL_POINTS)
    budget = energy_budget(src, lambda path: src.history(path, MAX_FILL_POINTS))
    terms, supplied, numerical = budget.terms, budget.supplied, budget.numerical
    lost = numerical[-1] / supplied[-1] if supplied[-1] > 0 else 0.0
    bands = ax.stackplot(
        t,
        *terms,
        numerical,
        labels=[*energy_terms(src.h5).values(), NUMERICAL],
        colors=[f"C{k}" for k in range(len(terms))] + ["0.75"],
        alpha=0.85,
        lw=0,
    )
    bands[-1].set_hatch("////")  # what the scheme lost stands apart from the physics
    bands[-1].set_edgecolor("firebrick")
    ax.plot(t, supplied, color="black", lw=1.4, ls="--", label=INPUT)
    ax.annotate(
        f"the scheme {'lost' if lost >= 0 else 'created'} {abs(100 * lost):.2g}% of the input",
        xy=(t[-1], supplied[-1] - 0.5 * numerical[-1]),
        xytext=(-8, 0),
        textcoords="offset points",
        ha="right",
        va="center",
        fontsize=9,
        color="firebrick" if abs(lost) > 0.01 else "0.3",
    )
    decorate(ax, src.t_label(), "energy (J)")
    ax.set_ylim(0, 1.06 * max(supplied.max(), np.sum(terms, axis=0).max()))
    fig.legend(loc="outside right upper", fontsize=9, frameon=False)


def penetration_path(h5: h5py.File) -> str:
    """The dataset of the working end's penetration u_N: a medium that yields records its own; a
    linear one's is the working end's displacement."""
    return "medium/penetration" if "medium/penetration" in h5 else "tool/working_end_displacement"


def _force_penetration(fig: Figure, src: Source, times) -> None:
    """The medium's force against the working end's penetration u_N: a loop whose area, once the
    medium is unloaded, is the net work on it; the permanent penetration marked."""
    ax = fig.subplots()
    ax.plot(
        src.history(penetration_path(src.h5)) * 1e3,
        src.history("medium/force") / 1e3,
        color="C1",
        lw=1.3,
        label="medium force",
    )
    penetration = src.summary["medium_penetration"]
    permanent = penetration["permanent"] * 1e3
    ax.axvline(permanent, color="C3", lw=0.9, ls="--")
    ax.plot(permanent, 0.0, "v", color="C3", ms=8, clip_on=False, label=f"permanent penetration {permanent:.4g} mm")
    ax.axhline(0, color="0.5", lw=0.6)
    # kN·mm = J: the loop's area reads in joules on these axes.
    ax.annotate(
        f"net work on the medium {src.summary['energy']['to_medium']:.4g} J\n"
        f"(the loop's area once the medium is unloaded)\n"
        f"deepest penetration {penetration['max'] * 1e3:.4g} mm",
        xy=(0.02, 0.97),
        xycoords="axes fraction",
        va="top",
        fontsize=9,
    )
    decorate(ax, "penetration of the working end u_N (mm)", "medium force (kN), compression > 0")
    ax.margins(x=0.02)
    ax.legend(loc="best", fontsize=9)


BLOW_COLUMNS = {  # the summary's blows table: column -> (panel title, unit, scale from SI)
    "peak_contact_force": ("peak contact force", "kN", 1e-3),
    "max_compressive_stress": ("max compressive stress", "MPa", 1e-6),
    "to_medium": ("energy to the medium", "J", 1.0),
    "transfer_efficiency": ("transfer efficiency", "%", 100.0),
    "permanent_penetration": ("permanent penetration", "mm", 1e3),
    "set": ("set (added by the blow)", "mm", 1e3),
}


def _blows(fig: Figure, src: Source, times) -> None:
    """The summary's blows table, a panel a column, against the blow number."""
    from matplotlib.ticker import MaxNLocator

    table = src.summary["blows"]
    number = np.arange(1, len(table) + 1)
    for ax, (column, (title, unit, scale)) in zip(fig.subplots(2, 3, sharex=True).flat, BLOW_COLUMNS.items()):
        ax.plot(number, [row[column] * scale for row in table], "o-", color="C0", lw=1.2, ms=4, label=title)
        ax.set_title(title, fontsize=10)
        decorate(ax, "blow", unit)
        ax.margins(x=0.05)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))


def _envelope(fig: Figure, src: Source, times) -> None:
    """The summary's stress envelope: each stretch of the tool's greatest compression and tension,
    as steps along it."""
    envelope = src.summary["stress_envelope"]
    ax = fig.subplots()
    x = np.repeat(envelope["x"], 2)[1:-1]  # each stretch's two ends
    for key, label, color in (("compression", "greatest compression", "C0"), ("tension", "greatest tension", "C3")):
        values = np.repeat([np.nan if v is None else v / 1e6 for v in envelope[key]], 2)
        ax.plot(x, values, color=color, lw=1.6, label=label)
    decorate(ax, "x from the struck end (m)", "stress (MPa)")
    ax.legend(fontsize=8)


def _cycle(fig: Figure, src: Source, times) -> None:
    """A hammer at work: the striker's position and velocity over the cycles, the drive's
    pressures, and each blow's impact energy and stroke."""
    from matplotlib.ticker import MaxNLocator

    cycle = src.summary["cycle"]
    (motion, pressures), (energies, strokes) = fig.subplots(2, 2)
    t = src.time()
    motion.plot(t, src.history("striker/displacement") * 1e3, color="C0", lw=1.2, label="position y (mm)")
    speed = motion.twinx()
    speed.plot(t, src.history("striker/velocity"), color="C1", lw=1.0, label="velocity (m/s)")
    speed.set_ylabel("velocity (m/s)")
    decorate(motion, src.t_label(), "position y (mm), toward the tool > 0")
    motion.legend(handles=motion.lines + speed.lines, fontsize=8, loc="lower left")
    for path, label, style in (("drive/rear_pressure", "rear", "-"), ("drive/supply_pressure", "supply", "--")):
        pressures.plot(t, src.history(path) / 1e6, ls=style, lw=1.2, label=label)
    decorate(pressures, src.t_label(), "pressure (MPa)")
    pressures.legend(fontsize=8)
    blow = np.arange(1, len(cycle["impact_velocity"]) + 1)
    # the striker's mass from the energy it brought, ½·m·v² at each impact
    mass = 2.0 * src.summary["energy"]["initial"] / sum(v * v for v in cycle["impact_velocity"])
    energies.plot(blow, [0.5 * mass * v * v for v in cycle["impact_velocity"]], "o-", ms=4, lw=1.2)
    decorate(energies, "blow", "impact energy (J)")
    strokes.plot(blow, np.asarray(cycle["stroke"]) * 1e3, "o-", ms=4, lw=1.2, color="C2")
    decorate(strokes, "blow", "stroke (mm)")
    for ax in (energies, strokes):
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))


@dataclass(frozen=True)
class _Plot:
    title: str
    needs: tuple[str, ...]  # what beyond the histories: keys of _NEEDS
    draw: Callable[[Figure, Source, Sequence[float] | None], None]


_TABLE = {
    "force": _Plot("Contact force", (), _force),
    "displacements": _Plot("Displacements", (), _displacements),
    "probes": _Plot("Stress at the probes", ("probes",), _probes),
    "stress_along": _Plot("Stress along the tool", ("fields",), _stress_along),
    "spacetime": _Plot("Stress in the tool over x and t", ("fields",), _spacetime),
    "energy": _Plot("Energy budget", (), _energy),
    "force_penetration": _Plot("Medium force against penetration", ("medium",), _force_penetration),
    "envelope": _Plot("Greatest stresses along the tool", ("envelope",), _envelope),
    "blows": _Plot("Blow by blow", ("blows",), _blows),
    "cycle": _Plot("A hammer at work", ("cycles",), _cycle),
}
PLOTS = {name: plot.title for name, plot in _TABLE.items()}


def _plot(name: str) -> _Plot:
    if name not in _TABLE:
        raise UnknownPlot(f"unknown plot {name!r}; the plots are: {', '.join(PLOTS)}")
    return _TABLE[name]


def _no_fields(h5: h5py.File, case: dict) -> str | None:
    if "fields/stress" in h5:
        return None
    if h5.attrs.get("numerics.model") == "lumped":
        return (
            "this result is of the lumped model, which has no stress wave in the tool: "
            'run the case with numerics.model = "rod" and outputs.fields = true'
        )
    return "this result has no stress fields: run the case with outputs.fields = true"


def _no_probes(h5: h5py.File, case: dict) -> str | None:
    if len(h5["probes/x"]):
        return None
    return (
        "this result has no probes: run the case with outputs.probes, the stations x (m) "
        "along the tool, e.g. [0.0, 0.25]"
    )


def _no_medium(h5: h5py.File, case: dict) -> str | None:
    if case.get("medium"):
        return None
    return (
        "this case has no medium at the working end: give it a medium (medium.stiffness, or "
        'medium.kind "bilinear" or "smith" with its fields)'
    )


def _no_envelope(h5: h5py.File, case: dict) -> str | None:
    if h5.attrs.get("numerics.model") != "lumped":
        return None
    return (
        "this result is of the lumped model, which has no stress along the tool: "
        'run the case with numerics.model = "rod"'
    )


def _no_blows(h5: h5py.File, case: dict) -> str | None:
    if case.get("blows") or case.get("cycles"):
        return None
    return 'this case has no blows table: run it blow after blow with blows.count, e.g. "blows": {"count": 5}'


def _no_cycles(h5: h5py.File, case: dict) -> str | None:
    if case.get("cycles"):
        return None
    return 'this case is no hammer at work: give it a drive and cycles, e.g. "cycles": {"count": 10}'


# What a plot may need beyond the histories: each check says why a result lacks it, or None.
_NEEDS: dict[str, Callable[[h5py.File, dict], str | None]] = {
    "fields": _no_fields,
    "probes": _no_probes,
    "medium": _no_medium,
    "envelope": _no_envelope,
    "blows": _no_blows,
    "cycles": _no_cycles,
}


def problem(h5: h5py.File, name: str) -> str | None:
    """Why this result (an open file) cannot make plot `name`, saying what to change; None if it can."""
    needs = _plot(name).needs
    case = json.loads(h5.attrs["case"]) if needs else {}
    return next(filter(None, (_NEEDS[need](h5, case) for need in needs)), None)


def problems(path: str | Path) -> dict[str, str | None]:
    """Every plot's `problem` for the result at `path`."""
    with open_result(path) as src:
        return {name: problem(src.h5, name) for name in PLOTS}


def _figure(src: Source, name: str, times: Sequence[float] | None) -> Figure:
    plot = _plot(name)
    reason = problem(src.h5, name)
    if reason:
        raise NotAvailable(reason)
    # Imported here, not at the top: matplotlib takes 0.3 s to import, which the API would pay at
    # every start although most of its processes never draw.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=FIGSIZE, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    plot.draw(fig, src, times)
    fig.suptitle(f"{plot.title} — {src.case.get('name', 'case')}")
    return fig


def figure(path: str | Path, name: str, times: Sequence[float] | None = None) -> Figure:
    """Plot `name` of the result at `path`; `times` (s) only for `stress_along`."""
    with open_result(path) as src:
        return _figure(src, name, times)


def _check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; the formats are: {', '.join(FORMATS)}")


def save(fig: Figure, fmt: str, to) -> None:
    _check_format(fmt)
    # No date in an SVG: the same result gives the same file.
    fig.savefig(to, format=fmt, metadata={"Date": None} if fmt == "svg" else None)


def render(path: str | Path, name: str, fmt: str, times: Sequence[float] | None = None) -> bytes:
    """Plot `name` of the result at `path` as PNG or SVG bytes."""
    buffer = io.BytesIO()
    with DRAWING:
        save(figure(path, name, times), fmt, buffer)
    return buffer.getvalue()


def write_plots(
    path: str | Path,
    out_dir: str | Path,
    formats: Sequence[str] = ("png", "svg"),
    names: Sequence[str] | None = None,
    times: Sequence[float] | None = None,
) -> tuple[list[Path], dict[str, str]]:
    """Write the plots of the result at `path` as `<out_dir>/<name>.<format>`.

    Returns the files written and, for each plot this result cannot make, the reason.
    """
    names = list(PLOTS) if names is None else list(names)
    # An unknown name or format is refused before anything is written.
    for name in names:
        _plot(name)
    for fmt in formats:
        _check_format(fmt)
    out_dir = Path(out_dir)
    written, skipped = [], {}
    with open_result(path) as src:
        for name in names:
            reason = problem(src.h5, name)
            if reason:
                skipped[name] = reason
                continue
            out_dir.mkdir(parents=True, exist_ok=True)
            with DRAWING:
                fig = _figure(src, name, times)
                for fmt in formats:
                    target = out_dir / f"{name}.{fmt}"
                    save(fig, fmt, target)
                    written.append(target)
    return written, skipped
