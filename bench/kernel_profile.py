"""Where a run's time goes, by compiled function: a preset on one grid of the default accuracy's
scheme, run over and over under Linux `perf record`, each sample counted to the kernel's function
its address falls in, to the C library's function it is in (libm's `sin`, `pow`), or to Python.

    .venv/bin/python bench/kernel_profile.py [--presets fig3 fig9] [--cells 128] [--seconds 5]

Needs `perf` (Debian's linux-perf) with permission to sample (`kernel.perf_event_paranoid` ≤ 2,
or root), and `nm` (binutils). Numba compiles the kernel into memory that no file names, so perf
cannot name it: the runs' process finds each of the solver's compiled functions in the compiled
kernel's cache (its name and size, from the object code there) and asks Numba's JIT engine where it
was loaded. A function compiled `inline="always"` is part of every function that calls it: most
of a step (the tool's interior, the incoming waves, the working end, the ends' audit, the records)
is inside `advance`; the struck end's step (`struck_end_step`), its contact balance
(`solve_spring_balance`) and the pass along the tool for its energy and stresses
(`tool_energy_and_stresses`) are functions of their own. Only the samples of the timed runs count
(`perf record -k CLOCK_MONOTONIC`: the runs' process gives their start and end on that clock).

Prints each part's share of the samples and what that share is of a step: the least time of a run
over its steps, so that Python's line is the run's fixed cost spread over its steps.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from bisect import bisect_right
from collections import Counter
from pathlib import Path

SAMPLE = re.compile(r"^\s*(\d+\.\d+):\s+([0-9a-f]+)\s+(.*?)\s+\((.*)\)\s*$")


def readable(symbol: str) -> str:
    """`module.function` of a Numba function's mangled name (`_ZN9percussim6solver…`), with
    `(from Python)` for the wrapper that unboxes its arguments."""
    wrapper = symbol.startswith("_ZN7cpython")
    parts, rest = [], symbol[len("_ZN7cpython") if wrapper else len("_ZN") :]
    while (digits := re.match(r"\d+", rest)) is not None:
        length = int(digits[0])
        parts.append(rest[len(digits[0]) : len(digits[0]) + length])
        rest = rest[len(digits[0]) + length :]
    name = ".".join(parts[-2:])
    return f"{name} (from Python)" if wrapper else name


def kernel_functions() -> list[tuple[int, int, str]]:
    """(start address, size, name) of each of the solver's compiled functions this process has
    loaded: their names and sizes from the object code in the compiled kernel's cache, their
    addresses from Numba's JIT engine (`codegen()._engine`, an internal of Numba's)."""
    from numba.core.registry import cpu_target

    from percussim.solver.compiled import cache_folder

    engine = cpu_target.target_context.codegen()._engine
    functions = []
    for path in Path(cache_folder()).rglob("*.nbc"):
        data = path.read_bytes()
        if (elf := data.find(b"\x7fELF")) < 0:
            continue
        with tempfile.NamedTemporaryFile(suffix=".o") as code:
            code.write(data[elf:])
            code.flush()
            symbols = subprocess.run(["nm", "-S", "--defined-only", code.name], capture_output=True, text=True)
        for line in symbols.stdout.splitlines():
            fields = line.split()
            if (
                len(fields) == 4
                and fields[2] in "Tt"
                and fields[3].startswith(("_ZN9percussim", "_ZN7cpython9percussim"))
            ):
                address = engine._ee.get_function_address(fields[3])
                if address:
                    functions.append((address, int(fields[1], 16), readable(fields[3])))
    return sorted(functions)


def run_for(preset: str, cells: int, seconds: float, table: Path) -> None:
    """The runs' process: the preset on `cells` cells again and again for `seconds`; writes the
    kernel's functions and the runs' clock to `table`."""
    from percussim.solver.case import parse_case
    from percussim.solver.controller import simulate_rod, warm_up
    from percussim.solver.grid import explicit_numerics
    from percussim.testing import at_default_accuracy

    warm_up()
    case = parse_case(at_default_accuracy(preset)).summary_only()
    numerics = explicit_numerics(case, cells)
    simulate_rod(case, numerics=numerics)
    functions = kernel_functions()
    least, runs = float("inf"), 0
    start = time.clock_gettime(time.CLOCK_MONOTONIC)
    while time.clock_gettime(time.CLOCK_MONOTONIC) < start + seconds:
        began = time.perf_counter()
        simulate_rod(case, numerics=numerics)
        least = min(least, time.perf_counter() - began)
        runs += 1
    end = time.clock_gettime(time.CLOCK_MONOTONIC)
    table.write_text(
        json.dumps(
            {"functions": functions, "start": start, "end": end, "least": least, "runs": runs, "steps": numerics.steps}
        )
    )


def attribute(samples: str, functions: list[tuple[int, int, str]], start: float, end: float) -> Counter:
    """Samples of `perf script -F time,ip,sym,dso` within [start, end], by part."""
    addresses = [a for a, _, _ in functions]
    parts: Counter = Counter()
    for line in samples.splitlines():
        match = SAMPLE.match(line)
        if not match or not start <= float(match[1]) <= end:
            continue
        ip, symbol, dso = int(match[2], 16), match[3], match[4]
        if "libm" in dso:
            parts[f"libm {symbol}"] += 1
        elif "libpython" in dso or "site-packages" in dso or "lib-dynload" in dso:
            parts["Python (set-up, summary, NumPy)"] += 1
        elif (k := bisect_right(addresses, ip)) > 0 and ip < functions[k - 1][0] + functions[k - 1][1]:
            parts[functions[k - 1][2]] += 1
        elif dso.startswith("/tmp/perf-"):  # perf's name for code no file holds: compiled, not from the cache
            parts["compiled, not in the cache"] += 1
        else:
            parts["other (system)"] += 1
    return parts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--presets", nargs="+", default=["fig3", "fig9"])
    parser.add_argument("--cells", type=int, default=128)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--run-for", help=argparse.SUPPRESS)  # the runs' process
    parser.add_argument("--table", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.run_for:
        run_for(args.run_for, args.cells, args.seconds, args.table)
        return
    if shutil.which("perf") is None:
        sys.exit("needs Linux perf (Debian: apt-get install linux-perf)")
    for preset in args.presets:
        with tempfile.TemporaryDirectory() as folder:
            data, table = Path(folder) / "perf.data", Path(folder) / "table.json"
            command = [sys.executable, __file__, "--run-for", preset, "--cells", str(args.cells)]
            command += ["--seconds", str(args.seconds), "--table", str(table)]
            subprocess.run(
                ["perf", "record", "-q", "-k", "CLOCK_MONOTONIC", "-o", str(data), "--", *command], check=True
            )
            samples = subprocess.run(
                ["perf", "script", "-i", str(data), "-F", "time,ip,sym,dso"],
                capture_output=True,
                text=True,
                check=True,
                env={**os.environ, "PAGER": "cat"},
            ).stdout
            run = json.loads(table.read_text())
        parts = attribute(samples, [tuple(f) for f in run["functions"]], run["start"], run["end"])
        total = sum(parts.values())
        step_ns = run["least"] / run["steps"] * 1e9
        print(
            f"{preset} on {args.cells} cells, {run['steps']} steps: {run['least'] * 1e3:.3f} ms a run "
            f"(least of {run['runs']}), {step_ns:.0f} ns a step; {total} samples"
        )
        for part, count in parts.most_common():
            print(f"  {part:34s} {count / total:6.1%} {count / total * step_ns:7.0f} ns a step")


if __name__ == "__main__":
    main()
