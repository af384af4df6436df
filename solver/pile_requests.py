"""What the pile engineer's studies ask, and the cases they run: the bearing graph and the inspector's
chart (`BearingGraph`: a pile case and its capacities, or its ram's strokes), and the drivability
(`Drivability`: a pile case and its `Soil`, layer by layer). Every variant is a case of its own,
validated and checked against the limits before anything runs, a refusal naming the request's field
it came from. Neither the kernel nor SciPy is loaded by importing this module, so that the service
checks a request as cheaply as a case.

The bearing graph's capacity R_u is the pile's whole ultimate resistance: the toe (`medium`, Smith
soil) takes S·R_u and the shaft's segments (1 − S)·R_u between them, each in its share of the
case's own shaft resistance; S is `toe_share`, by default the case's own share (its toe's R_u over
its toe's and shaft's).

The drivability's pile at depth d has its embedded length d at x in [L − d, L] (x from the struck
end, L the pile's length): each layer it passes through puts its `shaft_resistance` (N per metre)
on the stretch in it, and the layer at the toe its `toe_resistance` on the toe. A layer's
`setup_factor` multiplies its shaft resistance where driving starts again after a pause: the soil's
gain (setup, > 1) or loss (relaxation, < 1) meanwhile; the restrike is run at each depth when a
layer gives one other than 1.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, model_validator

from .case import INPUT, Case, CaseError, FieldError, field_error, parse_case, validated
from .limits import Limits, check_case
from .settle import check_counting

MAX_VARIANTS = 500  # capacities, strokes or depths a study may run

Capacity = Annotated[float, Field(gt=0, le=1e12)]
Stroke = Annotated[float, Field(gt=0, le=1e3)]
Depth = Annotated[float, Field(ge=0, le=1e4)]
Quake = Annotated[float, Field(gt=0, le=1.0)]
DampingFactor = Annotated[float, Field(ge=0, le=1e3)]


class BearingGraph(BaseModel):
    """A pile case and its capacities (a bearing graph) or its ram's strokes (an inspector's chart)."""

    model_config = INPUT

    case: Case
    capacity: list[Capacity] | None = Field(
        None,
        min_length=1,
        max_length=MAX_VARIANTS,
        description="the pile's ultimate resistances R_u (N), the toe's and the shaft's together: a bearing graph",
    )
    stroke: list[Stroke] | None = Field(
        None,
        min_length=1,
        max_length=MAX_VARIANTS,
        description="the ram's strokes (m) at the case's capacity: an inspector's chart (the case gives striker.stroke)",
    )
    toe_share: float | None = Field(
        None,
        gt=0,
        le=1,
        description="the toe's share S of the capacity, the shaft taking 1 − S (default: the case's own)",
    )

    @model_validator(mode="after")
    def _answerable(self) -> BearingGraph:
        if (self.capacity is None) == (self.stroke is None):
            raise field_error(
                "BearingGraph",
                ("capacity",),
                "give capacity (ultimate resistances: a bearing graph) or stroke (the ram's strokes: an "
                "inspector's chart), one of them",
                None,
            )
        medium = self.case.medium
        if medium is None or medium.kind != "smith":
            raise field_error(
                "BearingGraph",
                ("case", "medium", "kind") if medium else ("case", "medium"),
                "the pile's toe must be Smith soil (medium.kind 'smith'): its ultimate resistance is the toe's "
                "share of each capacity",
                medium.kind if medium else None,
            )
        if self.stroke is not None and (self.case.striker is None or self.case.striker.stroke is None):
            raise field_error(
                "BearingGraph",
                ("case", "striker", "stroke"),
                "an inspector's chart varies the ram's stroke: give the case a falling ram (striker.stroke "
                "instead of striker.velocity)",
                None,
            )
        if self.toe_share is not None and self.toe_share < 1.0 and not self.case.shaft:
            raise field_error(
                "BearingGraph",
                ("toe_share",),
                "the case has no shaft to take the rest of the capacity: give it shaft segments, or leave "
                "toe_share out (all at the toe)",
                self.toe_share,
            )
        return self

    @property
    def variable(self) -> str:
        """What the study varies: 'capacity' or 'stroke'."""
        return "capacity" if self.capacity is not None else "stroke"

    @property
    def values(self) -> list[float]:
        return self.capacity if self.capacity is not None else self.stroke


def parse_bearing_graph(data: dict) -> BearingGraph:
    """Validate a bearing graph given as JSON; `CaseError` names each bad field."""
    return validated(BearingGraph, data)


def capacity_of(case: Case) -> float:
    """The case's ultimate resistance R_u (N): its toe's and its shaft's together."""
    return case.medium.ultimate_resistance + sum(segment.ultimate_resistance for segment in case.shaft or [])


