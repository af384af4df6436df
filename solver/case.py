"""The impact case: what a user asks the solver to compute (the names of the contract).

Every model forbids unknown fields and non-finite numbers, so a typo or a NaN is refused with its
field path instead of being silently ignored. `parse_case` turns pydantic's errors into
`CaseError`, a list of (field path, reason) in words an engineer reads.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, field_validator, model_validator
from pydantic_core import InitErrorDetails, PydanticCustomError

_M = TypeVar("_M", bound=BaseModel)
STANDARD_GRAVITY = 9.81  # m/s², a falling ram's g where the case gives no gravity
Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]


# The job page builds its form from this schema (as /openapi.json publishes it). Beside each
# field's title (its label), type, bounds and default, it reads these keys, which validate nothing:
# `quantity`, its physical quantity (service/static/units.js gives its units); `symbol`, the
# paper's; `choices`, a label for each value of a choice; `implied`, the value the solver takes
# when the field is left out though the model's default is None.
def _quantity(name: str) -> dict:
    return {"json_schema_extra": {"quantity": name}}


# Upper bounds wide enough for any percussive device, from a dental scaler to a pile hammer, and
# narrow enough that no combination overflows the solver's arithmetic (fuzzing found where).
Mass = Annotated[float, Field(gt=0, le=1e9, **_quantity("mass"))]
Speed = Annotated[float, Field(ge=-1e6, le=1e6, **_quantity("speed"))]
Length = Annotated[float, Field(gt=0, le=1e4, **_quantity("length"))]
Area = Annotated[float, Field(gt=0, le=1e4, **_quantity("area"))]
# up to far stiffer than steel: rigid-limit studies
Modulus = Annotated[float, Field(ge=1e3, le=1e20, **_quantity("stress"))]
Density = Annotated[float, Field(ge=1e-3, le=1e6, **_quantity("density"))]
Stiffness = Annotated[float, Field(ge=0, le=1e20, **_quantity("stiffness"))]
Damping = Annotated[float, Field(ge=0, le=1e15, **_quantity("damping"))]
ForceAmplitude = Annotated[float, Field(ge=-1e12, le=1e12, **_quantity("force"))]
Frequency = Annotated[float, Field(gt=0, le=1e9, **_quantity("rate"))]
Duration = Annotated[float, Field(gt=0, le=1e4, **_quantity("time"))]
Instant = Annotated[float, Field(ge=0, le=1e4, **_quantity("time"))]


def _about(symbol: str | dict | None = None, **extra: Any) -> dict:
    """A field's schema keys for the page: the paper's `symbol` and any other (see above)."""
    return {"json_schema_extra": {"symbol": symbol, **extra} if symbol is not None else extra}


# Every input model's: an unknown field, a number that is not finite, and a boolean or a string
# where a number is expected ("mass": true, "mass": "2") are refused, naming the field, rather
# than read as 1 kg or 2 kg.
INPUT = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


def _whole(value: Any) -> Any:
    """A whole number written as a float (100.0, as many JSON writers print it) as the int it is."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


Whole = Annotated[int, BeforeValidator(_whole)]  # an int field's type: strict, yet 100.0 is 100


class _Model(BaseModel):
    model_config = INPUT


def field_error(model: str, loc: tuple, message: str, value: Any) -> ValidationError:
    """A validation error attached to `loc` below the model being validated."""
    detail = InitErrorDetails(type=PydanticCustomError("value_error", message), loc=loc, input=value)
    return ValidationError.from_exception_data(model, [detail])


def increasing(values: list[float], message: str) -> list[float]:
    """`values` if each is greater than the one before; else the error `message` (its {i}, {j},
    {a}, {b}: the first pair out of order, by index and value)."""
    for i in range(1, len(values)):
        if values[i] <= values[i - 1]:
            raise PydanticCustomError("value_error", message, {"i": i, "j": i - 1, "a": values[i - 1], "b": values[i]})
    return values


class Profile(_Model):
    """Piecewise-linear cross-section `S(x)`: stations `x` (m, from the struck end) and areas (m²)."""

    x: list[float] = Field(min_length=2, **_quantity("length"))
    area: list[Area] = Field(min_length=2)

    @field_validator("x")
    @classmethod
    def _increasing(cls, x: list[float]) -> list[float]:
        if x[0] != 0.0:
            raise PydanticCustomError("value_error", "x[0] must be 0 (the struck end, or a striker's impact face)")
        return increasing(x, "must be strictly increasing: x[{i}] = {b} is not greater than x[{j}] = {a}")

    @model_validator(mode="after")
    def _same_length(self) -> Profile:
        if len(self.area) != len(self.x):
            raise field_error(
                "Profile",
                ("area",),
                f"must have one area per station: {len(self.area)} areas for {len(self.x)} stations",
                self.area,
            )
        return self


class Tool(_Model):
    """The tool: an elastic rod of length `L`, modulus `E`, density `ρ`, area `S(x)`.

    Give either a uniform `area` or a piecewise-linear `profile`.
    """

    length: Length = Field(**_about("L"))
    youngs_modulus: Modulus = Field(title="Young's modulus", **_about("E"))
    density: Density = Field(**_about("ρ"))
    area: Area | None = Field(None, **_about("S"))
    profile: Profile | None = None

    @model_validator(mode="after")
    def _one_shape(self) -> Tool:
        _check_shape(self, "tool")
        return self


