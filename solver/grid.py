"""The tool on its grid and the numerics a case resolves to (τ, N, γ, number of steps)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Annotated, Literal

import numpy as np
from pydantic import ConfigDict, Field

from .case import Case, CaseError, FieldError, Numerics, Profile, Striker, Tool
from .schemes import Scheme, make_scheme, scheme_of

DEFAULT_CELLS = 100
DEFAULT_TOLERANCE = 0.01  # when the case gives no grid and no scheme
STEPS_PER_CONTACT = 200  # default τ resolves the estimated contact by this many steps
# From this Courant number the explicit scheme's end rows are the characteristic relation (it is 1
# but for rounding), and its ends integrate their own equations.
IMPEDANCE_COURANT = 1.0 - 1e-6


def tool_area(tool: Tool, x: np.ndarray) -> np.ndarray:
    """Cross-section `S(x)` (m²) at stations `x`."""
    if tool.profile is None:
        return np.full_like(np.asarray(x, dtype=float), tool.area)
    stations = profile_stations(tool.profile)
    return np.interp(x, stations.x, stations.area)


@dataclass(frozen=True)
class Stations:
    """A profile's stations as arrays: `x`, `area`, `∫_0^x S dx` at each (`integral`) and the slope
    of S on each segment after it; `inner` the stations between the ends, which split x into
    segments."""

    x: np.ndarray
    area: np.ndarray
    integral: np.ndarray
    slope: np.ndarray
    inner: np.ndarray


def profile_stations(profile: Profile) -> Stations:
    """The profile's `Stations`, made once for each profile (every grid of a ladder reads them)."""
    return _stations(tuple(profile.x), tuple(profile.area))


@lru_cache(maxsize=256)
def _stations(x: tuple[float, ...], area: tuple[float, ...]) -> Stations:
    px, pa = np.asarray(x), np.asarray(area)
    stations = Stations(
        x=px,
        area=pa,
        integral=np.concatenate(([0.0], np.cumsum(np.diff(px) * 0.5 * (pa[1:] + pa[:-1])))),
        slope=np.diff(pa) / np.diff(px),
        inner=px[1:-1],
    )
    for array in (stations.x, stations.area, stations.integral, stations.slope, stations.inner):
        array.setflags(write=False)  # shared by every caller
    return stations


def tool_mass(tool: Tool) -> float:
    """`m2 = ρ∫S dx`, exact for the piecewise-linear profile."""
    return float(tool_mass_ahead(tool, np.array([tool.length]))[0])


def tool_mass_ahead(tool: Tool, x: np.ndarray) -> np.ndarray:
    """`ρ∫_0^x S dx` (kg): the mass of the tool between the struck end and x."""
    return tool.density * area_integral(tool, np.asarray(x, dtype=float))


def wave_speed(tool: Tool) -> float:
    """`a = sqrt(E/ρ)` (m/s)."""
    return math.sqrt(tool.youngs_modulus / tool.density)


def striker_mass(striker: Striker) -> float:
    """m1 (kg): a lumped striker's mass, or an elastic one's `ρ∫S dx`."""
    return striker.mass if not striker.elastic else tool_mass(striker.rod())


def striker_transit(striker: Striker) -> float:
    """An elastic striker's wave transit time `L_s/a_s` (s; 0 for a lumped one)."""
    return striker.length / wave_speed(striker.rod()) if striker.elastic else 0.0


MIN_STRIKER_CELLS = 2  # an elastic striker's fewest cells: its face and back ends need one between


def striker_cells(striker: Striker, tau: float) -> int:
    """The cells of an elastic striker at Courant number 1 with the time step τ: the whole number
    of steps its wave transit takes (the rest of its length lies beyond its last node)."""
    return int(math.floor(striker_transit(striker) / tau * (1.0 + 1e-12)))


