"""Parameter sweeps: a base case, the values to give some of its fields, one row of results each.

Every combination of the values is one variant (a full factorial grid). `variants` validates them
all before anything runs, naming the parameter and value a bad variant came from;
`simulate.run_sweep` solves them on every core (one process a core: the kernel is serial and each process loads it from
Numba's cache) and returns one table.
"""

from __future__ import annotations

import copy
import itertools
import math
from typing import Any

from pydantic import BaseModel, Field

from .case import INPUT, Case, CaseError, FieldError, parse_case
from .limits import Limits, check_case
from .paths import set_field, value_at

MAX_VARIANTS = 10_000
MAX_ERRORS = 20  # bad variants named before giving up

# The table's columns after the parameters: (name, where in the summary; -1 is a list's last item).
COLUMNS = (
    ("co_impact_time", ("co_impact_time",)),
    ("peak_contact_force", ("peak_contact_force", "value")),
    ("max_compressive_stress", ("max_compressive_stress", "value")),
    ("max_tensile_stress", ("max_tensile_stress", "value")),
    ("striker_rebound_velocity", ("striker_rebound_velocity",)),
    ("energy_to_medium", ("energy", "to_medium")),
    ("transfer_efficiency", ("energy", "transfer_efficiency")),
    ("max_penetration", ("medium_penetration", "max")),
    ("permanent_penetration", ("medium_penetration", "permanent")),
    ("last_blow_set", ("blows", -1, "set")),  # the set per blow once it has settled
    ("contacts", ("contacts_total",)),
    # a hammer at work's (`cycles`): its blows a second, impact power and efficiency from the supply
    ("frequency", ("cycle", "frequency")),
    ("impact_power", ("cycle", "impact_power")),
    ("hydraulic_efficiency", ("cycle", "efficiency")),
    ("estimated_error", ("error_estimate", "worst")),  # the worst of the row's quantities
)


class Sweep(BaseModel):
    """A base case and, per field path (`striker.velocity`, `tool.profile.area.2`), its values."""

    model_config = INPUT

    case: Case
    parameters: dict[str, list[Any]] = Field(
        min_length=1, description="dotted field path → the values it takes; every combination runs"
    )


def variants(
    sweep: Sweep, max_variants: int = MAX_VARIANTS, limits: Limits | None = Limits(), field: str = "parameters"
) -> list[tuple[dict[str, Any], Case]]:
    """Every (parameter values, validated case) of the sweep, or `CaseError` naming, for each bad
    variant (invalid, or over a size limit unless `limits` is None), the parameter value it came
    from (as `field[path][index]`) and what it breaks."""
    names = list(sweep.parameters)
    for name, values in sweep.parameters.items():
        if not values:
            raise CaseError([FieldError(field=f"{field}[{name!r}]", message="give at least one value")])
    count = math.prod(len(v) for v in sweep.parameters.values())
    if count > max_variants:
        raise CaseError(
            [
                FieldError(
                    field=field,
                    message=(
                        f"{count} variants ({' × '.join(str(len(sweep.parameters[n])) for n in names)}) exceed "
                        f"the limit of {max_variants}: sweep fewer values"
                    ),
                )
            ]
        )
    base = sweep.case.model_dump(mode="json", exclude_none=True)
    found, errors = [], {}
    for picks in itertools.product(*(enumerate(sweep.parameters[n]) for n in names)):
        tree = copy.deepcopy(base)
        values = {name: value for name, (_, value) in zip(names, picks)}
        try:
            for name, (k, value) in zip(names, picks):
                where = f"{field}[{name!r}][{k}]"
                set_field(tree, name, value)
            case = parse_case(tree)
            if limits is not None:
                check_case(case, limits)
            found.append((values, case))
        except CaseError as error:
            for e in error.errors:
                # The parameter whose path the broken field starts with; else the only parameter
                # (the base case is valid, so it broke another field: striker.length makes
                # striker.mass wrong); else the whole variant.
                culprit = next(
                    (
                        f"{field}[{n!r}][{k}]"
                        for n, (k, _) in zip(names, picks)
                        if e.field == n or e.field.startswith(n + ".") or len(names) == 1
                    ),
                    f"{field} (" + ", ".join(f"{n} = {v!r}" for n, v in values.items()) + ")",
                )
                errors.setdefault(culprit, FieldError(field=culprit, message=f"{e.field}: {e.message}"))
        except (IndexError, ValueError, TypeError) as error:
            errors[where] = FieldError(field=where, message=f"cannot be set: {error}")
        if len(errors) >= MAX_ERRORS:
            break
    if errors:
        raise CaseError(list(errors.values()))
    return found


def table_row(summary: dict) -> dict[str, Any]:
    """The sweep table's columns from one variant's summary."""
    row = {column: value_at(summary, path) for column, path in COLUMNS}
    row["warnings"] = len(summary["warnings"])
    return row