def _check_shape(rod: Tool | Striker, name: str) -> None:
    """A rod has a uniform `area` or a `profile` whose last station is its length."""
    if (rod.area is None) == (rod.profile is None):
        raise field_error(name, ("area",), f"give exactly one of {name}.area (uniform) or {name}.profile", rod.area)
    if rod.profile is not None:
        last = rod.profile.x[-1]
        if abs(last - rod.length) > 1e-9 * rod.length:
            raise field_error(
                name,
                ("profile", "x", len(rod.profile.x) - 1),
                f"the last station must equal {name}.length = {rod.length} m",
                last,
            )


class Striker(_Model):
    """The striker at its pre-impact velocity `W1` (m/s, + toward the tool), or a ram falling its
    `stroke` (m), which strikes at `√(2·g·efficiency·stroke)` (efficiency 1 when not given):
    lumped, of mass `m1` (kg), or an elastic rod (a piston) of `length`, `youngs_modulus`,
    `density` and a uniform `area` or a `profile` (stations from its impact face, the end that
    meets the tool)."""

    velocity: Speed | None = Field(None, title="Impact velocity", **_about("W₁"))
    stroke: Annotated[float, Field(gt=0, le=1e3, **_quantity("length"))] | None = Field(
        None, title="Stroke (a falling ram)", **_about("h")
    )
    efficiency: Annotated[float, Field(gt=0.0, le=1.0)] | None = Field(
        None, title="Efficiency of the fall", **_about("η", quantity="dimensionless", implied=1.0)
    )
    mass: Mass | None = Field(None, **_about("m₁"))
    length: Length | None = None
    youngs_modulus: Modulus | None = Field(None, title="Young's modulus", **_about("E"))
    density: Density | None = Field(None, **_about("ρ"))
    area: Area | None = Field(None, **_about("S"))
    profile: Profile | None = None

    @model_validator(mode="after")
    def _velocity_or_stroke(self) -> Striker:
        if self.velocity is not None and self.stroke is not None:
            raise field_error(
                "Striker",
                ("stroke",),
                f"cannot be given with striker.velocity = {self.velocity} m/s: a falling ram strikes at "
                "√(2·g·efficiency·stroke); give striker.velocity or striker.stroke",
                self.stroke,
            )
        if self.velocity is None and self.stroke is None:
            raise field_error(
                "Striker", ("velocity",), "is required, unless the striker is a ram falling its striker.stroke", None
            )
        if self.stroke is None and self.efficiency is not None:
            raise field_error(
                "Striker",
                ("efficiency",),
                "belongs to a falling ram (striker.stroke), not a given velocity",
                self.efficiency,
            )
        return self

    def impact_velocity(self, gravity: float = STANDARD_GRAVITY) -> float:
        """W1: the velocity given, or a falling ram's `√(2·g·efficiency·stroke)` (m/s)."""
        if self.velocity is not None:
            return self.velocity
        efficiency = 1.0 if self.efficiency is None else self.efficiency
        return math.sqrt(2.0 * gravity * efficiency * self.stroke)

    @model_validator(mode="after")
    def _lumped_or_rod(self) -> Striker:
        if self.mass is not None and self.length is not None:
            raise field_error(
                "Striker",
                ("mass",),
                "cannot be given with striker.length: striker.mass makes a lumped striker, "
                "striker.length an elastic rod; give one of them",
                self.mass,
            )
        if self.mass is None and self.length is None:
            raise field_error(
                "Striker",
                ("mass",),
                "is required (a lumped striker), unless the striker is an elastic rod "
                "(striker.length, youngs_modulus, density and area or profile)",
                None,
            )
        rod_fields = ("youngs_modulus", "density", "area", "profile")
        if self.mass is not None:
            for name in rod_fields:
                if getattr(self, name) is not None:
                    raise field_error(
                        "Striker",
                        (name,),
                        "belongs to an elastic striker (with striker.length), not a lumped one (striker.mass)",
                        getattr(self, name),
                    )
            return self
        for name in ("youngs_modulus", "density"):
            if getattr(self, name) is None:
                raise field_error("Striker", (name,), "is required for an elastic striker (striker.length)", None)
        _check_shape(self, "striker")
        return self

    @property
    def elastic(self) -> bool:
        """Whether the striker is an elastic rod (else lumped)."""
        return self.length is not None

    def rod(self) -> Tool:
        """The elastic striker as a rod (its x from the impact face)."""
        return Tool(
            length=self.length,
            youngs_modulus=self.youngs_modulus,
            density=self.density,
            area=self.area,
            profile=self.profile,
        )


class Contact(_Model):
    """Striker–tool contact (7): `G(δ) = c1·δ^α` for δ ≥ 0, `c0` for δ < 0; damper `b1`.

    The contact force on the tool is `G(δ)·δ + b1·δ'`; α = 0.5 is Hertz-like (c1 in N/m^1.5).
    A cushion (`restitution` e < 1) loads along that law and unloads along one of the same power,
    stiffer, from the deepest overlap: continuous there, it gives back e² of what it stored.
    """

    stiffness: Annotated[Stiffness, Field(gt=0)] = Field(**_about("c₁", quantity="contact_stiffness"))
    exponent: float = Field(ge=0.0, le=0.5, **_about("α", quantity="dimensionless"))
    tension_stiffness: Stiffness = Field(0.0, title="Stiffness in tension", **_about("c₀"))
    damping: Damping = Field(0.0, **_about("b₁"))
    restitution: float = Field(
        1.0, gt=0.0, le=1.0, title="Coefficient of restitution", **_about("e", quantity="dimensionless")
    )