def fewest_cells(case: Case) -> int:
    """The fewest cells the explicit scheme at Courant number 1 (τ = L/(N·a)) takes the case on:
    an elastic striker's wave transit must span `MIN_STRIKER_CELLS` time steps, so a striker
    shorter (in transit time) than the tool needs N ≥ 2·(L/a)/(L_s/a_s)."""
    if not case.elastic_striker:
        return MIN_CELLS
    tool_transit = case.tool.length / wave_speed(case.tool)
    cells = max(MIN_CELLS, math.ceil(MIN_STRIKER_CELLS * tool_transit / striker_transit(case.striker)))
    while striker_cells(case.striker, tool_transit / cells) < MIN_STRIKER_CELLS:  # rounding's last step
        cells += 1
    return cells


# An elastic striker whose wave transit is p/q of the tool's (q at most this) is a whole number of
# cells on every multiple of q cells; its rest beyond the last node otherwise makes an error of
# first order, which grids each twice as fine as the last do not see (`whole_striker`)
WHOLE_STRIKER_DENOMINATOR = 1000
WHOLE_STRIKER_COARSEST = 2.0  # a ladder's grid is rounded up to one at most this many times finer


def whole_striker_unit(case: Case) -> int:
    """The fewest tool cells on which an elastic striker spans a whole number of cells (its wave
    transit over the tool's a ratio p/q, q ≤ `WHOLE_STRIKER_DENOMINATOR`, within the rounding
    `striker_cells` allows): q; 1 for a lumped striker or an incommensurate one."""
    if not case.elastic_striker:
        return 1
    ratio = striker_transit(case.striker) / (case.tool.length / wave_speed(case.tool))
    near = Fraction(ratio).limit_denominator(WHOLE_STRIKER_DENOMINATOR)
    return near.denominator if abs(float(near) - ratio) <= 1e-13 * ratio else 1


def whole_striker(case: Case, cells: int) -> int:
    """`cells` rounded up to a grid on which an elastic striker is a whole number of cells
    (`whole_striker_unit`), when that is at most `WHOLE_STRIKER_COARSEST` times finer; else `cells`.
    Its back end then lies on a node: the rock drill's energy to the rock converges to 90.81 J on
    such grids, where grids doubled from 49 cells agree with each other 0.40% under it."""
    unit = whole_striker_unit(case)
    whole = math.ceil(cells / unit) * unit
    return whole if whole <= WHOLE_STRIKER_COARSEST * cells else cells


def ladder_unit(case: Case, first: int) -> int:
    """What every grid of a ladder that starts on `first` cells is a multiple of: the elastic
    striker's `whole_striker_unit` when `first` is one (`first_cells` made it so), else 1. A ladder
    that started on other grids keeps to them: switched midway, its grids stop being nested."""
    unit = whole_striker_unit(case)
    return unit if first % unit == 0 else 1


def striker_grid(striker: Striker, tau: float) -> tuple[Grid, float]:
    """An elastic striker on its grid (`striker_cells`, cells of `a_s·τ` from its face) and the
    back delay: twice the transit time of its part beyond the last node (< 2τ)."""
    rod = striker.rod()
    cells = striker_cells(striker, tau)
    gridded = cells * wave_speed(rod) * tau
    if rod.profile is not None:
        x = [xi for xi in rod.profile.x if xi < gridded] + [gridded]
        part = rod.model_copy(
            update={
                "length": gridded,
                "profile": Profile(x=x, area=list(np.interp(x, rod.profile.x, rod.profile.area))),
            }
        )
    else:
        part = rod.model_copy(update={"length": gridded})
    return make_grid(part, cells, True), max(0.0, 2.0 * (striker_transit(striker) - cells * tau))


def rigid_wall_depth(case: Case) -> float | None:
    """The contact's deepest compression δ against a rigid wall (m): from the impact velocity, or
    with none from the external force; None when neither acts."""
    c1, p = case.contact.stiffness, 1.0 + case.contact.exponent  # p: the force's exponent
    w1 = abs(case.impact_velocity)
    if w1 > 0:
        return ((p + 1.0) * striker_mass(case.striker) * w1 * w1 / (2.0 * c1)) ** (1.0 / (p + 1.0))  # inf, not an error
    if case.force is not None and case.force.amplitude != 0:
        return (abs(case.force.amplitude) / c1) ** (1.0 / p)
    return None


