"""Dotted paths into a case's JSON (`striker.velocity`, `tool.profile.area.2`) and into a summary
(`energy.transfer_efficiency`, `blows.-1.set`): what sweeps, fits and optimisations vary and read."""

from __future__ import annotations

from typing import Any


def set_field(tree: dict, path: str, value: Any) -> None:
    """Set `path` (dots; list items by their index, `*` for every item: `shaft.*.quake` ties the
    segments' quakes to one value) in the case JSON `tree`. A path the case does not have is
    created, so that validation names it as an unknown field."""
    key, _, rest = path.partition(".")
    if isinstance(tree, list):
        for index in range(len(tree)) if key == "*" else [int(key)]:
            if rest:
                set_field(tree[index], rest, value)
            else:
                tree[index] = value
    elif isinstance(tree, dict):
        if rest:
            set_field(tree.setdefault(key, {}), rest, value)
        else:
            tree[key] = value
    else:
        raise TypeError(f"{path}: {tree!r} has no fields")


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
                value = value[0 if key == "*" else int(key)]  # `*`: every item, tied; the first says it
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