class Signal(_Model):
    """A history given at instants (a measured one): `time` (s, increasing) and its `values`,
    linear between them."""

    time: list[Annotated[float, Field(ge=-1e4, le=1e4)]] = Field(
        min_length=2, max_length=1_000_000, **_quantity("time")
    )
    values: list[Annotated[float, Field(ge=-1e12, le=1e12)]] = Field(min_length=2, max_length=1_000_000)

    @field_validator("time")
    @classmethod
    def _increasing(cls, time: list[float]) -> list[float]:
        return increasing(time, "must increase: time[{i}] = {b} s is not after time[{j}] = {a} s")

    @model_validator(mode="after")
    def _same_length(self) -> Signal:
        if len(self.values) != len(self.time):
            raise field_error(
                "Signal",
                ("values",),
                f"must have one value per instant: {len(self.values)} values for {len(self.time)} instants",
                len(self.values),
            )
        return self

    def width(self) -> float:
        """The time (s) the history spends at or above half its largest magnitude: its pulse's
        length, the time scale a grid must resolve."""
        t, v = np.asarray(self.time), np.abs(np.asarray(self.values))
        if not v.max() > 0.0:
            return float(t[-1] - t[0])
        above = np.flatnonzero(v >= 0.5 * v.max())
        return float(max(t[above[-1]] - t[above[0]], np.min(np.diff(t))))


class StruckEnd(_Model):
    """The struck end driven by a given history instead of a striker, as a measured signal would
    be: its `force` (N, compression positive) or its `velocity` (m/s, toward the working end
    positive); from the history's end on, the end is free."""

    force: Signal | None = None
    velocity: Signal | None = None

    @model_validator(mode="after")
    def _one_history(self) -> StruckEnd:
        if (self.force is None) == (self.velocity is None):
            raise field_error(
                "StruckEnd",
                ("force",),
                "give the struck end's force or its velocity (one of them)",
                None,
            )
        return self

    @property
    def driver(self) -> tuple[str, Signal]:
        """The quantity the struck end is driven by ('force' or 'velocity') and its history."""
        return ("force", self.force) if self.force is not None else ("velocity", self.velocity)


class Gravity(_Model):
    """Weight along the tool, from the struck end toward the working end (a vertical pile: 9.81):
    the tool, the anvil and the striker have weight, and the run starts from the tool and the
    anvil at rest on the soil (`shaft` and `medium`) under it."""

    acceleration: Annotated[float, Field(gt=0.0, le=1e3)] = Field(
        title="Acceleration of gravity", **_about("g", quantity="acceleration")
    )


class Anvil(_Model):
    """A lumped body between the striker and the tool (an anvil, an adapter, the paper's second
    striker): `mass` (kg), `velocity` (m/s at impact) and its `contact` with the tool; the case's
    `contact` is then the striker's with the anvil."""

    mass: Mass
    velocity: Speed = Field(0.0, title="Velocity at impact")
    contact: Contact


MEDIUM_FIELDS = {
    "linear": ("stiffness", "damping"),
    "bilinear": ("stiffness", "unloading_stiffness", "damping"),
    "smith": ("ultimate_resistance", "quake", "damping_factor"),
}
MEDIUM_REQUIRED = {
    "linear": ("stiffness",),
    "bilinear": ("stiffness", "unloading_stiffness"),
    "smith": ("ultimate_resistance", "quake"),
}


class Medium(_Model):
    """Working medium at x = L (4), pressed by the tool's working end (penetration u_N ≥ 0):

    - `linear`: spring `c2` (N/m) and damper `b2` (N·s/m), as in the paper;
    - `bilinear`: rock (Lundberg): `stiffness` k while loading, `unloading_stiffness` k_u ≥ k,
      damper `damping`; the penetration left when the force is off is permanent, and the medium
      does not pull;
    - `smith`: soil at a pile's toe (Smith): static resistance `R_s`, elastic–perfectly plastic up
      to `ultimate_resistance` R_u (N) at `quake` q (m), unloading with the same stiffness R_u/q,
      times `(1 + J·v)` with the `damping_factor` J (s/m); it does not pull.
    """

    # The page shows a medium's fields, and writes them, as its kind has them.
    model_config = ConfigDict(json_schema_extra={"kind_fields": MEDIUM_FIELDS})

    kind: Literal["linear", "bilinear", "smith"] = Field(
        "linear",
        **_about(
            choices={
                "linear": "linear: spring and damper",
                "bilinear": "bilinear: rock (Lundberg)",
                "smith": "Smith: soil at a pile's toe",
            }
        ),
    )
    stiffness: Stiffness | None = Field(None, **_about({"linear": "c₂", "bilinear": "k"}))
    damping: Damping = Field(0.0, **_about("b₂"))
    unloading_stiffness: Stiffness | None = Field(None, title="Unloading stiffness", **_about("kᵤ"))
    ultimate_resistance: Annotated[float, Field(gt=0, le=1e12, **_quantity("force"))] | None = Field(
        None, title="Ultimate resistance", **_about("Rᵤ")
    )
    quake: Annotated[float, Field(gt=0, le=1.0, **_quantity("length"))] | None = Field(None, **_about("q"))
    damping_factor: Annotated[float, Field(ge=0, le=1e3, **_quantity("slowness"))] = Field(
        0.0, title="Damping factor", **_about("J")
    )

    @model_validator(mode="after")
    def _fields_of_kind(self) -> Medium:
        allowed = MEDIUM_FIELDS[self.kind]
        for name, spec in type(self).model_fields.items():
            value = getattr(self, name)
            # given: a value other than the field's default (a stored case spells out defaults)
            if name != "kind" and value is not None and value != spec.default and name not in allowed:
                raise field_error(
                    "Medium",
                    (name,),
                    f"is not a field of a {self.kind} medium (its fields: {', '.join(allowed)})",
                    getattr(self, name),
                )
        for name in MEDIUM_REQUIRED[self.kind]:
            if getattr(self, name) is None:
                raise field_error("Medium", (name,), f"is required for a {self.kind} medium", None)
        if self.kind == "bilinear" and self.unloading_stiffness < self.stiffness:
            raise field_error(
                "Medium",
                ("unloading_stiffness",),
                f"must be ≥ medium.stiffness = {self.stiffness:.6g} N/m: rock unloads at least as stiffly as it loads",
                self.unloading_stiffness,
            )
        return self

    @property
    def loading_stiffness(self) -> float:
        """The medium's stiffness while it is loaded (N/m): c2, k, or R_u/q."""
        if self.kind == "smith":
            return self.ultimate_resistance / self.quake
        return self.stiffness


