"""The contact and the external force: R(t), the contact law (Φ'(δ), Φ(δ)) and its stiffness,
the difference quotient a step applies, and the safeguarded Newton solve of the overlap.
"""

from __future__ import annotations

import math

from .. import laws
from ..compiled import compiled
from ..layout import GRAZING
from .bundles import Contact

_external_force = compiled(inline="always")(laws.external_force)
_contact_law = compiled(inline="always")(laws.contact_law)
_contact_spring = compiled(inline="always")(laws.contact_spring)
_cushion_loss = compiled(inline="always")(laws.cushion_loss)
_linear_branch = compiled(inline="always")(laws.linear_branch)


@compiled(inline="always")
def external_force(t, force):
    """`R(t)` of the `ForceLaw` (`laws.external_force`)."""
    return _external_force(t, force.kind, force.amplitude, force.omega, force.start, force.duration)


@compiled(inline="always")
def contact_law(delta, contact):
    """`(Φ'(δ), Φ(δ))` of the `Contact` (`laws.contact_law`)."""
    return _contact_law(
        delta, contact.stiffness, contact.exponent, contact.tension_stiffness, contact.restitution, contact.deepest
    )


@compiled(inline="always")
def contact_spring(delta, contact):
    """`(Φ'(δ), Φ''(δ))` of the `Contact` (`laws.contact_spring`)."""
    return _contact_spring(
        delta, contact.stiffness, contact.exponent, contact.tension_stiffness, contact.restitution, contact.deepest
    )


@compiled(inline="always")
def linear_branch(delta, contact):
    """The line a linear `Contact`'s force follows at δ and the overlaps it holds over
    (`laws.linear_branch`)."""
    return _linear_branch(delta, contact.stiffness, contact.tension_stiffness, contact.restitution, contact.deepest)


@compiled(inline="always")
def _contact(contact, deepest, velocity):
    """The `Contact` pressed to `deepest`, its striker launched at `velocity`."""
    return Contact(
        striker_mass=contact.striker_mass,
        striker_velocity=velocity,
        stiffness=contact.stiffness,
        exponent=contact.exponent,
        tension_stiffness=contact.tension_stiffness,
        damping=contact.damping,
        impedance=contact.impedance,
        restitution=contact.restitution,
        deepest=deepest,
    )


@compiled(inline="always")
def pressed_to(contact, deepest):
    """The `Contact` as a cushion pressed to its `deepest` overlap so far (`laws.contact_law`)."""
    return _contact(contact, deepest, contact.striker_velocity)


@compiled(inline="always")
def launched_at(contact, velocity):
    """The `Contact` of a striker launched at `velocity` (a hammer's drive gives each blow its own)."""
    return _contact(contact, contact.deepest, velocity)


@compiled(inline="always")
def cushion_loss(contact, deepest):
    """What the `Contact` pressed to `deepest` has lost (`laws.cushion_loss`)."""
    return _cushion_loss(contact.stiffness, contact.exponent, contact.restitution, deepest)


@compiled(inline="always")
def quotient_force(delta, ref, ref_potential, contact):
    """`(Φ(δ) − Φ_ref)/(δ − ref)` and its derivative in δ (the midpoint values when δ ≈ ref).

    `Φ_ref` is Φ(ref) but for the state before impact, where no link acts yet and it is 0.
    """
    diff = delta - ref
    if abs(diff) > 1e-7 * (abs(delta) + abs(ref)):
        spring, potential = contact_law(delta, contact)
        inverse = 1.0 / diff
        f = (potential - ref_potential) * inverse
        return f, (spring - f) * inverse
    mid = 0.5 * (delta + ref)
    spring, stiffness = contact_spring(mid, contact)
    return spring, 0.5 * stiffness


ROUNDING = 2.0**-53  # a double's relative rounding


@compiled(inline="always")
def bracketed_newton_step(x, g, slope, lo, hi, scale, curvature=math.inf):
    """One Newton step on an increasing g, g(x) = `g`, g'(x) = `slope`, within the bracket [lo, hi]
    narrowed by the sign of g; a step that leaves it is replaced by bisection. Returns the new x,
    the bracket, and whether the step or the bracket is within `scale`, or what a Newton step Δ
    leaves to go is within rounding of the new x: at most `curvature`·Δ², `curvature` a bound on
    |g''|/(2g') about x (which saves the step that would only confirm it)."""
    if g > 0.0:
        hi = x
    else:
        lo = x
    x_new = x - g / slope
    newton = lo < x_new < hi
    if not newton:
        x_new = 0.5 * (lo + hi)
    step = abs(x_new - x)
    settled = newton and curvature * step * step <= ROUNDING * abs(x_new)
    return x_new, lo, hi, step <= scale or hi - lo <= scale or settled


@compiled()
def solve_overlap(free, compliance, ref, ref_potential, guess, contact, damper):
    """The new overlap δ of `δ + compliance·F(δ) = free`, `F(δ) = quotient(δ, ref) + damper·(δ − ref)`.

    F increases with δ (Φ is convex), so the root is unique and lies between `free` and
    `free − compliance·F(free)`, where `bracketed_newton_step` finds it.
    """
    f_free = quotient_force(free, ref, ref_potential, contact)[0] + damper * (free - ref)
    other = free - compliance * f_free
    lo, hi = min(free, other), max(free, other)
    if lo == hi:
        return free
    x = min(max(guess, lo), hi)
    scale = 1e-15 * (abs(lo) + abs(hi))
    for _ in range(100):
        f, df = quotient_force(x, ref, ref_potential, contact)
        g = x + compliance * (f + damper * (x - ref)) - free
        if g == 0.0:
            return x
        x, lo, hi, done = bracketed_newton_step(x, g, 1.0 + compliance * (df + damper), lo, hi, scale)
        if done:
            return x
    return x


@compiled(inline="always")
def crossing(before_that, before, now):
    """Where in the last step (0 … 1) the overlap crossed zero, on the parabola through its last
    three values (a straight line when it has only two); third order, so the contact times' error
    is the scheme's, not where the crossing fell between two layers."""
    linear = before / (before - now)
    if not (before_that == before_that):
        return linear
    a = 0.5 * (now + before_that) - before
    b = 0.5 * (now - before_that)
    disc = b * b - 4.0 * a * before
    if a == 0.0 or disc < 0.0:
        return linear
    root = math.sqrt(disc)
    for x in ((-b + root) / (2.0 * a), (-b - root) / (2.0 * a)):
        if 0.0 <= x <= 1.0:
            return x
    return linear


@compiled(inline="always")
def crossing_rate(before_that, before, now, at):
    """The overlap's change per step where `crossing` put its zero (`at`), on the same parabola
    (the same straight line)."""
    if not (before_that == before_that):
        return now - before
    return 0.5 * (now - before_that) + (now + before_that - 2.0 * before) * at


@compiled(inline="always")
def rounding_of(first, second):
    """The rounding of an overlap between two faces displaced by `first` and `second`: within it,
    an overlap changes no contact (`GRAZING`)."""
    return GRAZING * (abs(first) + abs(second))


@compiled(inline="always")
def fade_time(rounding, rate):
    """How long an overlap changing at `rate` (δ1') takes to cross its `rounding` (`rounding_of`):
    where a contact ends, next to nothing if the faces part, a slow link's relaxation time if the
    contact fades out."""
    return rounding / max(abs(rate), 1e-300)
