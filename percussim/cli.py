"""`percussim`: run an impact case from the command line."""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TypeVar

EXIT_FAILED, EXIT_INVALID, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 1, 2, 130, 141
T = TypeVar("T")
PROGRESS_DELAY = 2.0  # s: a run done sooner shows no progress bar
# What the optional installs bring (pyproject.toml's extras): a command needing one says which.
EXTRA_OF = {
    "fastapi": "service",
    "starlette": "service",
    "uvicorn": "service",
    "celery": "service",
    "kombu": "service",
    "redis": "service",
    "matplotlib": "plots",
}


def _no_such_file(path: str) -> int:
    print(f"percussim: no such case file or preset: {path} (`percussim presets` lists the presets)", file=sys.stderr)
    return EXIT_INVALID


def _case_source(arg: str) -> str | dict:
    """The CASE argument: a case JSON file, or else a preset's name (its case JSON); a name that
    is neither stays a path, whose reading then fails as a missing file."""
    from .solver.presets import preset_json, preset_names

    return preset_json(arg) if not Path(arg).exists() and arg in preset_names() else arg


def _refused(what: str, error) -> int:
    """Name every offending field of a refused case or sweep on stderr."""
    print(f"percussim: invalid {what}:", file=sys.stderr)
    for e in error.errors:
        print(f"  {e.field}: {e.message}", file=sys.stderr)
    return EXIT_INVALID


@contextmanager
def _progress_bar(forced: bool) -> Iterator[Callable[[float], None]]:
    """A progress bar on stderr, moved by calling it with the fraction done (0..1). Shown only on
    a terminal and once the run has taken PROGRESS_DELAY, unless `forced`; stdout is left to the summary."""
    from tqdm import tqdm

    with tqdm(
        total=1.0,
        file=sys.stderr,
        delay=0 if forced else PROGRESS_DELAY,
        disable=not (forced or sys.stderr.isatty()),
        bar_format="percussim: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}",
    ) as bar:
        yield lambda fraction: bar.update(fraction - bar.n)


def _print_summary(summary: dict, path: str | None) -> int:
    """Write the summary to `path` if asked, its warnings to stderr, and print it."""
    # Files first: a closed stdout (`| head`) must not lose the summary.
    text = json.dumps(summary, indent=2)
    if path:
        Path(path).write_text(text + "\n")
    for warning in summary["warnings"]:
        print(f"percussim: warning: {warning}", file=sys.stderr)
    print(text)
    return 0


def _limits():
    """The size limits of local runs: the service's settings (`PERCUSSIM_MAX_*`) read here too."""
    from percussim.common.settings import load

    return load().limits()


def _run(args: argparse.Namespace) -> int:
    from .solver.case import CaseError
    from .solver.errors import NumericalFailure
    from .solver.simulate import simulate

    try:
        case = _case_source(args.case)
        with _progress_bar(args.progress) as advance:
            # The result file is streamed to as the run goes: a long run's outputs never sit in memory.
            result = simulate(case, model=args.model, result_path=args.output, progress=advance, limits=_limits())
    except FileNotFoundError:
        return _no_such_file(args.case)
    except CaseError as error:
        return _refused(f"case {args.case}", error)
    except NumericalFailure as error:
        print(f"percussim: {error}", file=sys.stderr)
        return EXIT_FAILED
    return _print_summary(result.summary, args.summary)


def _submit(args: argparse.Namespace) -> int:
    from .client import Client, Refused, ServiceError

    if args.no_wait and (args.summary or args.output):
        print("percussim: --no-wait writes no --summary or --output: the job has not run yet", file=sys.stderr)
        return EXIT_INVALID
    try:
        with Client(args.url, api_key=args.api_key) as api:
            case = _case_source(args.case)
            if args.no_wait:
                print(json.dumps(api.submit(case), indent=2))
                return 0
            try:
                job_id = _submit_and_wait(api, lambda: api.submit(case), args.progress)
            except KeyboardInterrupt:
                return EXIT_INTERRUPTED
            if args.output:
                api.download(job_id, args.output)
            summary = api.summary(job_id)
    except FileNotFoundError:
        return _no_such_file(args.case)
    except Refused as error:
        return _refused(f"case {args.case}", error)
    except ServiceError as error:  # a failed or cancelled job, an unreachable service, a bad key
        print(f"percussim: {error}", file=sys.stderr)
        return EXIT_FAILED
    return _print_summary(summary, args.summary)


