"""percussim.testing: what the tests and the benches stand on, importable as a module from
either. The closed-form references the solver is held to (`reference`: the linear impact,
Saint-Venant's rigid impact, a cushioned ram, Lundberg's rock) and the cases built around them
(`closed_forms`: pistons, rock, soil, anvils, a split Hopkinson bar's record); a pile and its
soil for the pile studies (`piles`); a live stack of
Redis, PostgreSQL, the API and its workers on this machine (`live_stack`). Nothing in the solver,
the API or the workers imports it.
"""

from __future__ import annotations

import copy

from percussim.solver.presets import preset_json


def merge(base: dict, changes: dict) -> dict:
    """`base` with `changes` merged in, recursively (a None value removes the key)."""
    out = copy.deepcopy(base)
    for key, value in changes.items():
        if value is None:
            out.pop(key, None)
        elif isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


def at_default_accuracy(name: str) -> dict:
    """Preset `name` with only its duration in `numerics` (the default accuracy) and no outputs."""
    case = preset_json(name)
    case["numerics"] = {"duration": case["numerics"]["duration"]}
    case.pop("outputs", None)
    return case
