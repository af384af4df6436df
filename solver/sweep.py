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

from pydantic import BaseModel, ConfigDict, Field

from .case import Case, CaseError, FieldError, Outputs, parse_case
from .limits import Limits, check_case

MAX_VARIANTS = 10_000
MAX_ERRORS = 20  # bad variants named before giving up
# A table row needs only the summary's extremes: no fields, no probes, no history beyond step 0.
TABLE_OUTPUTS = Outputs(history_stride=2**62)

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
    ("estimated_error", ("error_estimate", "worst")),  # the worst of the row's quantities
)


class Sweep(BaseModel):
    """A base case and, per field path (`striker.velocity`, `tool.profile.area.2`), its values."""

    model_config = ConfigDict(extra="forbid")

    case: Case
    parameters: dict[str, list[Any]] = Field(
        min_length=1, description="dotted field path → the values it takes; every combination runs")


def _set(tree: dict, path: str, value: Any) -> None:
    """Set `path` (dots; list items by their index) in the case JSON `tree`. A path the case does
    not have is created, so that validation names it as an unknown field."""
    *parents, leaf = path.split(".")
    node: Any = tree
    for key in parents:
        node = node[int(key)] if isinstance(node, list) else node.setdefault(key, {})
    if isinstance(node, list):
        node[int(leaf)] = value
    elif isinstance(node, dict):
        node[leaf] = value
    else:
        raise TypeError(f"{path}: {node!r} has no fields")


def variants(sweep: Sweep, max_variants: int = MAX_VARIANTS,
             limits: Limits = Limits()) -> list[tuple[dict[str, Any], Case]]:
    """Every (parameter values, validated case) of the sweep, or `CaseError` naming, for each bad
    variant (invalid, or over a size limit), the parameter value it came from and what it breaks."""
    names = list(sweep.parameters)
    for name, values in sweep.parameters.items():
        if not values:
            raise CaseError([FieldError(field=f"parameters[{name!r}]", message="give at least one value")])
    count = math.prod(len(v) for v in sweep.parameters.values())
    if count > max_variants:
        raise CaseError([FieldError(field="parameters", message=(
            f"{count} variants ({' × '.join(str(len(sweep.parameters[n])) for n in names)}) exceed "
            f"the limit of {max_variants}: sweep fewer values"))])
    base = sweep.case.model_dump(mode="json", exclude_none=True)
    found, errors = [], {}
    for picks in itertools.product(*(enumerate(sweep.parameters[n]) for n in names)):
        tree = copy.deepcopy(base)
        values = {name: value for name, (_, value) in zip(names, picks)}
        try:
            for name, (k, value) in zip(names, picks):
                where = f"parameters[{name!r}][{k}]"
                _set(tree, name, value)
            case = parse_case(tree)
            check_case(case, limits)
            found.append((values, case))
        except CaseError as error:
            for e in error.errors:
                # The parameter whose path the broken field starts with; else the only parameter
                # (the base case is valid, so it broke another field: striker.length makes
                # striker.mass wrong); else the whole variant.
                culprit = next((f"parameters[{n!r}][{k}]" for n, (k, _) in zip(names, picks)
                                if e.field == n or e.field.startswith(n + ".") or len(names) == 1),
                               "parameters (" + ", ".join(f"{n} = {v!r}" for n, v in values.items()) + ")")
                errors.setdefault(culprit, FieldError(field=culprit, message=f"{e.field}: {e.message}"))
        except (IndexError, ValueError, TypeError) as error:
            errors[where] = FieldError(field=where, message=f"cannot be set: {error}")
        if len(errors) >= MAX_ERRORS:
            break
    if errors:
        raise CaseError(list(errors.values()))
    return found


def _at(summary: dict, path: tuple) -> Any:
    """The summary's value at `path`; None where it has none (no medium, no blows, or a summary
    stored before the quantity existed, as a service's older jobs have)."""
    value: Any = summary
    for key in path:
        if isinstance(value, dict):
            value = value.get(key)
        elif isinstance(value, list) and value:
            value = value[key]
        else:
            return None
    return value


def table_row(summary: dict) -> dict[str, Any]:
    """The sweep table's columns from one variant's summary."""
    row = {column: _at(summary, path) for column, path in COLUMNS}
    row["warnings"] = len(summary["warnings"])
    return row