def toe_share_of(case: Case) -> float:
    """The toe's share of the case's ultimate resistance."""
    return case.medium.ultimate_resistance / capacity_of(case)


def with_capacity(case: Case, capacity: float, share: float) -> dict:
    """The case JSON with `capacity` split: `share` of it at the toe, the rest over the shaft's
    segments in the case's proportions (none left at a share of 1)."""
    tree = case.model_dump(mode="json", exclude_none=True)
    tree["medium"]["ultimate_resistance"] = share * capacity
    shaft = tree.pop("shaft", [])
    if share < 1.0:
        own = sum(segment["ultimate_resistance"] for segment in shaft)
        for segment in shaft:
            segment["ultimate_resistance"] *= (1.0 - share) * capacity / own
        tree["shaft"] = shaft
    return tree


def bearing_variants(request: BearingGraph, limits: Limits | None = Limits()) -> list[Case]:
    """The case of each capacity or stroke, in order; `CaseError` names each bad one as
    `capacity[k]` or `stroke[k]`."""
    case = request.case
    share = request.toe_share or toe_share_of(case)
    trees = []
    for value in request.values:
        if request.variable == "capacity":
            trees.append(with_capacity(case, value, share))
            continue
        # the case's own resistances as given, unless the toe's share is asked
        if request.toe_share is None:
            tree = case.model_dump(mode="json", exclude_none=True)
        else:
            tree = with_capacity(case, capacity_of(case), share)
        tree["striker"]["stroke"] = value
        trees.append(tree)
    return _checked(trees, [f"{request.variable}[{k}]" for k in range(len(trees))], limits)


def _checked(trees: list[dict], fields: list[str], limits: Limits | None) -> list[Case]:
    """Each tree as a validated case within the limits (its counting run's too); `CaseError` names
    each bad one by its field in `fields`."""
    cases, errors = [], []
    for tree, field in zip(trees, fields):
        try:
            case = parse_case(tree)
            if limits is not None:
                check_case(case, limits)
                check_counting(case, limits)
            cases.append(case)
        except CaseError as error:
            errors += [FieldError(field=field, message=f"{e.field}: {e.message}") for e in error.errors]
    if errors:
        raise CaseError(errors)
    return cases


class Layer(BaseModel):
    """A layer of soil from `from` to `to` (m below the surface): its resistance on the shaft per
    metre of pile in it, on the toe when the toe is in it, Smith's quakes and damping factors, and
    the factor on its shaft resistance when driving starts again after a pause."""

    model_config = ConfigDict(**INPUT, validate_by_alias=True, validate_by_name=False, serialize_by_alias=True)

    start: Depth = Field(alias="from", description="m below the surface")
    end: Depth = Field(alias="to", description="m below the surface")
    shaft_resistance: float = Field(ge=0, le=1e10, description="ultimate shaft resistance per metre of pile, N/m")
    toe_resistance: float = Field(gt=0, le=1e12, description="ultimate resistance at the toe in this layer, N")
    shaft_quake: Quake = Field(description="m")
    toe_quake: Quake = Field(description="m")
    shaft_damping_factor: DampingFactor = Field(description="Smith's J on the shaft, s/m")
    toe_damping_factor: DampingFactor = Field(description="Smith's J at the toe, s/m")
    setup_factor: float = Field(
        1.0,
        gt=0,
        le=100,
        description="× the shaft resistance when driving starts again after a pause: > 1 the soil's setup, "
        "< 1 its relaxation",
    )

    @model_validator(mode="after")
    def _ordered(self) -> Layer:
        if self.end <= self.start:
            raise field_error("Layer", ("to",), f"must be deeper than from = {self.start} m", self.end)
        return self