class ShaftSegment(_Model):
    """Soil on the tool's side from `from` to `to` (m from the struck end): Smith's law as at the
    toe (`medium.kind = 'smith'`), made two-sided (the soil slips both ways), its
    `ultimate_resistance` spread evenly over the segment's length and acting at each section
    against that section's displacement and velocity."""

    model_config = ConfigDict(**INPUT, validate_by_alias=True, validate_by_name=False, serialize_by_alias=True)

    start: Annotated[float, Field(ge=0, le=1e4, **_quantity("length"))] = Field(alias="from", title="From")
    end: Annotated[float, Field(gt=0, le=1e4, **_quantity("length"))] = Field(alias="to", title="To")
    ultimate_resistance: Annotated[float, Field(gt=0, le=1e12, **_quantity("force"))] = Field(
        title="Ultimate resistance", **_about("Rᵤ")
    )
    quake: Annotated[float, Field(gt=0, le=1.0, **_quantity("length"))] = Field(**_about("q"))
    damping_factor: Annotated[float, Field(ge=0, le=1e3, **_quantity("slowness"))] = Field(
        0.0, title="Damping factor", **_about("J")
    )

    @model_validator(mode="after")
    def _ordered(self) -> ShaftSegment:
        if self.end <= self.start:
            raise field_error("ShaftSegment", ("to",), f"must be greater than from = {self.start} m", self.end)
        return self


class Blows(_Model):
    """Blow after blow: `count` blows of `numerics.duration` each."""

    count: Whole = Field(ge=1, le=1000, description="how many blows", title="Number of blows", **_about(implied=1))


Pressure = Annotated[float, Field(ge=0, le=1e10, **_quantity("stress"))]


class Accumulator(_Model):
    """A gas accumulator on the supply line: `p·V_gas^n = precharge·volume^n`."""

    volume: Annotated[float, Field(gt=0, le=1.0, **_quantity("volume"))] = Field(title="Gas volume", **_about("V₀"))
    precharge: Annotated[float, Field(gt=0, le=1e10, **_quantity("stress"))] = Field(
        title="Precharge pressure", **_about("p₀")
    )
    polytropic_exponent: float = Field(1.4, ge=1.0, le=1.67, title="Polytropic exponent", **_about("n"))


class AdaptiveControl(_Model):
    """After each blow the next stroke moves toward the one that gives `target_set` a blow, within
    `min_stroke` and `max_stroke` (harder rock, longer stroke)."""

    kind: Literal["adaptive"] = Field(**_about(choices={"adaptive": "adaptive stroke"}))
    target_set: Annotated[float, Field(gt=0, le=1.0, **_quantity("length"))] = Field(title="Target set a blow")
    min_stroke: Length = Field(title="Shortest stroke")
    max_stroke: Length = Field(title="Longest stroke")