@contextmanager
def _ctrl_c_after_the_answer() -> Iterator[None]:
    """Ctrl-C while a submission is on its way takes effect once the service has answered (as
    KeyboardInterrupt, where the block ends): only the answer names what to cancel, and a job
    whose submission was cut off would run on unseen."""
    import signal

    pressed = []
    previous = signal.signal(signal.SIGINT, lambda *_: pressed.append(True))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if pressed:
        raise KeyboardInterrupt


def _submit_and_wait(api, submit: Callable[[], dict], progress: bool) -> str:
    """Submit a job (or a study) to the service and wait for it with a progress bar; Ctrl-C
    cancels it, as it stops a local run, rather than leave it running unseen, and raises
    KeyboardInterrupt. The job's id."""
    try:
        with _ctrl_c_after_the_answer():
            job_id = submit()["id"]
        with _progress_bar(progress) as advance:
            api.wait(job_id, progress=lambda fraction, record: advance(fraction))
    except KeyboardInterrupt:
        api.cancel(job_id)
        print(f"percussim: cancelled job {job_id}", file=sys.stderr)
        raise
    return job_id


def _presets(args: argparse.Namespace) -> int:
    from textwrap import shorten

    from .solver.presets import preset_json, preset_names

    def text(name: str) -> str:
        return json.dumps(preset_json(name), indent=2, ensure_ascii=False) + "\n"

    if args.write:
        folder = Path(args.write)
        folder.mkdir(parents=True, exist_ok=True)
        for name in preset_names():
            (folder / f"{name}.json").write_text(text(name))
        return 0
    if args.name is None:
        if args.output:
            print("percussim: -o writes one preset: name it", file=sys.stderr)
            return EXIT_INVALID
        width = max(map(len, preset_names()), default=0)
        for name in preset_names():
            print(f"{name:<{width}}  {shorten(preset_json(name).get('description', ''), 100, placeholder=' …')}")
        return 0
    try:
        case = text(args.name)
    except KeyError as error:
        print(f"percussim: {error.args[0]}", file=sys.stderr)
        return EXIT_INVALID
    if args.output:
        Path(args.output).write_text(case)
    else:
        print(case, end="")
    return 0


