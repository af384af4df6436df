"""`percussim`: run an impact case from the command line."""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

EXIT_FAILED, EXIT_INVALID = 1, 2


def _no_such_file(path: str) -> int:
    print(f"percussim: no such case file: {path}", file=sys.stderr)
    return EXIT_INVALID


def _refused(what: str, error) -> int:
    """Name every offending field of a refused case or sweep on stderr."""
    print(f"percussim: invalid {what}:", file=sys.stderr)
    for e in error.errors:
        print(f"  {e.field}: {e.message}", file=sys.stderr)
    return EXIT_INVALID


def _run(args: argparse.Namespace) -> int:
    from .case import CaseError, load_case
    from .controller import NumericalFailure
    from .simulate import simulate

    try:
        case = load_case(args.case)
        # The result file is streamed to as the run goes: a long run's outputs never sit in memory.
        result = simulate(case, model=args.model, result_path=args.output)
    except FileNotFoundError:
        return _no_such_file(args.case)
    except CaseError as error:
        return _refused(f"case {args.case}", error)
    except NumericalFailure as error:
        print(f"percussim: {error}", file=sys.stderr)
        return EXIT_FAILED
    # Files first: a closed stdout (`| head`) must not lose the summary.
    text = json.dumps(result.summary, indent=2)
    if args.summary:
        Path(args.summary).write_text(text + "\n")
    for warning in result.summary["warnings"]:
        print(f"percussim: warning: {warning}", file=sys.stderr)
    print(text)
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from .case import CaseError, load_case
    from .sweep import Sweep, run_sweep

    try:
        sweep = Sweep(case=load_case(args.case), parameters=dict(args.vary))
        rows = run_sweep(sweep, processes=args.processes, progress=lambda done, total: print(
            f"\rpercussim: {done}/{total} variants", end="", file=sys.stderr, flush=True))
    except FileNotFoundError:
        return _no_such_file(args.case)
    except CaseError as error:
        return _refused(f"sweep of {args.case}", error)
    print(file=sys.stderr)
    columns = list(dict.fromkeys(key for row in rows for key in row))
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=columns)
            writer.writeheader()
            writer.writerows(rows)
    print("\t".join(columns))
    for row in rows:
        print("\t".join(_cell(row.get(c)) for c in columns))
    return EXIT_FAILED if any("error" in r for r in rows) else 0


def _cell(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else "" if value is None else str(value)


def _parameter(text: str) -> tuple[str, list]:
    """`path=v1,v2,...`: each value as JSON (numbers, true, "text") or else as a string."""
    path, sep, values = text.partition("=")
    if not (sep and path and values):
        raise argparse.ArgumentTypeError(f"expected FIELD=V1,V2,... (e.g. striker.velocity=3,5,7), not {text!r}")

    def value(item: str):
        try:
            return json.loads(item)
        except ValueError:
            return item

    return path, [value(v) for v in values.split(",")]


def _warmup(args: argparse.Namespace) -> int:
    from .controller import warm_up

    warm_up()
    return 0


def _worker(args: argparse.Namespace) -> int:
    from worker.main import run_worker

    run_worker(concurrency=args.concurrency, loglevel=args.loglevel, name=args.name)
    return 0


def _serve(args: argparse.Namespace) -> int:
    from service.main import run_service

    run_service(host=args.host, port=args.port, workers=args.workers, start_workers=not args.no_worker)
    return 0


def _count(text: str) -> int:
    """A number of processes: a whole number, 0 or more."""
    if not (text.isascii() and text.isdigit()):
        raise argparse.ArgumentTypeError(f"must be a whole number, 0 or more, not {text!r}")
    return int(text)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="percussim", description=__doc__)
    commands = p.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="solve a case locally and print its pulse summary")
    run.add_argument("case", help="impact case JSON")
    run.add_argument("--summary", metavar="OUT.json", help="also write the summary here")
    run.add_argument("--output", metavar="RESULT.h5", help="write the full result (HDF5) here")
    run.add_argument("--model", choices=["rod", "lumped"],
                     help="override numerics.model: the elastic rod or the two-mass model problem")
    run.set_defaults(handler=_run)
    sweep = commands.add_parser("sweep", help="solve every combination of some fields' values, on every core")
    sweep.add_argument("case", help="the base impact case JSON")
    sweep.add_argument("--vary", type=_parameter, action="append", required=True, metavar="FIELD=V1,V2,...",
                       help="a field path and its values (repeat for a grid), e.g. striker.velocity=3,5,7")
    sweep.add_argument("--processes", type=_count, help="processes (default: one a core)")
    sweep.add_argument("--csv", metavar="OUT.csv", help="also write the table here")
    sweep.set_defaults(handler=_sweep)
    warm = commands.add_parser("warmup", help="compile the kernel into Numba's cache (done at install)")
    warm.set_defaults(handler=_warmup)
    work = commands.add_parser("worker", help="run a queue worker (PERCUSSIM_BROKER_URL; none: embedded)")
    work.add_argument("--concurrency", type=int, default=1, help="jobs run at once (processes)")
    work.add_argument("--loglevel", default="info")
    work.add_argument("--name", help="worker name (default percussim@HOST)")
    work.set_defaults(handler=_worker)
    serve = commands.add_parser("serve", help="run the HTTP API (embedded: with its own workers)")
    serve.add_argument("--host", default="127.0.0.1")
    serve.add_argument("--port", type=int, default=8000)
    started = serve.add_mutually_exclusive_group()
    started.add_argument("--workers", type=_count, metavar="N",
                         help="queue workers to start (default: 1 embedded, 0 with PERCUSSIM_BROKER_URL)")
    started.add_argument("--no-worker", action="store_true", help="run the API alone")
    serve.set_defaults(handler=_serve)
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    return args.handler(args)


if __name__ == "__main__":
    sys.exit(main())