def contact_time_estimate(case: Case) -> float:
    """Duration of the striker's contact with a rigid wall under the case's contact law (s).

    The tool yields, so the true contact is longer: a time step from this estimate errs on the
    fine side. With no impact velocity the external force sets the indentation instead; with a
    history driving the struck end (`struck_end`), its pulse's length.
    """
    if case.struck_end is not None:
        return case.struck_end.driver[1].width()
    depth = rigid_wall_depth(case)
    if depth is None:
        return case.numerics.duration
    stiffness = case.contact.stiffness * depth**case.contact.exponent
    # A depth that underflowed to 0 (a striker of a few yoctograms) leaves the contact too short
    # to estimate: 0, which the caller refuses as "no time step can be chosen".
    return math.pi * math.sqrt(striker_mass(case.striker) / stiffness) if stiffness > 0 else 0.0


def contact_stiffness_estimate(case: Case) -> float:
    """The contact's tangent stiffness `(1+α)·c1·δ^α` at the depth of a rigid-wall impact (N/m);
    the contact's own stiffness c1 (α = 0) when nothing drives it; 0 with no contact."""
    if case.contact is None:
        return 0.0
    alpha = case.contact.exponent
    depth = rigid_wall_depth(case)
    return (1.0 + alpha) * case.contact.stiffness * (depth if depth is not None else 0.0) ** alpha


# A contact or a medium this many times as stiff as the tool's end cell (E·S/h) makes the ends ring
# against it and the contact chatter (tens of contacts where there is one): an end carrying its
# half-cell mass from about as stiff, the paper's massless end from about 20× (`bench/validation.py`).
# Below, a contact that still chatters is refused once run (`adaptive.refuse_chatter`). Only the
# ends that integrate their own equations take any stiffness.
STIFF_END = {"mass": 1.0, "massless": 20.0}


def check_stiff_ends(case: Case, weights: Scheme, cells: int, end_areas: tuple[float, float]) -> None:
    """Refuse up front a fixed grid whose ends would ring against the contact or the medium,
    naming the field and what to do (`STIFF_END`)."""
    limit = STIFF_END["mass" if weights.end_masses else "massless"]
    h = case.tool.length / cells
    fix = (
        "leave numerics.cells, time_step and scheme out (the default accuracy takes any "
        "stiffness), or give numerics.scheme = 'explicit' with numerics.cells only (Courant "
        "number 1, whose ends integrate their own equations)"
    )
    errors = []
    for field, stiffness, area in (
        ("contact.stiffness", contact_stiffness_estimate(case), end_areas[0]),
        ("medium.stiffness", case.medium.loading_stiffness if case.medium else 0.0, end_areas[1]),
    ):
        end_cell = case.tool.youngs_modulus * area / h
        if stiffness > limit * end_cell:
            needed = cells * stiffness / (limit * end_cell)
            # Extreme inputs (a velocity of 1e-300 m/s) overflow the estimate: no grid would do.
            cells_hint = f"at least {math.ceil(needed)} cells" if needed < 1e15 else "a gentler case"
            what = "the contact's" if field.startswith("contact") else "the medium's"
            errors.append(
                FieldError(
                    field=field,
                    message=f"{what} stiffness, about {stiffness:.3g} N/m, is {stiffness / end_cell:.3g}× "
                    f"that of the tool's end cell on {cells} cells ({end_cell:.3g} N/m): the "
                    f"scheme '{weights.name}' would ring against it and the contact chatter. "
                    f"{fix[0].upper() + fix[1:]}, or use {cells_hint}",
                )
            )
    if errors:
        raise CaseError(errors)