def _guarded(args: argparse.Namespace, what: str, work: Callable[[], T]) -> T | int:
    """`work()` on the command's case, here or on the service at `args.url`; or the exit status of
    what stopped it: a missing file, a refusal naming the fields (here or by the service), the
    service's error (a failed or cancelled job, no answer, a bad key), or Ctrl-C."""
    from .client import Refused, ServiceError
    from .solver.case import CaseError

    try:
        return work()
    except FileNotFoundError as error:
        return _no_such_file(error.filename or args.case)
    except (CaseError, Refused) as error:
        return _refused(f"{what} of {args.case}", error)
    except ServiceError as error:
        print(f"percussim: {error}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        if not args.url:  # on a service, the cancel said what was stopped
            print("\npercussim: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _sweep(args: argparse.Namespace) -> int:
    rows = _guarded(args, "sweep", lambda: _sweep_on_service(args) if args.url else _sweep_here(args))
    if isinstance(rows, int):
        return rows
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
    return EXIT_FAILED if any("error" in r or r.get("status", "succeeded") != "succeeded" for r in rows) else 0


def _variants_done(done: int, total: int) -> None:
    print(f"\rpercussim: {done}/{total} variants", end="", file=sys.stderr, flush=True)


def _sweep_here(args: argparse.Namespace) -> list[dict]:
    """Every variant solved on this machine's cores: a row each, the values then the columns."""
    from .solver.case import as_case
    from .solver.simulate import run_sweep
    from .solver.sweep import Sweep

    sweep = Sweep(case=as_case(_case_source(args.case)), parameters=dict(args.vary))
    return run_sweep(sweep, processes=args.processes, progress=_variants_done, limits=_limits())


def _sweep_on_service(args: argparse.Namespace) -> list[dict]:
    """Every variant a job on the service at `args.url`: a row each, the values then the job, its
    status and the columns. Ctrl-C cancels the variants not yet finished."""
    from .client import FINISHED, Client

    with Client(args.url, api_key=args.api_key) as api:
        case = _case_source(args.case)
        try:
            with _ctrl_c_after_the_answer():
                sweep = api.submit_sweep(case, dict(args.vary))
            done = api.wait_sweep(
                sweep["id"],
                progress=lambda fraction, s: _variants_done(
                    sum(s["counts"].get(status, 0) for status in FINISHED), s["total"]
                ),
            )
        except KeyboardInterrupt:
            api.cancel_sweep(sweep["id"])
            print(f"\npercussim: cancelled sweep {sweep['id']}", file=sys.stderr)
            raise
    return [row.pop("values") | row for row in done["rows"]]


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


def _times(text: str) -> list[float]:
    from .solver.plots import parse_times

    try:
        return parse_times(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _plots(args: argparse.Namespace) -> int:
    from .solver.plots import write_plots

    result = Path(args.result)
    if not result.is_file():
        print(f"percussim: no such result file: {result}", file=sys.stderr)
        return EXIT_INVALID
    try:
        written, skipped = write_plots(
            result,
            args.out or result.with_name(f"{result.stem}-plots"),
            formats=args.format,
            names=args.only,
            times=args.times,
        )
    except ValueError as error:  # not a result, an unknown plot or format, a time outside the run
        print(f"percussim: {error}", file=sys.stderr)
        return EXIT_INVALID
    for name, reason in skipped.items():
        print(f"percussim: skipped {name}: {reason}", file=sys.stderr)
    for path in written:
        print(path)
    return 0 if written else EXIT_FAILED


def _bounds(text: str) -> tuple[str, list[float]]:
    """`path=LOW:HIGH`, two numbers."""
    path, sep, pair = text.partition("=")
    low, colon, high = pair.partition(":")
    try:
        if not (sep and path and colon):
            raise ValueError
        return path, [float(low), float(high)]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected FIELD=LOW:HIGH (e.g. contact.stiffness=1e9:1e13), not {text!r}"
        ) from None


def _limit(text: str) -> tuple[str, dict]:
    """`QUANTITY<=VALUE` or `QUANTITY>=VALUE`."""
    for sign, side in (("<=", "max"), (">=", "min")):
        name, found, value = text.partition(sign)
        if found:
            try:
                return name.strip(), {side: float(value)}
            except ValueError:
                break
    raise argparse.ArgumentTypeError(
        f"expected QUANTITY<=VALUE or QUANTITY>=VALUE (e.g. max_compressive_stress<=250e6), not {text!r}"
    )


def _save_study(answer: dict, args: argparse.Namespace, plot: str) -> None:
    """The full answer to --output, its plot to --plot (format from the extension)."""
    from .solver.study_plots import render_study

    if args.output:
        Path(args.output).write_text(json.dumps(answer, indent=2) + "\n")
    if args.plot:
        fmt = Path(args.plot).suffix.lstrip(".").lower() or "png"
        Path(args.plot).write_bytes(render_study(answer, plot, fmt, name=Path(args.case).stem))


def _write_study(answer: dict, args: argparse.Namespace, plot: str, shown: dict) -> None:
    """The full answer to --output, its plot to --plot, `shown` to stdout and the warnings to
    stderr."""
    _save_study(answer, args, plot)
    for warning in answer.get("warnings", []):
        print(f"percussim: warning: {warning}", file=sys.stderr)
    print(json.dumps(shown, indent=2))


def _study(args: argparse.Namespace, what: str, request: Callable[[], dict], solve: Callable[..., dict]) -> dict | int:
    """Run a study (`what`: a calibration, an optimisation, a signal match) here, or on the service
    at `args.url`; the answer, or the exit status of a refusal or a failure."""

    def work() -> dict:
        if args.url:
            return _study_on_service(args, what, request())
        with _progress_bar(args.progress) as advance:
            return solve(request(), processes=args.processes, progress=advance, limits=_limits())

    return _guarded(args, what, work)


# What each study is called on the service: the client's submit and view, and the answer's name in
# the view (None: the view is the answer, its rows beside the job's record).
ON_SERVICE = {
    "calibration": ("submit_calibration", "calibration", "fit"),
    "optimisation": ("submit_optimization", "optimization", "optimum"),
    "bearing graph": ("submit_bearing_graph", "bearing_graph", None),
    "drivability": ("submit_drivability", "drivability", None),
    "signal match": ("submit_signal_match", "signal_match", "match"),
}


def _study_on_service(args: argparse.Namespace, what: str, request: dict) -> dict:
    """The study as a job on the service: submitted, waited for, its answer read back."""
    from .client import Client

    submit, view, answer = ON_SERVICE[what]
    with Client(args.url, api_key=args.api_key) as api:
        study_id = _submit_and_wait(api, lambda: getattr(api, submit)(request), args.progress)
        found = getattr(api, view)(study_id)
        return found if answer is None else found[answer]


def _calibrate(args: argparse.Namespace) -> int:
    from .solver.calibrate import calibrate
    from .solver.case import as_case
    from .solver.record import CLOCK_FIELDS, read_record

    def request() -> dict:
        clock = {name: getattr(args, name) for name in CLOCK_FIELDS if getattr(args, name) is not None}
        return {
            "case": as_case(_case_source(args.case)),
            "record": read_record(args.record, **clock),
            "parameters": dict(args.fit),
        }

    fit = _study(args, "calibration", request, calibrate)
    if isinstance(fit, int):
        return fit
    _write_study(
        fit,
        args,
        "fit",
        {
            key: fit[key]
            for key in (
                "parameters",
                "correlation",
                "nrmse",
                "noise",
                "evaluations",
                "warnings",
                "record",
                "grid",
                "seconds",
            )
        },
    )
    return 0


def _match(args: argparse.Namespace) -> int:
    from .solver.case import read_case_json
    from .solver.signal_match import read_pile_record, signal_match

    def request() -> dict:
        source = _case_source(args.case)
        return {
            "case": source if isinstance(source, dict) else read_case_json(source),
            "record": read_pile_record(Path(args.record).read_text()).model_dump(),
            "parameters": dict(args.fit) if args.fit else None,
        }

    match = _study(args, "signal match", request, signal_match)
    if isinstance(match, int):
        return match
    _write_study(
        match,
        args,
        "signal_match",
        {
            key: match[key]
            for key in (
                "capacity",
                "resistance_distribution",
                "match_quality",
                "case_method",
                "parameters",
                "nrmse",
                "evaluations",
                "warnings",
                "grid",
                "seconds",
            )
        },
    )
    return 0


def _optimize(args: argparse.Namespace) -> int:
    from .solver.case import as_case
    from .solver.optimize import optimize

    def request() -> dict:
        return {
            "case": as_case(_case_source(args.case)),
            "variables": dict(args.vary),
            "objective": {"maximize": args.maximize} if args.maximize else {"minimize": args.minimize},
            "limits": {name: bound for name, bound in (args.limit or [])},
            "max_evaluations": args.evaluations,
        }

    answer = _study(args, "optimisation", request, optimize)
    if isinstance(answer, int):
        return answer
    _write_study(
        answer,
        args,
        "convergence",
        {
            key: answer[key]
            for key in ("objective", "values", "quantities", "evaluations", "stopped", "warnings", "grid", "seconds")
        },
    )
    return 0 if answer["values"] is not None else EXIT_FAILED


def _range(text: str) -> list[float]:
    """`LOW:HIGH:COUNT`: COUNT values evenly from LOW to HIGH (LOW alone for a COUNT of 1)."""
    low, high, count = (text.split(":") + ["", ""])[:3]
    try:
        values = [float(low), float(high)]
        count_ = int(count)
        if count_ < 1 or text.count(":") != 2:
            raise ValueError
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected LOW:HIGH:COUNT, COUNT a whole number ≥ 1 (e.g. 1e6:4e6:10), not {text!r}"
        ) from None
    if count_ == 1:
        return values[:1]
    return [values[0] + (values[1] - values[0]) * k / (count_ - 1) for k in range(count_)]


def _row_warnings(answer: dict, name: str) -> list[str]:
    """Each row's warnings, named by the row's value of `name`."""
    return [
        f"{name} = {row[name]:.6g}: {warning}"
        for row in answer["rows"]
        for warning in row.get("warnings", []) + ([row["error"]] if row.get("error") else [])
    ]


def _write_rows(answer: dict, args: argparse.Namespace, plot: str, first: str, totals: dict) -> int:
    """A pile study's answer: all of it to --output, its plot to --plot, its warnings and each
    row's to stderr, and a table of its rows (then `totals`) to stdout. Fails if a variant failed."""
    _save_study(answer, args, plot)
    for warning in answer["warnings"] + _row_warnings(answer, first):
        print(f"percussim: warning: {warning}", file=sys.stderr)
    columns = [first, "set", "blow_count", "max_compressive_stress", "max_tensile_stress", "transferred_energy",
               "error_estimate", "blows"]  # fmt: skip
    print("\t".join(columns))
    for row in answer["rows"]:
        print("\t".join(_cell(row.get(c)) for c in columns))
    for name, value in totals.items():
        print(f"{name}\t{_cell(value)}")
    return EXIT_FAILED if any(row.get("error") for row in answer["rows"]) else 0


def _bearing_graph(args: argparse.Namespace) -> int:
    from .solver.case import as_case
    from .solver.pile_studies import bearing_graph

    def request() -> dict:
        given = {"capacity": args.capacity, "stroke": args.stroke, "toe_share": args.toe_share}
        return {"case": as_case(_case_source(args.case))} | {k: v for k, v in given.items() if v is not None}

    answer = _study(args, "bearing graph", request, bearing_graph)
    if isinstance(answer, int):
        return answer
    return _write_rows(answer, args, "bearing_graph", answer["variable"], {})


def _drivability(args: argparse.Namespace) -> int:
    from .solver.case import CaseError, FieldError, as_case
    from .solver.pile_studies import drivability

    def request() -> dict:
        try:
            soil = json.loads(Path(args.soil).read_bytes())
        except (OSError, ValueError) as error:
            reason = "no such file" if isinstance(error, FileNotFoundError) else str(error)
            raise CaseError([FieldError(field="soil", message=f"{args.soil}: {reason}")]) from None
        return {"case": as_case(_case_source(args.case)), "soil": soil}

    answer = _study(args, "drivability", request, drivability)
    if isinstance(answer, int):
        return answer
    totals = ("total_blows", "driving_time", "refusal_depth", "driven_to", "restrike_refusal_depth")
    return _write_rows(answer, args, "drivability", "depth", {name: answer[name] for name in totals})


def _warmup(args: argparse.Namespace) -> int:
    from .solver.compiled import prune_caches
    from .solver.controller import warm_up

    warm_up(processes=min(2, os.cpu_count() or 1))  # the flight compiles beside the blow
    removed = prune_caches()
    if removed:
        print(
            f"removed the compiled kernels of {len(removed)} other version(s) of the solver, unused for a day or more"
        )
    return 0


def _worker(args: argparse.Namespace) -> int:
    from percussim.worker.main import run_worker

    run_worker(concurrency=args.concurrency, loglevel=args.loglevel, name=args.name)
    return 0


def _serve(args: argparse.Namespace) -> int:
    from percussim.service.main import run_service

    run_service(host=args.host, port=args.port, workers=args.workers, start_workers=not args.no_worker)
    return 0


def _count(text: str) -> int:
    """A number of processes: a whole number, 0 or more."""
    if not (text.isascii() and text.isdigit()):
        raise argparse.ArgumentTypeError(f"must be a whole number, 0 or more, not {text!r}")
    return int(text)


def _here_or_on_service(command: argparse.ArgumentParser, on_service: str) -> None:
    """--processes here, or --url (with --api-key) for a service instead."""
    where = command.add_mutually_exclusive_group()
    where.add_argument("--processes", type=_count, help="processes here (default: one a core)")
    where.add_argument("--url", help=on_service)
    command.add_argument(
        "--api-key",
        default=os.environ.get("PERCUSSIM_API_KEY"),
        help="with --url: sent as X-API-Key (default: $PERCUSSIM_API_KEY)",
    )


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="percussim", description=__doc__)
    commands = p.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="solve a case locally and print its pulse summary")
    run.add_argument("case", help="impact case JSON, or a preset's name")
    run.add_argument("--summary", metavar="OUT.json", help="also write the summary here")
    run.add_argument("--output", metavar="RESULT.h5", help="write the full result (HDF5) here")
    run.add_argument(
        "--model",
        choices=["rod", "lumped"],
        help="override numerics.model: the elastic rod or the two-mass model problem",
    )
    run.add_argument(
        "--progress",
        action="store_true",
        help="show the progress bar on stderr even when it is not a terminal or the run is short",
    )
    run.set_defaults(handler=_run)
    submit = commands.add_parser("submit", help="run a case on a percussim service and print its pulse summary")
    submit.add_argument("case", help="impact case JSON, or a preset's name")
    submit.add_argument(
        "--url",
        default=os.environ.get("PERCUSSIM_URL", "http://127.0.0.1:8000"),
        help="the service (default: $PERCUSSIM_URL, else http://127.0.0.1:8000)",
    )
    submit.add_argument(
        "--api-key", default=os.environ.get("PERCUSSIM_API_KEY"), help="sent as X-API-Key (default: $PERCUSSIM_API_KEY)"
    )
    submit.add_argument("--summary", metavar="OUT.json", help="also write the summary here")
    submit.add_argument("--output", metavar="RESULT.h5", help="download the full result (HDF5) here")
    submit.add_argument("--no-wait", action="store_true", help="print the queued job's record and return")
    submit.add_argument(
        "--progress",
        action="store_true",
        help="show the progress bar on stderr even when it is not a terminal or the job is short",
    )
    submit.set_defaults(handler=_submit)
    sweep = commands.add_parser(
        "sweep",
        help="solve every combination of some fields' values, on every core or on a percussim service's workers",
    )
    sweep.add_argument("case", help="the base impact case JSON, or a preset's name")
    sweep.add_argument(
        "--vary",
        type=_parameter,
        action="append",
        required=True,
        metavar="FIELD=V1,V2,...",
        help="a field path and its values (repeat for a grid), e.g. striker.velocity=3,5,7",
    )
    _here_or_on_service(sweep, "run every variant as a job on this service instead (each keeps its result there)")
    sweep.add_argument("--csv", metavar="OUT.csv", help="also write the table here")
    sweep.set_defaults(handler=_sweep)
    presets = commands.add_parser(
        "presets", help="list the presets (the paper's cases, a rock drill, a pile), or give one's case JSON"
    )
    which = presets.add_mutually_exclusive_group()
    which.add_argument("name", nargs="?", help="print this preset's case JSON")
    which.add_argument("--write", metavar="DIR", help="write every preset's case JSON into DIR as NAME.json")
    presets.add_argument("-o", "--output", metavar="FILE", help="write the named preset here instead")
    presets.set_defaults(handler=_presets)
    fit = commands.add_parser("calibrate", help="fit a case's parameters to a measured record (CSV)")
    fit.add_argument("case", help="impact case JSON, or a preset's name")
    fit.add_argument(
        "--record",
        required=True,
        metavar="RECORD.csv",
        help="header time,<quantity> (contact_force, medium_force, stress@X, "
        "struck_end_velocity, working_end_velocity), then samples in SI units; "
        "or a header <quantity> alone, one value a line, with --sample-rate (or "
        "comment lines '# sample_rate = HZ' and '# time_start = S' before the header)",
    )
    fit.add_argument(
        "--sample-rate",
        dest="sample_rate",
        type=float,
        metavar="HZ",
        help="an evenly sampled record's samples a second (its file then has no time column)",
    )
    fit.add_argument(
        "--time-start",
        dest="time_start",
        type=float,
        metavar="S",
        help="with --sample-rate: the first sample's time (default 0)",
    )
    fit.add_argument(
        "--time-offset",
        dest="time_offset",
        type=float,
        metavar="S",
        help="the model's time at the record's time 0 (a record triggered at its gauge: "
        "about x/c after the impact); left out, 0 for a record that starts at rest, "
        "else fitted (or fit it within bounds: --fit record.time_offset=LOW:HIGH)",
    )
    fit.add_argument(
        "--fit",
        type=_bounds,
        action="append",
        required=True,
        metavar="FIELD=LOW:HIGH",
        help="a parameter and its bounds (repeat), e.g. contact.stiffness=1e9:1e13",
    )
    match = commands.add_parser(
        "match", help="a pile's soil and capacity from the force and velocity measured near its head (signal matching)"
    )
    match.add_argument(
        "case", help="the pile: tool, shaft, a Smith medium and numerics, no striker (the record drives it)"
    )
    match.add_argument(
        "--record",
        required=True,
        metavar="RECORD.csv",
        help="header time,force@X,velocity@X (X: the gauges' station below the head, m), then samples in SI "
        "units (compression and velocity toward the toe positive)",
    )
    match.add_argument(
        "--fit",
        type=_bounds,
        action="append",
        metavar="FIELD=LOW:HIGH",
        help="a parameter and its bounds (repeat), e.g. shaft.0.ultimate_resistance=1e5:2e6 (default: each "
        "shaft segment's and the toe's resistance, one quake and one damping factor for the shaft, and the toe's)",
    )
    optimise = commands.add_parser(
        "optimize", help="find the fields' values that maximise or minimise a summary quantity within limits"
    )
    optimise.add_argument("case", help="impact case JSON, or a preset's name")
    optimise.add_argument(
        "--vary",
        type=_bounds,
        action="append",
        required=True,
        metavar="FIELD=LOW:HIGH",
        help="a field and its bounds (repeat), e.g. striker.length=0.1:0.8",
    )
    goal = optimise.add_mutually_exclusive_group(required=True)
    goal.add_argument("--maximize", metavar="QUANTITY", help="e.g. energy.transfer_efficiency")
    goal.add_argument("--minimize", metavar="QUANTITY", help="e.g. max_compressive_stress")
    optimise.add_argument(
        "--limit",
        type=_limit,
        action="append",
        metavar="QUANTITY<=VALUE",
        help="a limit on a summary quantity (repeat; <= or >=), e.g. max_compressive_stress<=250e6",
    )
    optimise.add_argument(
        "--evaluations",
        type=int,
        default=1000,
        metavar="N",
        help="the budget of model runs, both stages (default 1000)",
    )
    bearing = commands.add_parser(
        "bearing-graph",
        help="a pile's blow count and stresses against its capacity (bearing graph) or its ram's stroke "
        "(inspector's chart), each blow after blow until the set settles",
    )
    bearing.add_argument("case", help="a pile case JSON with Smith soil at its toe, or a preset's name")
    varied = bearing.add_mutually_exclusive_group(required=True)
    varied.add_argument(
        "--capacity",
        type=_range,
        metavar="LOW:HIGH:COUNT",
        help="ultimate capacities R_u (N), toe and shaft together, e.g. 1e6:4e6:10",
    )
    varied.add_argument(
        "--stroke",
        type=_range,
        metavar="LOW:HIGH:COUNT",
        help="the ram's strokes (m) at the case's capacity, e.g. 0.5:2:7 (the case gives striker.stroke)",
    )
    bearing.add_argument(
        "--toe-share",
        dest="toe_share",
        type=float,
        metavar="S",
        help="the toe's share of the capacity, the shaft taking the rest (default: the case's own)",
    )
    drive = commands.add_parser(
        "drivability",
        help="a pile driven into layered soil: blow count and stresses at each depth, total blows, driving "
        "time, refusal",
    )
    drive.add_argument("case", help="a pile case JSON (its hammer, cushion and pile), or a preset's name")
    drive.add_argument(
        "--soil",
        required=True,
        metavar="SOIL.json",
        help="layers (from, to, shaft_resistance, toe_resistance, quakes, damping factors, setup_factor), "
        "depths, blow_rate, refusal: see docs/piling.md",
    )
    for study, plotted in (
        (fit, "the record against the model"),
        (match, "the force and the waves at the gauges, the resistance along the pile and the load test"),
        (optimise, "the evaluations"),
        (bearing, "the blow count and stresses"),
        (drive, "the blow count and stresses by depth"),
    ):
        study.add_argument("--output", metavar="OUT.json", help="write the whole answer here")
        study.add_argument("--plot", metavar="PLOT.png", help=f"draw {plotted} here (.png or .svg)")
        _here_or_on_service(
            study, "run it as a job on this service instead, its runs spread over the service's workers"
        )
        study.add_argument(
            "--progress", action="store_true", help="show the progress bar on stderr even when it is not a terminal"
        )
    fit.set_defaults(handler=_calibrate)
    match.set_defaults(handler=_match)
    optimise.set_defaults(handler=_optimize)
    bearing.set_defaults(handler=_bearing_graph)
    drive.set_defaults(handler=_drivability)
    plot = commands.add_parser("plot", help="draw the plots of a result file (PNG, SVG)")
    plot.add_argument("result", help="an HDF5 result of percussim run --output or the service")
    plot.add_argument("--out", metavar="DIR", help="folder for the plots (default: RESULT-plots next to the file)")
    plot.add_argument("--format", nargs="+", default=["png", "svg"], metavar="FORMAT", help="png, svg or both")
    plot.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help="these plots only: force, displacements, probes, stress_along, spacetime, energy, "
        "force_penetration, blows",
    )
    plot.add_argument(
        "--times",
        type=_times,
        metavar="T1,T2,...",
        help="times (s) of the stress_along curves (default: over the first contact)",
    )
    plot.set_defaults(handler=_plots)
    warm = commands.add_parser(
        "warmup",
        help="compile the kernel into Numba's cache (done at install); remove other versions' long unused",
    )
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
    started.add_argument(
        "--workers",
        type=_count,
        metavar="N",
        help="queue workers to start (default: 1 embedded, 0 with PERCUSSIM_BROKER_URL)",
    )
    started.add_argument("--no-worker", action="store_true", help="run the API alone")
    serve.set_defaults(handler=_serve)
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        return args.handler(args)
    except ValueError as error:
        from percussim.common.settings import SettingsError

        if not isinstance(error, SettingsError):
            raise
        for line in str(error).splitlines():
            print(f"percussim: {line}", file=sys.stderr)
        return EXIT_INVALID
    except ModuleNotFoundError as error:
        extra = EXTRA_OF.get((error.name or "").partition(".")[0])
        if extra is None:
            raise
        print(
            f"percussim: {args.command} needs the {extra!r} extra, which is not installed "
            f"({error.name} is missing): pip install 'percussim[{extra}]'",
            file=sys.stderr,
        )
        return EXIT_FAILED
    except BrokenPipeError:
        # stdout closed early (`| head`): the files asked for are written; end quietly, as a
        # process stopped by SIGPIPE, instead of with a traceback when Python flushes stdout.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE


if __name__ == "__main__":
    sys.exit(main())