class HydraulicDrive(_Model):
    """A differential piston: the front area always at the supply pressure (it returns the
    striker), the rear area switched by the valve to supply when the striker, on its way back,
    passes `stroke` from the impact point, and to return at impact."""

    kind: Literal["hydraulic"] = Field(**_about(choices={"hydraulic": "hydraulic: a differential piston"}))
    supply_pressure: Annotated[float, Field(gt=0, le=1e10, **_quantity("stress"))] = Field(**_about("p_s"))
    return_pressure: Pressure = Field(0.0, **_about("p_r"))
    front_area: Area = Field(**_about("A_f"))
    rear_area: Area = Field(**_about("A_r"))
    stroke: Length = Field(**_about("s"))
    valve_time: Annotated[float, Field(ge=0, le=1.0, **_quantity("time"))] = Field(0.0, title="Valve switching time")
    flow: Annotated[float, Field(gt=0, le=10.0, **_quantity("flow"))] | None = Field(
        None, title="Pump flow", **_about("Q")
    )
    accumulator: Accumulator | None = None
    friction: Annotated[float, Field(ge=0, le=1e9, **_quantity("force"))] = Field(0.0, **_about("F_f"))
    control: AdaptiveControl | None = None

    @model_validator(mode="after")
    def _works(self) -> HydraulicDrive:
        if self.rear_area <= self.front_area:
            raise field_error(
                "HydraulicDrive",
                ("rear_area",),
                f"must be larger than front_area = {self.front_area} m²: with the rear on supply the net push "
                "toward the tool is (rear_area − front_area)·supply_pressure, so the piston would never work",
                self.rear_area,
            )
        if self.supply_pressure <= self.return_pressure:
            raise field_error(
                "HydraulicDrive",
                ("supply_pressure",),
                f"must be above return_pressure = {self.return_pressure} Pa: the front's pull returns the "
                "striker only then",
                self.supply_pressure,
            )
        if self.flow is not None and self.accumulator is None:
            raise field_error(
                "HydraulicDrive",
                ("accumulator",),
                "is needed with a pump's flow: the gas buffers the supply; without either the supply holds "
                "its pressure",
                None,
            )
        if self.accumulator is not None and self.accumulator.precharge >= self.supply_pressure:
            raise field_error(
                "HydraulicDrive",
                ("accumulator", "precharge"),
                f"must be below supply_pressure = {self.supply_pressure} Pa: the gas is compressed by the supply",
                self.accumulator.precharge,
            )
        return self


class Cycles(_Model):
    """A hammer at work: `count` cycles, each a return stroke, a work stroke and a blow."""

    count: Whole = Field(ge=1, le=10_000, description="how many work cycles", title="Number of cycles")


class SineForce(_Model):
    """External force on the striker `R(t) = P·sin(ωt)`."""

    kind: Literal["sine"] = Field(**_about(choices={"sine": "R = P·sin(ωt)"}))
    amplitude: ForceAmplitude = Field(**_about("P"))
    omega: Frequency = Field(title="Angular frequency", **_about("ω"))


class AbsSineForce(_Model):
    """External force on the striker `R(t) = P·|sin(ωt)|`."""

    kind: Literal["abs_sine"] = Field(**_about(choices={"abs_sine": "R = P·|sin(ωt)|"}))
    amplitude: ForceAmplitude = Field(**_about("P"))
    omega: Frequency = Field(title="Angular frequency", **_about("ω"))


class PulseForce(_Model):
    """External force on the striker `R(t) = P` for `t1 ≤ t ≤ t1 + Δt`, else 0."""

    kind: Literal["pulse"] = Field(**_about(choices={"pulse": "R = P for t₁ ≤ t ≤ t₁ + Δt"}))
    amplitude: ForceAmplitude = Field(**_about("P"))
    start: Instant = Field(0.0, **_about("t₁"))
    duration: Duration = Field(**_about("Δt"))


Force = Annotated[SineForce | AbsSineForce | PulseForce, Field(discriminator="kind")]


class Numerics(_Model):
    """Time span and accuracy. With only `duration` the case is solved to the default accuracy, as
    if `tolerance` were 0.01: the solver chooses the scheme and the grid and estimates its error.
    Giving `cells`, `time_step` or `scheme` runs that fixed grid instead (the paper's scheme unless
    another is named), its error estimated from two coarser companion runs."""

    duration: Duration = Field(title="Duration of the run", **_about("T"))
    time_step: Duration | None = Field(
        default=None,
        description="τ (s) of a fixed grid; default from the case itself",
        title="Time step",
        **_about("τ"),
    )
    cells: Whole | None = Field(  # the service limits are far lower than the bound
        default=None,
        ge=1,
        le=2**31,
        description="N = L/h of a fixed grid; default 100 once a grid is asked",
        **_about("N", implied=100),
    )
    tolerance: float | None = Field(
        default=None,
        ge=1e-5,
        le=0.2,
        description="relative accuracy asked on every headline quantity (co-impact time, peak "
        "contact force, maximum compressive and tensile stress, energy to the medium, "
        "rebound velocity, transfer efficiency); the solver chooses the grid and reports "
        "its error estimate. Default 0.01 when numerics gives no cells, time_step or scheme",
        **_about(quantity="ratio", implied=0.01),
    )
    scheme: Literal["paper", "sigma", "explicit"] | None = Field(
        default=None,
        description="a fixed grid's scheme: 'paper', the weighted scheme (8) with γ (first order); "
        "'sigma', the symmetric σ-scheme (second order, energy-conserving); 'explicit', "
        "central differences (second order, Courant number a·τ/h ≤ 1; at 1, its default, "
        "exact along a uniform tool, with ends that integrate their own equations). "
        "Default 'paper' when a grid is given; chosen by the solver otherwise",
        **_about(choices={"paper": "paper: weighted (8), γ", "sigma": "sigma: symmetric, σ", "explicit": "explicit"}),
    )
    gamma: float = Field(
        default=0.5,
        le=1.0,
        description="weight γ of the new time layer in the paper's scheme (8); 0.5 ≤ γ ≤ 1",
        title="Weight of the new layer",
        # the lower bound is _implicit_enough's, which names the reason
        **_about("γ", quantity="dimensionless", minimum=0.5),
    )
    sigma: float = Field(
        default=0.25,
        le=1.0,
        description="weight σ of layers n±1 in the σ-scheme; 1/4 ≤ σ ≤ 1",
        title="Weight of layers n±1",
        **_about("σ", quantity="dimensionless", minimum=0.25),  # the lower bound is _sigma_stable's
    )
    end_masses: bool | None = Field(
        default=None,
        description="keep the half-cell mass at each end of the tool (second-order end conditions); "
        "default: yes for 'sigma' and 'explicit', no for 'paper' (its massless ends (9), (10))",
        title="End masses",
        **_about(choices={"true": "kept (second order)", "false": "massless ends"}),
    )
    model: Literal["rod", "lumped"] | None = Field(
        default=None,
        description="'rod': the tool as an elastic rod (8)–(13), the default; 'lumped': the two-mass "
        "model problem (21)–(25), its modelling error estimated as ε²",
        title="Tool model",
        **_about(choices={"rod": "elastic rod", "lumped": "two masses (21)–(25)"}),
    )

    @field_validator("gamma")
    @classmethod
    def _implicit_enough(cls, gamma: float) -> float:
        if gamma < 0.5:
            raise PydanticCustomError(
                "value_error",
                "must be ≥ 0.5: the weighted scheme is only stable for every time step when "
                "γ ≥ 1/2; for an explicit scheme use numerics.scheme = 'explicit'",
            )
        return gamma

    @field_validator("sigma")
    @classmethod
    def _sigma_stable(cls, sigma: float) -> float:
        if sigma < 0.25:
            raise PydanticCustomError(
                "value_error",
                "must be ≥ 0.25: the σ-scheme is stable for every time step only when σ ≥ 1/4; "
                "for σ = 0 use numerics.scheme = 'explicit'",
            )
        return sigma

    @model_validator(mode="after")
    def _tolerance_or_grid(self) -> Numerics:
        if self.tolerance is not None:
            given = [name for name in ("time_step", "cells") if getattr(self, name) is not None]
            if given:
                raise field_error(
                    "Numerics",
                    ("tolerance",),
                    f"cannot be combined with numerics.{given[0]}: under a tolerance the solver "
                    "chooses the grid; give one or the other",
                    self.tolerance,
                )
        return self