@dataclass(frozen=True)
class ResolvedNumerics:
    """The numerics a run actually uses; stored with every result, and its summary's `numerics`
    (the descriptions are the response model's, `summary.Summary`)."""

    __pydantic_config__ = ConfigDict(extra="forbid")

    model: Annotated[
        Literal["rod", "lumped"], Field(description="the tool as an elastic rod, or the two-mass model (21)–(25)")
    ]
    scheme: Annotated[
        str,
        Field(
            description="'paper' (the weighted scheme (8), γ), 'sigma' (σ), 'explicit'; 'dop853' for the lumped model"
        ),
    ]
    time_step: Annotated[float, Field(description="τ, s")]
    cells: Annotated[int, Field(description="N, cells along the tool (0 for the lumped model)")]
    gamma: Annotated[float, Field(description="γ, the paper's weight of the new layer")]
    sigma: Annotated[float, Field(description="σ, the weight of the σ-scheme")]
    end_masses: Annotated[bool, Field(description="whether the tool's end nodes carry their half-cell mass")]
    steps: Annotated[int, Field(description="M, time steps (of all blows)")]
    courant: Annotated[float, Field(description="a·τ/h, 1")]
    # "impedance": the explicit scheme at Courant number 1, each end integrating its own equations
    # (`kernel.struck_end_step`).
    ends: Annotated[
        str,
        Field(
            description="how the tool's ends are solved: 'impedance', 'mass' (half-cell "
            "end masses), 'massless' (quasi-static) or 'none' (lumped)"
        ),
    ] = "mass"

    def as_dict(self) -> dict:
        return dict(vars(self))  # its fields are scalars: dataclasses.asdict's deep copy is not needed

    def weights(self) -> Scheme:
        return make_scheme(self.scheme, self.gamma, self.sigma, self.end_masses)


def resolve_numerics(
    case: Case,
    model: str | None = None,
    scheme: str | None = None,
    cells: int | None = None,
    time_step: float | None = None,
) -> ResolvedNumerics:
    """Fill in the defaults (arguments override the case): N = 100 cells; τ the smaller of h/a
    (Courant 1, for the rod) and the estimated contact time / 200, so that both the wave and the
    contact are resolved; for the explicit scheme h/a, where it is exact along a uniform tool and
    its ends integrate their own equations. An explicit scheme's Courant limit is checked here,
    before anything runs."""
    num = case.numerics
    model = model or num.model or "rod"
    weights = scheme_of(num, scheme)
    cells = cells or num.cells or DEFAULT_CELLS
    h = case.tool.length / cells
    a = wave_speed(case.tool)
    if not (h > 0.0 and 0.0 < a < math.inf and math.isfinite(a / h)):
        # Extremes that pass each field's own check but leave no grid to compute on.
        raise CaseError(
            [
                FieldError(
                    field="tool",
                    message=f"length {case.tool.length:.3g} m on {cells} cells and a wave speed "
                    f"sqrt(youngs_modulus/density) = {a:.3g} m/s leave no usable grid: give "
                    "values of a real tool",
                )
            ]
        )
    # The lumped model has no wave to resolve: τ only samples its histories.
    wave_limit = h / a if model == "rod" else math.inf
    if weights.name == "explicit" and model == "rod":
        default_tau = wave_limit
    else:
        default_tau = min(wave_limit, contact_time_estimate(case) / STEPS_PER_CONTACT)
    tau = time_step or num.time_step or default_tau
    steps = num.duration / tau if tau > 0 else math.inf
    if not math.isfinite(steps):
        raise CaseError(
            [
                FieldError(
                    field="numerics.time_step",
                    message=f"no time step can be chosen for this case (the estimated contact time is "
                    f"{tau * STEPS_PER_CONTACT:.3g} s): give numerics.time_step",
                )
            ]
        )
    courant = a * tau / h
    if model == "rod" and courant > weights.courant_limit * (1.0 + 1e-9):
        raise CaseError(
            [
                FieldError(
                    field="numerics.time_step",
                    message=f"the explicit scheme needs a Courant number a·τ/h ≤ 1, and τ = {tau:.4g} s on "
                    f"{cells} cells gives {courant:.4g}: set numerics.time_step ≤ {h / a:.4g} s, "
                    "use fewer cells, or numerics.scheme = 'sigma'",
                )
            ]
        )
    # every blow has the same steps
    steps = max(1, math.ceil(steps - 1e-9)) * case.blows_run
    ends = None
    if model != "rod":
        ends = "none"
    elif weights.name == "explicit" and weights.end_masses and courant >= IMPEDANCE_COURANT:
        ends = "impedance"
    if case.beyond_paper and ends != "impedance":
        field = case.beyond_paper[0]
        raise CaseError(
            [
                FieldError(
                    field=field,
                    message=f"{field} is solved only with the tool as a rod, by the explicit scheme at "
                    "Courant number 1 (its ends integrate their own equations): leave "
                    "numerics.model, cells, time_step and scheme out (the default accuracy), give "
                    "numerics.tolerance, or numerics.scheme = 'explicit' with numerics.cells only",
                )
            ]
        )
    if ends == "impedance" and case.elastic_striker and striker_cells(case.striker, tau) < MIN_STRIKER_CELLS:
        need = math.ceil(MIN_STRIKER_CELLS * cells * (h / a) / striker_transit(case.striker))
        raise CaseError(
            [
                FieldError(
                    field="numerics.cells",
                    message=f"the elastic striker's wave transit, {striker_transit(case.striker):.3g} s, "
                    f"is under {MIN_STRIKER_CELLS} time steps of {tau:.3g} s: give at least {need} "
                    "cells, or leave numerics.cells out (the default accuracy)",
                )
            ]
        )
    if model == "rod" and ends != "impedance":
        ends = "mass" if weights.end_masses else "massless"
        check_stiff_ends(case, weights, cells, tuple(tool_area(case.tool, np.array([0.0, case.tool.length]))))
    return ResolvedNumerics(
        model=model,
        scheme=weights.name,
        time_step=tau,
        cells=cells,
        gamma=num.gamma,
        sigma=num.sigma,
        end_masses=weights.end_masses,
        steps=steps,
        courant=courant,
        ends=ends,
    )


