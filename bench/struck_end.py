"""What one step of the struck end's own integration costs (`kernel.struck_end.struck_end_step`):
the lumped striker, the contact and the tool's end over a time step at Courant number 1, on each
preset's finest grid at the default accuracy; the working end's step (`working_end_step`) beside it.

    .venv/bin/python bench/struck_end.py [--calls 200000] [--repeats 5]

Three states of the same step, each call starting from the same one:
- **pressed**: the contact at the overlap of half its peak force, its faces closing;
- **pressed, linear**: the same, the contact linear with the same force there, so that each
  stage's balance is solved directly (`solve_spring_balance` on one line of the law), where the
  preset's law (α = 0.5) takes Newton's iterations;
- **apart**: the faces as far apart as they were pressed, closing (the law's tension line: no
  iteration either).

The difference between the first two is what the contact law's iterations cost; what the second
costs is the rest of the integration: the stages' algebra, the rates, the events' check, the count
of substeps. Least over the repeats, ns a call, with the substeps a step takes
(`struck_substeps`: a stiff contact's rise takes more than one).
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

from percussim.solver import controller as C
from percussim.solver.case import parse_case
from percussim.solver.controller import warm_up
from percussim.solver.grid import explicit_numerics, make_grid
from percussim.solver.kernel import bundles as B
from percussim.solver.kernel.contact import contact_spring
from percussim.solver.kernel.struck_end import struck_end_step, struck_substeps
from percussim.solver.kernel.working_end import working_end_step
from percussim.solver.simulate import simulate
from percussim.testing import at_default_accuracy

PRESETS = ("fig3", "fig5", "fig9")


@numba.njit
def struck_calls(calls, start, state, waves, contact, striker, anvil, force, events, tau):
    kept = 0.0  # read, so that no call is left out
    for _ in range(calls):
        state[:] = start
        kept += struck_end_step(0.0, tau, state, waves, contact, striker, anvil, force, events)[0] + state[0]
    return kept


@numba.njit
def working_calls(calls, start, state, tau, v_in, medium):
    kept = 0.0
    for _ in range(calls):
        state[:] = start
        kept += working_end_step(tau, state, v_in, 0.0, medium)[0] + state[0]
    return kept


def least(run, repeats: int, calls: int) -> float:
    """ns a call, least over `repeats`."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        run(calls)
        best = min(best, time.perf_counter() - start)
    return best / calls * 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--calls", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    warm_up()
    print(f"{'':15s} {'pressed':>15s} {'pressed, linear':>15s} {'apart':>15s} {'working end':>12s}")
    print(f"{'preset':8s} {'cells':>6s}" + 3 * f" {'ns':>7s} {'subst.':>7s}" + f" {'ns':>12s}")
    for name in PRESETS:
        data = at_default_accuracy(name)
        summary = simulate(data).summary
        case = parse_case(data)
        numerics = explicit_numerics(case, summary["runs"][-1]["cells"])
        grid = make_grid(case.tool, numerics.cells, end_masses=False)
        contact, medium = C.end_conditions(case, grid)
        anvil = C.anvil_on(case, grid, contact)
        force = C.force_law(case.force)
        striker = B.StrikerEnd(elastic=False, impedance=1.0, mass=case.striker.mass, weight=0.0)
        tau = numerics.time_step
        # the overlap of half the peak force, on the preset's law
        overlap = (0.5 * summary["peak_contact_force"]["value"] / contact.stiffness) ** (1.0 / (1.0 + contact.exponent))
        spring = contact_spring(overlap, contact)[0]
        linear = contact._replace(exponent=0.0, stiffness=spring / overlap)
        events = np.zeros((4, 4))
        waves = (0.0, 0.0, 0.0, 0.0)
        columns = []
        for law, gap in ((contact, overlap), (linear, overlap), (contact, -overlap)):
            start = np.zeros(B.STRUCK_END_STATE)
            start[B.END_STRIKER_DISP] = gap
            start[B.END_STRIKER_VELOCITY] = case.impact_velocity
            start[B.END_CONTACT_FORCE] = start[B.END_ANVIL_FORCE] = spring if gap > 0 else 0.0
            start[B.END_IN_CONTACT] = float(gap > 0)
            state = start.copy()
            ns = least(
                lambda calls, law=law, start=start, state=state: struck_calls(
                    calls, start, state, waves, law, striker, anvil, force, events, tau
                ),
                args.repeats,
                args.calls,
            )
            x = (gap, case.impact_velocity, 0.0, 0.0, 0.0)
            columns.append(
                f" {ns:7.0f} {struck_substeps(x, start[B.END_CONTACT_FORCE], tau, 0.0, law, striker, anvil, tau):7d}"
            )
        far = np.zeros(B.WORKING_END_STATE)
        far_state = far.copy()
        working = least(lambda calls: working_calls(calls, far, far_state, tau, 1.0, medium), args.repeats, args.calls)
        print(f"{name:8s} {numerics.cells:6d}{''.join(columns)} {working:12.0f}")


if __name__ == "__main__":
    main()