class Outputs(_Model):
    """What to keep beyond the summary: probe stations, full fields, and their sampling strides."""

    probes: list[float] = Field(
        default_factory=list, description="stations x (m) for stress histories", **_quantity("length")
    )
    history_stride: Whole = Field(
        default=1, ge=1, description="keep every k-th step in the histories", title="History stride"
    )
    fields: bool = Field(
        default=False, description="keep displacement and stress along the tool", title="Fields along the tool"
    )
    field_stride: Whole = Field(
        default=10, ge=1, description="keep every k-th step in the fields", title="Field stride"
    )


SUMMARY_ONLY = Outputs(history_stride=2**62)
"""What a run read for its summary alone keeps: no probes, no fields, no history beyond its first
step (the summary's extremes, contacts and energies are observed as the run goes)."""


class Case(_Model):
    """One impact case: striker, tool, contact, optional anvil, medium, force and blows, numerics,
    outputs."""

    name: str = "case"
    description: str | None = None
    striker: Striker | None = None
    tool: Tool
    contact: Contact | None = None
    struck_end: StruckEnd | None = None
    anvil: Anvil | None = None
    medium: Medium | None = None
    shaft: list[ShaftSegment] | None = Field(None, min_length=1)
    gravity: Gravity | None = None
    force: Force | None = None
    blows: Blows | None = None
    drive: HydraulicDrive | None = None
    cycles: Cycles | None = None
    numerics: Numerics
    outputs: Outputs = Field(default_factory=Outputs)

    @model_validator(mode="after")
    def _struck_by_a_striker_or_a_history(self) -> Case:
        """A striker and its contact strike the tool, or a given history drives its struck end
        (`struck_end`), which then leaves no striker, contact, anvil or R(t) to act."""
        if self.struck_end is None:
            for name in ("striker", "contact"):
                if getattr(self, name) is None:
                    raise field_error(
                        "Case", (name,), "is required, unless a history drives the struck end (struck_end)", None
                    )
            return self
        if self.striker is not None:
            raise field_error(
                "Case",
                ("struck_end",),
                "cannot be given with a striker: a history drives the struck end instead of a striker; "
                "leave striker and contact out, or struck_end",
                self.struck_end.driver[0],
            )
        for name in ("contact", "anvil", "force"):
            if getattr(self, name) is not None:
                raise field_error(
                    "Case",
                    (name,),
                    "has nothing to act on: a history drives the struck end (struck_end), with no striker",
                    None,
                )
        return self

    @model_validator(mode="after")
    def _a_hammer_at_work(self) -> Case:
        """`cycles` run a `drive`, each the other's; they exclude `blows`, and an adaptive stroke
        needs a medium whose set it reads."""
        if self.cycles is not None and self.blows is not None:
            raise field_error(
                "Case",
                ("cycles",),
                "cannot be given with blows: cycles run their blows (a return stroke, a work stroke and a blow "
                "each); give one of them",
                self.cycles.count,
            )
        if (self.cycles is None) != (self.drive is None):
            given, missing = ("cycles", "drive") if self.drive is None else ("drive", "cycles")
            raise field_error(
                "Case", (missing,), f"is required with {given}: a drive works the striker cycle after cycle", None
            )
        if self.drive is not None and self.striker is None:
            raise field_error("Case", ("drive",), "drives a striker: give striker, not struck_end", None)
        if self.cycles is not None:
            # between blows the tool rests on the medium, unloaded (`kernel.rest_tool`): a rest that
            # holds forces in the tool (its weight, a shaft's residual load) is not modelled
            if self.medium is None:
                raise field_error(
                    "Case", ("medium",), "is required with cycles: between blows the tool rests on it", None
                )
            for name, value in (("gravity", self.gravity), ("shaft", self.shaft)):
                if value:
                    raise field_error(
                        "Case",
                        (name,),
                        "cannot be given with cycles: between blows the tool comes to rest on the medium "
                        "unloaded, and a rest under the tool's weight or a shaft's load is not modelled; "
                        "give blows instead",
                        None,
                    )
        control = self.drive.control if self.drive is not None else None
        if control is not None and not self.medium_yields:
            raise field_error(
                "Case",
                ("drive", "control"),
                "sets the stroke from the set a blow: it needs a medium that yields (medium.kind 'bilinear' or "
                "'smith')",
                control.kind,
            )
        return self

    @model_validator(mode="after")
    def _probes_on_tool(self) -> Case:
        for i, x in enumerate(self.outputs.probes):
            if not 0.0 <= x <= self.tool.length:
                raise field_error(
                    "Case",
                    ("outputs", "probes", i),
                    f"must lie on the tool, 0 ≤ x ≤ tool.length = {self.tool.length} m",
                    x,
                )
        return self

    @model_validator(mode="after")
    def _shaft_on_tool(self) -> Case:
        """Segments lie on the tool and do not overlap."""
        for i, segment in enumerate(self.shaft or []):
            if segment.end > self.tool.length:
                raise field_error(
                    "Case",
                    ("shaft", i, "to"),
                    f"must lie on the tool, ≤ tool.length = {self.tool.length} m",
                    segment.end,
                )
        ordered = sorted(enumerate(self.shaft or []), key=lambda item: item[1].start)
        for (_, before), (i, segment) in zip(ordered, ordered[1:]):
            if segment.start < before.end:
                raise field_error(
                    "Case",
                    ("shaft", i, "from"),
                    f"overlaps the segment from {before.start} m to {before.end} m: segments do not overlap",
                    segment.start,
                )
        return self

    @model_validator(mode="after")
    def _gravity_supported(self) -> Case:
        """Under gravity the tool and the anvil must rest on the soil: a medium that holds any
        load (linear, rock), or a shaft and Smith toe whose ultimate resistances exceed their weight."""
        if self.gravity is None:
            return self
        from .grid import tool_mass  # grid reads the case's models

        g = self.gravity.acceleration
        weight = (tool_mass(self.tool) + (self.anvil.mass if self.anvil else 0.0)) * g
        medium = self.medium
        if medium is not None and medium.kind != "smith" and medium.loading_stiffness > 0:
            return self
        capacity = sum(s.ultimate_resistance for s in self.shaft or []) + (
            medium.ultimate_resistance if medium is not None and medium.kind == "smith" else 0.0
        )
        if weight >= capacity:
            raise field_error(
                "Case",
                ("gravity",),
                f"the tool{' and the anvil' if self.anvil else ''} weigh {weight:.6g} N, more than the soil "
                f"holds ({capacity:.6g} N: the shaft's and the toe's ultimate resistances): nothing would "
                "stop the fall; give the medium or the shaft more resistance, or leave gravity out",
                self.gravity.acceleration,
            )
        return self

    @model_validator(mode="after")
    def _force_on_a_lumped_striker(self) -> Case:
        if self.force is not None and self.elastic_striker:
            raise field_error(
                "Case",
                ("force",),
                "acts on a lumped striker (striker.mass); an elastic striker (striker.length) is "
                "driven by its velocity at impact only",
                self.force.kind,
            )
        return self

    @property
    def impact_velocity(self) -> float:
        """W1 (m/s): the striker's given velocity, or its fall's (under the case's gravity); 0
        with no striker (a history drives the struck end)."""
        if self.striker is None:
            return 0.0
        if self.gravity is None:
            return self.striker.impact_velocity()
        return self.striker.impact_velocity(self.gravity.acceleration)

    @property
    def blows_run(self) -> int:
        """How many blows a run has: its `blows`, or one a work cycle (`cycles`), else one."""
        if self.cycles is not None:
            return self.cycles.count
        return self.blows.count if self.blows else 1

    @property
    def medium_yields(self) -> bool:
        """Whether the medium yields (rock or soil: a set a blow)."""
        return self.medium is not None and self.medium.kind != "linear"

    @property
    def elastic_striker(self) -> bool:
        """Whether an elastic striker (a rod) strikes the tool."""
        return self.striker is not None and self.striker.elastic

    @property
    def beyond_paper(self) -> list[str]:
        """The fields that ask for more than the paper's model (a lumped striker, no anvil, a
        linear medium, one blow), which only the ends that integrate their own equations take."""
        fields = []
        if self.struck_end is not None:
            fields.append("struck_end")
        if self.elastic_striker:
            fields.append("striker.length")
        if self.anvil is not None:
            fields.append("anvil")
        if self.medium_yields:
            fields.append("medium.kind")
        if self.blows is not None and self.blows.count > 1:
            fields.append("blows.count")
        if self.shaft:
            fields.append("shaft")
        if self.gravity is not None:
            fields.append("gravity")
        if self.cycles is not None:
            fields.append("cycles")
        if self.contact is not None and self.contact.restitution < 1.0:
            fields.append("contact.restitution")
        if self.anvil is not None and self.anvil.contact.restitution < 1.0:
            fields.append("anvil.contact.restitution")
        return fields

    def summary_only(self) -> Case:
        """The case keeping only what its summary needs (`SUMMARY_ONLY`)."""
        return self.model_copy(update={"outputs": SUMMARY_ONLY})