@dataclass(frozen=True)
class Grid:
    """The tool on `N + 1` nodes `x_i = i·h`, with the coefficients of the operator `(S·u_x)_x`.

    `area` is `S_i` and `area_mid` the mean area of each cell (exact for the piecewise-linear
    profile). The operator is conservative, `Λu_i = lower_i·(u_{i−1} − u_i) + upper_i·(u_{i+1} − u_i)`
    with `lower_i, upper_i = S_{i∓½}/S̄_i` and `S̄_i` the mean of the node's two cells: its
    stiffness is symmetric, so no taper can feed energy into the tool. (The paper's form
    `1 ∓ q_i`, `q_i = (S_{i+1} − S_{i−1})/(4S_i)`, is not: with the paper's scheme a 1:10 step in
    area multiplied the energy 29-fold.) The end cells take the area at the end instead of their
    mean (`make_grid`). `node_area·ρh` is each node's mass, half a cell at the
    ends, 0 at a massless end; `end_area` the cell areas in the end rows' stiffness `S·E/h`.
    """

    x: np.ndarray
    area: np.ndarray
    area_mid: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    node_area: np.ndarray
    end_area: tuple[float, float]
    h: float
    youngs_modulus: float
    density: float

    @property
    def cells(self) -> int:
        return len(self.x) - 1

    @property
    def uniform(self) -> bool:
        return bool((self.area == self.area[0]).all())


def area_integral(tool: Tool, x: np.ndarray) -> np.ndarray:
    """`∫_0^x S dx`, exact for the piecewise-linear profile."""
    if tool.profile is None:
        return tool.area * x
    stations = profile_stations(tool.profile)
    k = np.searchsorted(stations.inner, x, side="right")  # the segment each x lies on
    d = x - stations.x[k]
    return stations.integral[k] + stations.area[k] * d + 0.5 * stations.slope[k] * d * d


def node_areas(area_mid: np.ndarray) -> np.ndarray:
    """S̄_i, the mean area of each node's half cells (`S̄_i·ρh` its mass; half a cell at the ends)."""
    return np.concatenate(([0.5 * area_mid[0]], 0.5 * (area_mid[1:] + area_mid[:-1]), [0.5 * area_mid[-1]]))


