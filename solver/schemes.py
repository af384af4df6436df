"""The time-stepping schemes a case can ask for, as the few numbers the kernel needs.

All three share the kernel's step (one elimination along the tool, one scalar contact solve) and
the operator `(S·u_x)_x` in conservative form (cell areas between nodes, `grid.py`):

- `paper`: the weighted scheme (8)–(13), `γ` on the new layer and `1 − γ` on the current one,
  massless ends (9), (10) and backward dampers. First order in τ; dissipative for γ ≥ 1/2.
- `sigma`: the symmetric σ-scheme, `σu^{n+1} + (1 − 2σ)u^n + σu^{n−1}` in the operator,
  boundary terms centred on layer n. Second order; for σ ≥ 1/4 stable for every τ and it conserves
  a discrete energy.
- `explicit`: σ = 0, central differences; stable for Courant numbers `a·τ/h ≤ 1`.

With `end_masses` each end node carries its half-cell mass (`ρS(h/2)·ü_0 = S E (u_1 − u_0)/h + F_c`),
which makes the ends second order; the paper's ends drop it. Second-order schemes default to it.
"""

from __future__ import annotations

from dataclasses import dataclass

from .case import Numerics

SCHEMES = ("paper", "sigma", "explicit")
ORDER = {"paper": 1, "sigma": 2, "explicit": 2}  # observed order in h and τ together


@dataclass(frozen=True)
class Scheme:
    """The weights of one scheme.

    `weight_new`, `weight_old`: weight of layers n+1 and n−1 in the tool's operator (γ and 0 for
    the paper, σ and σ for the σ-scheme); layer n gets the rest. `centered`: boundary springs,
    dampers and the contact are centred on layer n (second order) rather than on n+½ (the paper's).
    """

    name: str
    weight_new: float
    weight_old: float
    centered: bool
    end_masses: bool

    @property
    def order(self) -> int:
        return ORDER[self.name] if self.end_masses or self.name == "paper" else 1

    @property
    def courant_limit(self) -> float:
        """Largest stable `a·τ/h` (infinite for the implicit schemes)."""
        return 1.0 if self.name == "explicit" else float("inf")


def make_scheme(name: str, gamma: float = 0.5, sigma: float = 0.25, end_masses: bool | None = None) -> Scheme:
    """The scheme `name` with its weight (γ for 'paper', σ for 'sigma') and end option
    (default: half-cell end masses for the second-order schemes)."""
    if end_masses is None:
        end_masses = name != "paper"
    if name == "paper":
        return Scheme(name, gamma, 0.0, centered=False, end_masses=end_masses)
    if name not in SCHEMES:
        raise ValueError(f"unknown scheme {name!r}")
    weight = sigma if name == "sigma" else 0.0
    return Scheme(name, weight, weight, centered=True, end_masses=end_masses)


def scheme_of(numerics: Numerics, name: str | None = None) -> Scheme:
    """The case's scheme (or `name`), default 'paper', with its γ, σ and end option."""
    return make_scheme(name or numerics.scheme or "paper", numerics.gamma, numerics.sigma, numerics.end_masses)