class FieldError(BaseModel):
    """One reason a case was refused, with the dotted path of the field it concerns."""

    field: str
    message: str


class CaseError(ValueError):
    """A case that cannot be solved; `errors` names each offending field."""

    def __init__(self, errors: list[FieldError]):
        self.errors = errors
        super().__init__("; ".join(f"{e.field}: {e.message}" for e in errors))

    def __reduce__(self):
        # rebuilt from its errors, not its message: a pool's worker hands it back pickled
        return CaseError, (self.errors,)


_MESSAGES = {
    "missing": "is required",
    "extra_forbidden": "is not a known field",
    "greater_than": "must be > {gt}",
    "greater_than_equal": "must be ≥ {ge}",
    "less_than": "must be < {lt}",
    "less_than_equal": "must be ≤ {le}",
    "finite_number": "must be a finite number",
    "float_parsing": "must be a number",
    "float_type": "must be a number",
    "int_parsing": "must be a whole number",
    "int_type": "must be a whole number",
    "int_from_float": "must be a whole number",
    "bool_type": "must be true or false",
    "string_type": "must be a string",
    "too_short": "must have at least {min_length} entries",
    "list_type": "must be a list",
    "model_type": "must be an object",
    "model_attributes_type": "must be an object",
    "union_tag_invalid": "kind must be one of {expected_tags}",
    "union_tag_not_found": "needs a 'kind' ({discriminator})",
}