def make_grid(tool: Tool, cells: int, end_masses: bool) -> Grid:
    h = tool.length / cells
    x = np.arange(cells + 1) * h  # as `np.linspace` makes it, without its cost on a coarse grid
    x[-1] = tool.length
    area = tool_area(tool, x)
    area_mid = np.diff(area_integral(tool, x)) / h
    # The end cells take the ends' own areas: an end answers a sudden force through the impedance
    # just inside it, and a cell mean h/2 away would put it O(h) off on a taper (the cells' mass
    # changes by O(h²)).
    area_mid[0], area_mid[-1] = area[0], area[-1]
    node_area = node_areas(area_mid)
    lower, upper = np.zeros(cells + 1), np.zeros(cells + 1)
    lower[1:-1] = area_mid[:-1] / node_area[1:-1]
    upper[1:-1] = area_mid[1:] / node_area[1:-1]
    if not end_masses:
        node_area[0] = node_area[-1] = 0.0
    return Grid(
        x=x,
        area=area,
        area_mid=area_mid,
        lower=lower,
        upper=upper,
        node_area=node_area,
        end_area=(float(area_mid[0]), float(area_mid[-1])),
        h=h,
        youngs_modulus=tool.youngs_modulus,
        density=tool.density,
    )


def shaft_spans(grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """The stretch of shaft each node carries, `[left_i, right_i]` (m): its half cells
    `[x_i − h/2, x_i + h/2]`, nodes 1 and N − 1 the ends' half cells too, the ends none (they keep
    their own equations)."""
    h, length = grid.h, grid.x[-1]
    left = np.maximum(grid.x - 0.5 * h, 0.0)
    right = np.minimum(grid.x + 0.5 * h, length)
    left[1], right[-2] = 0.0, length
    left[[0, -1]] = right[[0, -1]]
    return left, right


def node_weights(grid: Grid, acceleration: float) -> np.ndarray:
    """Each node's weight (N) under `acceleration` (m/s²): the mass of its half cells, the ends'
    carried by nodes 1 and N − 1 as their shaft is (`shaft_spans`), the ends none."""
    weight = node_areas(grid.area_mid) * grid.density * grid.h * acceleration
    weight[1] += weight[0]
    weight[-2] += weight[-1]
    weight[[0, -1]] = 0.0
    return weight


def shaft_nodes(segments: list, grid: Grid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The soil along the tool's side (`Case.shaft`'s segments) node by node on `grid`: each
    interior node's ultimate resistance r_i (N), stiffness k_i (N/m) and damping factor J_i (s/m).

    Each segment's resistance is spread evenly over its length, and a node takes what lies within
    its stretch (`shaft_spans`). k_i sums each share over its quake; J_i is the shares' mean."""
    n = grid.cells
    left, right = shaft_spans(grid)
    resistance, stiffness, damped = np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1)
    for segment in segments:
        share = np.clip(np.minimum(right, segment.end) - np.maximum(left, segment.start), 0.0, None)
        r = segment.ultimate_resistance * share / (segment.end - segment.start)
        resistance += r
        stiffness += r / segment.quake
        damped += r * segment.damping_factor
    damping_factor = np.divide(damped, resistance, out=np.zeros(n + 1), where=resistance > 0)
    return resistance, stiffness, damping_factor


# The coarsest grid of a ladder resolves the contact's time scale (`time_scale`) by this many
# steps at a tolerance of 1e-2, and by √(1e-2/tol) times as many at another.
FIRST_POINTS = 4.0
MIN_CELLS = 2
SEGMENT_CELLS = 2  # cells over the shortest segment of the tool's profile, on the first grid
STEP_FRACTION = 0.01  # of the tool's length: a shorter segment of the profile is a step


def rigidity(case: Case) -> float:
    """ε: the two-mass system's highest frequency over the tool's lowest elastic one, `πa/(2L)`.

    The contact is linearised at the depth of a rigid-wall impact (the estimate the time step
    starts from too): tangent stiffness `(1+α)·c1·depth^α`.
    """
    alpha, m1 = case.contact.exponent, striker_mass(case.striker)
    m2 = tool_mass(case.tool)
    period = contact_time_estimate(case)
    k_contact = (1.0 + alpha) * m1 * (math.pi / period) ** 2  # = (1+α)·G at the rigid-wall depth
    k_medium = case.medium.loading_stiffness if case.medium else 0.0
    # The larger root of det(K − ω²M) = 0 for K = [[k, −k], [−k, k + k_medium]], M = diag(m1, m2):
    # a quadratic whose roots are real and whose larger one suffers no cancellation.
    half_trace = 0.5 * (k_contact / m1 + (k_contact + k_medium) / m2)
    omega2 = half_trace + math.sqrt(max(half_trace**2 - k_contact * k_medium / (m1 * m2), 0.0))
    return math.sqrt(omega2) / (math.pi * wave_speed(case.tool) / (2.0 * case.tool.length))


