"""Dotted paths into a case's JSON (`striker.velocity`, `tool.profile.area.2`) and into a summary
(`energy.transfer_efficiency`, `blows.-1.set`): what sweeps, fits and optimisations vary and read."""

from __future__ import annotations

from typing import Any


def set_field(tree: dict, path: str, value: Any) -> None:
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


def value_at(tree: Any, path: tuple | str) -> Any:
    """The value at `path` (a tuple of keys, or dots; -1 is a list's last item); None where there
    is none (no medium, no blows, or a summary stored before the quantity existed)."""
    keys = path.split(".") if isinstance(path, str) else path
    value = tree
    for key in keys:
        if isinstance(value, dict):
            value = value.get(key)
        elif isinstance(value, list) and value:
            try:
                value = value[int(key)]
            except (ValueError, IndexError):
                return None
        else:
            return None
    return value


def quantity(summary: dict, path: str) -> float | None:
    """A summary quantity by its path: a number, or the `value` of a peak (`max_compressive_stress`
    is its `value`); None when the summary has none there or it is not a number."""
    value = value_at(summary, path)
    if isinstance(value, dict):
        value = value.get("value")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)