class Soil(BaseModel):
    """The layers from the surface down, the depths to drive the pile to, its rate of blows and
    the blow count that is refusal."""

    model_config = INPUT

    layers: list[Layer] = Field(min_length=1, description="from the surface down, each starting where the last ends")
    depths: list[Depth] = Field(
        min_length=1, max_length=MAX_VARIANTS, description="the toe's depths to analyse, m, from the first to the last"
    )
    blow_rate: float = Field(gt=0, le=1e3, description="blows per second, Hz")
    refusal: float = Field(gt=0, le=1e6, description="the blow count that is refusal, blows per metre")

    @model_validator(mode="after")
    def _layered(self) -> Soil:
        if self.layers[0].start != 0.0:
            raise field_error(
                "Soil", ("layers", 0, "from"), "must be 0: the layers start at the surface", self.layers[0].start
            )
        for i, (above, layer) in enumerate(zip(self.layers, self.layers[1:]), start=1):
            if layer.start != above.end:
                how = "overlaps the layer above it" if layer.start < above.end else "leaves a gap below the layer above"
                raise field_error(
                    "Soil",
                    ("layers", i, "from"),
                    f"{how}, which ends at {above.end} m: each layer starts where the one above ends",
                    layer.start,
                )
        bottom = self.layers[-1].end
        for k, depth in enumerate(self.depths):
            if depth <= 0.0 or (k and depth <= self.depths[k - 1]):
                raise field_error(
                    "Soil",
                    ("depths", k),
                    "must be below the surface and deeper than the depth before it",
                    depth,
                )
            if depth > bottom:
                raise field_error("Soil", ("depths", k), f"lies below the last layer, which ends at {bottom} m", depth)
        return self

    @property
    def restrike(self) -> bool:
        """Whether a layer's shaft resistance changes over a pause."""
        return any(layer.setup_factor != 1.0 for layer in self.layers)

    def at(self, depth: float) -> Layer:
        """The layer the toe is in at `depth` (at a boundary, the one below it)."""
        return next((layer for layer in self.layers if layer.start <= depth < layer.end), self.layers[-1])


class Drivability(BaseModel):
    """A pile case (its hammer, cushion and pile) and the soil it is driven into."""

    model_config = INPUT

    case: Case
    soil: Soil

    @model_validator(mode="after")
    def _within_the_pile(self) -> Drivability:
        length = self.case.tool.length
        for k, depth in enumerate(self.soil.depths):
            if depth > length:
                raise field_error(
                    "Drivability",
                    ("soil", "depths", k),
                    f"is beyond the pile's length, tool.length = {length} m",
                    depth,
                )
        return self


def parse_drivability(data: dict) -> Drivability:
    """Validate a drivability given as JSON; `CaseError` names each bad field."""
    return validated(Drivability, data)


def at_depth(case: Case, soil: Soil, depth: float, restrike: bool = False) -> dict:
    """The case JSON of the pile with its toe at `depth`: the shaft's segments from the layers it
    passes through and the toe's Smith soil from the layer it is in (see the module's docstring);
    `restrike` multiplies each layer's shaft resistance by its setup factor."""
    tree = case.model_dump(mode="json", exclude_none=True)
    length = case.tool.length
    tree.pop("shaft", None)
    segments = []
    for layer in soil.layers:
        top, bottom = layer.start, min(layer.end, depth)
        if bottom > top and layer.shaft_resistance > 0.0:
            factor = layer.setup_factor if restrike else 1.0
            segments.append(
                {
                    # as L − (d − z), so that the toe's end is L exactly
                    "from": length - (depth - top),
                    "to": length - (depth - bottom),
                    "ultimate_resistance": layer.shaft_resistance * (bottom - top) * factor,
                    "quake": layer.shaft_quake,
                    "damping_factor": layer.shaft_damping_factor,
                }
            )
    if segments:
        tree["shaft"] = segments
    toe = soil.at(depth)
    tree["medium"] = {
        "kind": "smith",
        "ultimate_resistance": toe.toe_resistance,
        "quake": toe.toe_quake,
        "damping_factor": toe.toe_damping_factor,
    }
    return tree


def drivability_variants(request: Drivability, limits: Limits | None = Limits()) -> list[tuple[float, bool, Case]]:
    """(depth, restrike, case) of each depth, driving then (when a layer gives a setup factor)
    restriking; `CaseError` names each bad one as `soil.depths[k]`."""
    soil = request.soil
    runs = (False, True) if soil.restrike else (False,)
    picks = [(k, depth, restrike) for k, depth in enumerate(soil.depths) for restrike in runs]
    trees = [at_depth(request.case, soil, depth, restrike) for _, depth, restrike in picks]
    cases = _checked(trees, [f"soil.depths[{k}]" for k, _, _ in picks], limits)
    return [(depth, restrike, case) for (_, depth, restrike), case in zip(picks, cases)]


def set_aside(case: Case) -> list[str]:
    """The warning that the case's own soil is not the drivability's."""
    given = [name for name in ("medium", "shaft") if getattr(case, name)]
    if not given:
        return []
    return [
        f"the case's {' and '.join(given)} {'is' if len(given) == 1 else 'are'} set aside: the soil gives the "
        "shaft's and the toe's resistance at each depth"
    ]
