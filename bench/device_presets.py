"""The rock-drill and pile presets at the default accuracy: time, grids, the summary's headline
numbers beside the closed forms of their first blow, a sweep of the piston's length against
Lundberg's efficiency, and the pile blow after blow.

    .venv/bin/python bench/device_presets.py [--repeats 10] [--write]

Times are the least of `--repeats` runs after compilation (`percussim.simulate`, one process).
The closed forms (`percussim/testing/reference.py`): the rock drill's piston, of the rod's impedance Z, sends
Z·v/2 for 2L_p/a, and Lundberg's bilinear rock gives the bit's peak force, the penetration and the
rock's share of the energy (`LundbergRock`); the pile's ram strikes with m·g·η·h, and Smith's
soil at the toe, unloaded from R_u, springs back by its quake and takes R_u·set as plastic work.
The pile's bearing graph follows (`solver.pile_studies.bearing_graph`).

`--write` puts the tables in README.md between its `device presets` markers, and the bearing
graph's plot in docs/images/pile_bearing_graph.png.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from marked import write_marked

from percussim.solver.pile_studies import bearing_graph
from percussim.solver.presets import load_preset, preset_json
from percussim.solver.simulate import run_sweep, simulate
from percussim.solver.study_plots import render_study
from percussim.solver.sweep import Sweep, variants
from percussim.testing.reference import LundbergRock

ROOT = Path(__file__).resolve().parents[1]

PISTON_LENGTHS = (0.1, 0.2, 0.3, 0.5, 0.8)
PILE_BLOWS = 4
PILE_CAPACITIES = (0.5e6, 1.0e6, 1.5e6, 2.0e6, 2.5e6, 3.0e6, 3.5e6, 4.0e6)
FIGURE = ROOT / "docs" / "images" / "pile_bearing_graph.png"


def timed(name: str, repeats: int) -> tuple[dict, float]:
    """The preset's summary at the default accuracy and the least time of `repeats` runs (ms)."""
    case = load_preset(name)
    summary = simulate(case).summary  # compiles
    best = min(_seconds(case) for _ in range(repeats))
    return summary, 1e3 * best


def _seconds(case) -> float:
    start = time.perf_counter()
    simulate(case)
    return time.perf_counter() - start


def rows_of(summary: dict, expected: dict[str, float | None]) -> list[str]:
    """Table rows: quantity, the solver's value, the closed form's (— where there is none)."""
    found = {
        "peak contact force (N)": summary["peak_contact_force"]["value"],
        "its time (s)": summary["peak_contact_force"]["time"],
        "max compressive stress (Pa)": summary["max_compressive_stress"]["value"],
        "transfer efficiency": summary["energy"]["transfer_efficiency"],
        "max penetration (m)": summary["medium_penetration"]["max"],
        "permanent penetration (m)": summary["medium_penetration"]["permanent"],
    }
    return [
        f"| {name} | {value:.4g} | {'—' if expected.get(name) is None else f'{expected[name]:.4g}'} |"
        for name, value in found.items()
    ]


def rock_table(summary: dict) -> list[str]:
    case = load_preset("rock_drill")
    rock = LundbergRock.of_case(case)
    return rows_of(
        summary,
        {
            "peak contact force (N)": rock.incident,
            "max compressive stress (Pa)": rock.peak_force / case.tool.area,
            "transfer efficiency": rock.efficiency,
            "max penetration (m)": rock.max_penetration,
            "permanent penetration (m)": rock.permanent_penetration,
        },
    )


def pile_table(summary: dict) -> list[str]:
    case = load_preset("pile")
    ram, soil = case.striker, case.medium
    permanent = summary["medium_penetration"]["permanent"]
    return rows_of(summary, {"max penetration (m)": permanent + soil.quake}) + [
        f"| energy at impact (J) | {summary['energy']['initial']:.4g} | "
        f"{ram.mass * 9.81 * ram.efficiency * ram.stroke:.4g} (m·g·η·h) |",
        f"| transferred energy, EMX (J) | {summary['energy']['transferred']:.4g} | — |",
        f"| plastic work at the toe (J) | {summary['energy']['medium_plastic']:.4g} | "
        f"{soil.ultimate_resistance * permanent:.4g} (R_u·set) |",
        f"| blow count (1/m) | {summary['blow_count']:.4g} | — |",
    ]


