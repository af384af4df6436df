"""Size limits checked before a run starts, so a case too large is refused, never killed later."""

from __future__ import annotations

from dataclasses import dataclass

from . import layout as L
from .case import Case, CaseError, FieldError
from .grid import ResolvedNumerics, explicit_numerics, first_cells, resolve_numerics, striker_cells, tolerance_of


@dataclass(frozen=True)
class Limits:
    """Sizes a run may not exceed; `PERCUSSIM_MAX_CELLS`, `…_STEPS`, `…_NODE_STEPS` and
    `…_OUTPUT_VALUES` set them, for the service and the command line alike."""

    max_cells: int = 100_000
    max_steps: int = 20_000_000
    max_node_steps: float = 2e10  # cells × steps: about a few minutes of kernel time
    # Numbers kept in histories, probes and fields: 1.6 GB, on disk when streamed to a result file,
    # in memory otherwise.
    max_output_values: float = 2e8


def output_values(case: Case, numerics: ResolvedNumerics) -> float:
    """How many numbers the run keeps for its outputs."""
    out = case.outputs
    rows = numerics.steps // out.history_stride + 1
    values = rows * (L.HISTORY_COLUMNS + len(out.probes))
    if out.fields and numerics.model == "rod":
        nodes = numerics.cells + 1
        if case.elastic_striker:
            nodes += striker_cells(case.striker, numerics.time_step) + 1
        values += (numerics.steps // out.field_stride + 1) * 2 * nodes
    return float(values)


@dataclass(frozen=True)
class Excess:
    """A limit a run would exceed: `field` is the case's field that sets it, `what` says by how
    much and which setting raises it, `remedy` what to change in the case."""

    field: str
    what: str
    remedy: str = ""


def excesses(case: Case, numerics: ResolvedNumerics, limits: Limits = Limits()) -> list[Excess]:
    """Each limit the run of `case` on `numerics` would exceed."""
    found = []
    if numerics.cells > limits.max_cells:
        found.append(
            Excess(
                "numerics.cells",
                f"{numerics.cells} cells exceed the limit of {limits.max_cells} (PERCUSSIM_MAX_CELLS raises it)",
            )
        )
    blows = case.blows_run
    per_blow = f" × {blows} blows" if blows > 1 else ""
    fewer_blows = f", or give fewer {'cycles' if case.cycles else 'blows'}.count" if blows > 1 else ""
    if numerics.steps > limits.max_steps:
        found.append(
            Excess(
                "numerics.time_step",
                f"{numerics.steps} time steps (duration / time_step{per_blow}) exceed the limit of "
                f"{limits.max_steps} (PERCUSSIM_MAX_STEPS raises it)",
                f"raise numerics.time_step or shorten numerics.duration{fewer_blows}",
            )
        )
    work = float(numerics.cells) * numerics.steps
    if numerics.model == "rod" and work > limits.max_node_steps:
        found.append(
            Excess(
                "numerics",
                f"{work:.3g} node-steps (cells × steps) exceed the limit of {limits.max_node_steps:.3g} "
                "(PERCUSSIM_MAX_NODE_STEPS raises it)",
                f"use fewer cells or a larger time_step{fewer_blows}",
            )
        )
    values = output_values(case, numerics)
    if values > limits.max_output_values:
        found.append(
            Excess(
                "outputs",
                f"the outputs would keep {values:.3g} numbers, over the limit of "
                f"{limits.max_output_values:.3g} (PERCUSSIM_MAX_OUTPUT_VALUES raises it)",
                "raise outputs.history_stride or outputs.field_stride",
            )
        )
    return found


def check_limits(case: Case, numerics: ResolvedNumerics, limits: Limits = Limits()) -> None:
    """Raise `CaseError` naming each limit the case exceeds and the field that sets it."""
    found = excesses(case, numerics, limits)
    if found:
        raise CaseError(
            [FieldError(field=e.field, message=e.what + (f": {e.remedy}" if e.remedy else "")) for e in found]
        )


def check_case(case: Case, limits: Limits) -> None:
    """Refuse up front a case over the limits (`CaseError` naming each): the grid it gives, or,
    under a tolerance, the first grid of its ladder (a later one over them ends the ladder)."""
    tol = tolerance_of(case.numerics)
    if tol is not None:
        numerics = explicit_numerics(case, first_cells(case, tol))
    else:
        numerics = resolve_numerics(case)
    check_limits(case, numerics, limits)