def time_scale(case: Case) -> float:
    """The time the contact force's shape is drawn over (a driving history's pulse length): the
    rigid-wall contact time, or, for a
    contact stiff against the tool (its damping ratio on the tool's impedance Z above about 1),
    the time the tool brakes the striker in, m1/Z (Saint-Venant's 1/β): the contact's own quick
    rise is left to the ends' substeps."""
    if case.struck_end is not None:
        return contact_time_estimate(case)
    tool = case.tool
    area = tool.area if tool.area is not None else tool.profile.area[0]
    braking = striker_mass(case.striker) / (tool.density * wave_speed(tool) * area)
    scale = max(contact_time_estimate(case), braking)
    if case.elastic_striker:
        # an elastic striker's pulse has the striker's transit as its features' length: on the
        # first grid it has `MIN_STRIKER_CELLS` (at a tolerance of 1e-2)
        scale = min(scale, 2.0 * striker_transit(case.striker))
    return scale


def profile_cells(case: Case) -> int:
    """The fewest cells that give each segment of the tool's profile `SEGMENT_CELLS`: on coarser
    grids the waves reflected inside the tool are not yet the tool's, and their differences say
    nothing of the error (a 5-mm taper in a 0.1-m tool left the tension 6% off on 4, 8 and 16
    cells, each within 0.7% of the next). A segment under `STEP_FRACTION` of the tool's length is
    a step, which any grid takes."""
    if case.tool.profile is None:
        return MIN_CELLS
    length = case.tool.length
    x = case.tool.profile.x
    segments = [b - a for a, b in zip(x, x[1:]) if b - a >= STEP_FRACTION * length]
    return math.ceil(SEGMENT_CELLS * length / min(segments)) if segments else MIN_CELLS


def first_cells(case: Case, tol: float) -> int:
    """The coarsest grid of a ladder: `FIRST_POINTS` steps over the contact's time scale, the
    tool's profile resolved (`profile_cells`), no fewer cells than the case's ends take
    (`fewest_cells`), and an elastic striker a whole number of cells where its length allows
    (`whole_striker`)."""
    points = FIRST_POINTS * math.sqrt(1e-2 / tol)
    tau = time_scale(case) / points
    if not tau > 0.0:  # a striker of a few yoctograms: its contact time underflows
        raise CaseError(
            [
                FieldError(
                    field="striker",
                    message=f"the contact of a {striker_mass(case.striker):.3g}-kg striker at {case.impact_velocity:.3g} "
                    "m/s lasts no time that a grid can resolve: give values of a real striker",
                )
            ]
        )
    cells = max(fewest_cells(case), profile_cells(case), math.ceil(case.tool.length / (wave_speed(case.tool) * tau)))
    return whole_striker(case, cells)


def explicit_numerics(case: Case, cells: int) -> ResolvedNumerics:
    """The explicit scheme at Courant number 1 on `cells` cells."""
    h = case.tool.length / cells
    return resolve_numerics(case, model="rod", scheme="explicit", cells=cells, time_step=h / wave_speed(case.tool))


def tolerance_of(numerics: Numerics) -> float | None:
    """The tolerance a case is solved to: its own, or the default when it gives neither a grid
    nor a scheme (and asks for the rod); None for a fixed grid or the lumped model."""
    if numerics.tolerance is not None:
        return numerics.tolerance
    fixed = (numerics.cells, numerics.time_step, numerics.scheme)
    if all(value is None for value in fixed) and numerics.model != "lumped":
        return DEFAULT_TOLERANCE
    return None