_WRONG_TYPE = {"float_type", "int_type", "bool_type", "string_type"}


def _as_json(value: bool | str) -> str:
    if isinstance(value, bool):
        return json.dumps(value)
    text = json.dumps(value if len(value) <= 40 else value[:37] + "...", ensure_ascii=False)
    return f"the string {text}"


def field_path(loc: tuple) -> str:
    """('tool', 'profile', 'area', 2) -> 'tool.profile.area[2]'."""
    path = ""
    for part in loc:
        if isinstance(part, int):
            path += f"[{part}]"
        else:
            path += ("." if path else "") + str(part)
    return path or "case"


def describe_errors(error: ValidationError) -> list[FieldError]:
    """Pydantic's errors as field paths and reasons an engineer reads."""
    return describe(error.errors(include_url=False))


def describe(errors: list[dict]) -> list[FieldError]:
    """Pydantic's error entries (`type`, `loc` below the model, `msg`, `ctx`) as field paths and
    reasons an engineer reads."""
    described = []
    for e in errors:
        template = _MESSAGES.get(e["type"])
        message = template.format(**e.get("ctx", {})) if template else e["msg"]
        if e["type"] in _WRONG_TYPE and isinstance(e.get("input"), (bool, str)):
            message += f", not {_as_json(e['input'])}"  # what was sent: `true`, the string "2"
        # A discriminated union adds the chosen kind to the path ("force.pulse.duration").
        loc = tuple(p for p in e["loc"] if p not in ("sine", "abs_sine", "pulse"))
        described.append(FieldError(field=field_path(loc), message=message))
    return described


def validated(model: type[_M], data: Any, field: str = "") -> _M:
    """`data` (JSON as Python) validated as `model`; `CaseError` names each bad field, under
    `field` when given (a record's `time[3]` as `record.time[3]`)."""
    try:
        return model.model_validate(data)
    except ValidationError as error:
        raise CaseError(
            [
                FieldError(field=f"{field}.{e.field}" if field else e.field, message=e.message)
                for e in describe_errors(error)
            ]
        ) from None


def parse_case(data: dict | str | bytes) -> Case:
    """Validate a case given as a dict or JSON text; raise `CaseError` naming each bad field."""
    try:
        if isinstance(data, (str, bytes)):
            return Case.model_validate_json(data)
        return Case.model_validate(data)
    except ValidationError as error:
        raise CaseError(describe_errors(error)) from None


def as_case(case: Case | dict | str | os.PathLike) -> Case:
    """A case given as a `Case`, as case JSON in a dict, or as the path of a case JSON file."""
    if isinstance(case, Case):
        return case
    if isinstance(case, dict):
        return parse_case(case)
    return load_case(case)


def load_case(path: str | os.PathLike) -> Case:
    """Read and validate a case JSON file."""
    text = Path(path).read_text()
    _decoded(text)
    return parse_case(text)


def read_case_json(path: str | os.PathLike) -> dict:
    """A case JSON file's contents, not yet validated (a signal match's pile has no striker);
    `CaseError` when it is not JSON."""
    return _decoded(Path(path).read_text())


def _decoded(text: str) -> Any:
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise CaseError([FieldError(field="case", message=f"is not valid JSON: {error}")]) from None