def pile_bearing_graph(figure: Path | None) -> list[str]:
    """The pile preset's bearing graph, the toe keeping its share: a row per capacity; its plot
    to `figure` when given."""
    answer = bearing_graph({"case": preset_json("pile"), "capacity": list(PILE_CAPACITIES)}, processes=1)
    if figure is not None:
        figure.write_bytes(render_study(answer, "bearing_graph", "png", "pile"))
    lines = [
        "| capacity (MN) | blows run | set (mm) | blow count (1/m) | max compression (MPa) | max tension (MPa) "
        "| EMX (kJ) | estimated error |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in answer["rows"]:
        count = "refusal" if row["blow_count"] is None else f"{row['blow_count']:.4g}"
        lines.append(
            f"| {row['ultimate_resistance'] / 1e6:g} | {row['blows']} | {row['set'] * 1e3:.4g} | {count} | "
            f"{row['max_compressive_stress'] / 1e6:.4g} | {row['max_tensile_stress'] / 1e6:.4g} | "
            f"{row['transferred_energy'] / 1e3:.4g} | {row['error_estimate']:.1e} |"
        )
    return lines


def piston_sweep() -> list[str]:
    sweep = Sweep(case=preset_json("rock_drill"), parameters={"striker.length": list(PISTON_LENGTHS)})
    lines = [
        "| piston length (m) | Lundberg's x | transfer efficiency | Lundberg | permanent penetration (m) |",
        "|---|---|---|---|---|",
    ]
    for row, (_, case) in zip(run_sweep(sweep, processes=1), variants(sweep)):
        expected = LundbergRock.of_case(case)
        lines.append(
            f"| {row['striker.length']:g} | {expected.x:.3f} | {row['transfer_efficiency']:.4f} | "
            f"{expected.efficiency:.4f} | {row['permanent_penetration']:.4g} |"
        )
    return lines


def pile_blows() -> list[str]:
    case = preset_json("pile") | {"blows": {"count": PILE_BLOWS}}
    blows = simulate(case).summary["blows"]
    lines = [
        "| blow | peak contact force (N) | max compressive stress (Pa) | transfer efficiency | set (m) |",
        "|---|---|---|---|---|",
    ]
    for k, blow in enumerate(blows, 1):
        lines.append(
            f"| {k} | {blow['peak_contact_force']:.4g} | {blow['max_compressive_stress']:.4g} | "
            f"{blow['transfer_efficiency']:.4f} | {blow['set']:.4g} |"
        )
    return lines


def report(repeats: int, figure: Path | None = None) -> str:
    rock, rock_ms = timed("rock_drill", repeats)
    pile, pile_ms = timed("pile", repeats)
    head = ["| quantity | solver | closed form |", "|---|---|---|"]

    def grids(summary: dict) -> str:
        return ", ".join(str(r["cells"]) for r in summary["runs"])

    return "\n".join(
        [
            f"Each at the default accuracy (1%), least of {repeats} runs after compilation "
            "(`bench/device_presets.py --write`).",
            "",
            f"`rock_drill`: {rock_ms:.1f} ms, grids of {grids(rock)} cells, estimated error "
            f"{rock['error_estimate']['worst']:.1e}.",
            "",
            *head,
            *rock_table(rock),
            "",
            f"`pile`: {pile_ms:.1f} ms, grids of {grids(pile)} cells, estimated error "
            f"{pile['error_estimate']['worst']:.1e}.",
            "",
            *head,
            *pile_table(pile),
            "",
            "The rock drill's piston length swept (`striker.length`): the efficiency rises to Lundberg's "
            "optimum (x = 1.2564) and falls past it.",
            "",
            *piston_sweep(),
            "",
            f"The pile, {PILE_BLOWS} blows (`blows.count`): before each the helmet rests on the pile again, "
            "the soil's state carried from the blow before; the set settles.",
            "",
            *pile_blows(),
            "",
            "The pile's bearing graph (`percussim bearing-graph pile --capacity 0.5e6:4e6:8`): each capacity "
            "split as the preset's, 71% at the toe, and driven until its set settles.",
            "",
            "![the pile preset's bearing graph](docs/images/pile_bearing_graph.png)",
            "",
            *pile_bearing_graph(figure),
        ]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument("--write", action="store_true", help="write the tables into README.md")
    args = parser.parse_args()
    text = report(args.repeats, FIGURE if args.write else None)
    print(text)
    if args.write:
        write_marked(ROOT / "README.md", "device presets", text)


if __name__ == "__main__":
    main()
