"""A Python client for the percussim HTTP API.

    from percussim import Client

    with Client("http://127.0.0.1:8000") as api:
        summary = api.run("examples/fig9.json", progress=lambda fraction, record: print(fraction))
        print(summary["co_impact_time"], summary["peak_contact_force"]["value"])
        rows = api.run_sweep("examples/fig5.json", {"striker.velocity": [3, 5, 7]})
        fit = api.calibrate({"case": "examples/fig5.json", "record": "record.csv",
                             "parameters": {"contact.stiffness": [1e10, 1e13]}})
        graph = api.run_bearing_graph({"case": "pile.json", "capacity": [1e6, 2e6, 3e6]})

It needs only httpx: the solver (and so NumPy, h5py and Numba) is imported by `result` alone,
which reads the HDF5 result into the same `Result` a local run gives, and by a calibration
given its record as a CSV file, which is read and checked here.

Every error the service answers is raised as a `ServiceError` that says what went wrong:
`Refused` (422, 413) lists each offending field, `JobFailed` carries the failed or cancelled
job's record, `Unauthorized` (401), `NotFound` (404) and `Unavailable` (503, after retrying as
the service's `Retry-After` asks, `retries` times) name the problem.
"""

from __future__ import annotations

import json
import os
import secrets
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO, NamedTuple
from urllib.parse import quote

import httpx

if TYPE_CHECKING:
    from percussim.solver.case import Case
    from percussim.solver.result import Result

FINISHED = ("succeeded", "failed", "cancelled")

Progress = Callable[[float, dict], None]  # (fraction done 0..1, the job's or the sweep's record)


class FieldError(NamedTuple):
    """One reason the service refused a request: the field's dotted path and why."""

    field: str
    message: str


class ServiceError(Exception):
    """The service answered with an error or could not be reached; `status` is the HTTP status
    (None when there was no answer)."""

    def __init__(self, message: str, status: int | None = None):
        super().__init__(message)
        self.status = status


class Refused(ServiceError):
    """The service refused the request (422, or 413 for a body over its size limit); `errors`
    names each offending field."""

    def __init__(self, errors: list[FieldError], status: int):
        super().__init__(
            "the service refused the request:\n" + "\n".join(f"  {e.field}: {e.message}" for e in errors), status
        )
        self.errors = errors


class Unauthorized(ServiceError):
    """401: the service needs an API key, or does not know the one given."""


class NotFound(ServiceError):
    """404: no such job or preset (or the job belongs to another API key)."""


class Unavailable(ServiceError):
    """503: the service's job queue stayed unavailable through every retry."""


class JobFailed(ServiceError):
    """The job failed or was cancelled; `record` is its job record (`status`, `error`)."""

    def __init__(self, record: dict):
        reason = f"failed: {record.get('error')}" if record["status"] == "failed" else "was cancelled"
        super().__init__(f"job {record['id']} {reason}")
        self.record = record


def _error(response: httpx.Response) -> ServiceError:
    """The exception for an error answer, with the service's own words."""
    try:
        detail = response.json()["detail"]
    except (ValueError, KeyError, TypeError):
        detail = response.text or response.reason_phrase
    if isinstance(detail, list) and all(isinstance(d, dict) for d in detail):
        return Refused(
            [FieldError(d.get("field", "?"), d.get("message", str(d))) for d in detail], response.status_code
        )
    kind = {401: Unauthorized, 404: NotFound, 503: Unavailable}.get(response.status_code, ServiceError)
    return kind(f"{detail} (HTTP {response.status_code} from {response.request.url})", response.status_code)


def _case_json(case: dict | str | os.PathLike | Case) -> dict:
    """Case JSON from a dict, the path of a case JSON file or a `percussim.Case`."""
    if isinstance(case, (str, os.PathLike)):
        return json.loads(Path(case).read_bytes())
    return case if isinstance(case, dict) else case.model_dump(mode="json", exclude_none=True)


def _retry_after(response: httpx.Response) -> float:
    """Seconds to wait before asking again: the service's `Retry-After`, else 1 s."""
    value = response.headers.get("Retry-After", "")
    return float(value) if value.isdigit() else 1.0


class Client:
    """A percussim service at `url` (e.g. "http://127.0.0.1:8000"), used as a context manager
    or closed with `close()`.

    `api_key` is sent as `X-API-Key` (needed when the service sets `PERCUSSIM_API_KEYS`);
    `timeout` bounds each HTTP call, in seconds; a 503 is retried `retries` times, each after
    the `Retry-After` the service asks for. `transport` is passed to httpx (for tests, proxies).
    """

    def __init__(
        self,
        url: str,
        api_key: str | None = None,
        timeout: float = 30.0,
        retries: int = 3,
        transport: httpx.BaseTransport | None = None,
    ):
        headers = {"X-API-Key": api_key} if api_key else {}
        self.url = url
        self.retries = retries
        self._http = httpx.Client(base_url=url, headers=headers, timeout=timeout, transport=transport)

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        self._http.close()

    # -- presets

    def presets(self) -> list[dict]:
        """The presets, each `{"name", "description"}`."""
        return self._json("GET", "/v1/presets")

    def preset(self, name: str) -> dict:
        """Preset `name` as case JSON (a dict), ready for `submit`."""
        return self._json("GET", f"/v1/presets/{quote(name, safe='')}")

    # -- jobs

    def submit(self, case: dict | str | os.PathLike | Case) -> dict:
        """Queue `case`: a dict of case JSON, the path of a case JSON file, or a `percussim.Case`.
        Returns the new job's record (`id`, `status` "queued", ...); raises `Refused` naming
        every offending field of an invalid case."""
        if isinstance(case, dict):
            return self._json("POST", "/v1/jobs", json=case)
        # A file is sent as read: the service validates it and names what is wrong, even bad JSON.
        text = (
            Path(case).read_bytes() if isinstance(case, (str, os.PathLike)) else case.model_dump_json(exclude_none=True)
        )
        return self._json("POST", "/v1/jobs", content=text, headers={"content-type": "application/json"})

    def job(self, job_id: str) -> dict:
        """The job's record: `status` (queued, running, succeeded, failed, cancelled),
        `progress` 0..1, `created`, `started`, `finished`, `error`."""
        return self._json("GET", self._job_path(job_id))

    def jobs(
        self,
        offset: int = 0,
        limit: int = 50,
        status: str | None = None,
        name: str | None = None,
        sweep: str | None = None,
    ) -> list[dict]:
        """Records of recent jobs, newest first, from `offset`, at most `limit` (≤ 500); only those
        of `status`, of cases named `name`, or the variants of `sweep`, when given."""
        query = {"offset": offset, "limit": limit, "status": status, "name": name, "sweep": sweep}
        return self._json("GET", "/v1/jobs", params={k: v for k, v in query.items() if v is not None})["jobs"]

    def wait(
        self, job_id: str, progress: Progress | None = None, poll: float = 0.2, timeout: float | None = None
    ) -> dict:
        """Wait for the job to finish, asking every `poll` seconds, and return its record once it
        has succeeded. `progress(fraction, record)` is called with each record polled. Raises
        `JobFailed` if the job failed or was cancelled, `TimeoutError` after `timeout` seconds."""
        record = self._poll(
            lambda: self.job(job_id),
            lambda r: r["status"] in FINISHED,
            progress,
            poll,
            timeout,
            lambda r: f"job {job_id} is still {r['status']}",
        )
        if record["status"] != "succeeded":
            raise JobFailed(record)
        return record

    def summary(self, job_id: str) -> dict:
        """The pulse summary of a succeeded job (a dict, as `percussim run` prints it)."""
        return self._json("GET", f"{self._job_path(job_id)}/summary")

    def result(self, job_id: str) -> Result:
        """The succeeded job's HDF5 result, read into memory as a `percussim.Result`, the
        same object a local `simulate` returns: `history` maps dataset paths ("contact/force",
        "time", "energy/to_medium", ...) to NumPy arrays, with `probe_x`, `probe_stress`,
        `fields` (None unless asked), `summary`, `case` and `numerics`; `arrays()` gives every
        array under its HDF5 path. The file is streamed to a temporary file first, so that only
        the arrays are held; use `download` for a file too large for even those."""
        from percussim.solver.io import read_result

        with tempfile.TemporaryFile() as f:
            self._stream_to(job_id, f)
            f.seek(0)
            return read_result(f)

    def download(self, job_id: str, path: str | os.PathLike) -> Path:
        """Write the succeeded job's HDF5 result to `path`, streamed, under a temporary name
        renamed when complete (a reader never sees half a file). Returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        # Not mkstemp: its file is owner-only, and a downloaded result should get the umask's permissions.
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(8)}.part")
        try:
            with open(tmp, "xb") as f:
                self._stream_to(job_id, f)
            os.replace(tmp, path)
        finally:
            Path(tmp).unlink(missing_ok=True)
        return path

    def _stream_to(self, job_id: str, f: BinaryIO) -> None:
        """Write the succeeded job's HDF5 result to the open binary file `f`, chunk by chunk."""
        answer = self._send("GET", self._result_path(job_id), stream=True)
        try:
            for chunk in answer.iter_bytes():
                f.write(chunk)
        finally:
            answer.close()

    def cancel(self, job_id: str) -> dict:
        """Cancel an unfinished job (or study): a queued one at once, a running one between two
        chunks of its run (`wait` then raises `JobFailed`). Returns its record; a finished job is
        left as it is and raises a 409 `ServiceError`."""
        return self._json("POST", f"{self._job_path(job_id)}/cancel")

    def delete(self, job_id: str) -> None:
        """Remove a finished job (or study) and its files. An unfinished one raises a 409
        `ServiceError` (cancel it first), and so does a sweep's variant (`delete_sweep`)."""
        if self.job(job_id)["status"] not in FINISHED:
            raise ServiceError(f"job {job_id} has not finished: cancel it first", status=409)
        self._send("DELETE", self._job_path(job_id))

    def run(
        self, case: dict | str | os.PathLike | Case, progress: Progress | None = None, timeout: float | None = None
    ) -> dict:
        """Submit `case`, wait for it (see `wait`) and return its pulse summary."""
        job_id = self.submit(case)["id"]
        self.wait(job_id, progress=progress, timeout=timeout)
        return self.summary(job_id)

    # -- sweeps

    def submit_sweep(self, case: dict | str | os.PathLike | Case, parameters: dict[str, list]) -> dict:
        """Queue every combination of `parameters` (dotted field path → its values, e.g.
        `{"striker.velocity": [3, 5, 7], "contact.stiffness": [4e11, 8e11]}`) over `case` (as for
        `submit`), each a job of its own over all the workers. Returns the sweep (`id`, `total`,
        `rows`, ...); raises `Refused` naming the parameter value each bad variant came from."""
        return self._json("POST", "/v1/sweeps", json={"case": _case_json(case), "parameters": parameters})

    def sweep(self, sweep_id: str) -> dict:
        """The sweep: `progress` 0..1, `counts` by status, `finished`, `columns`, and a row per
        variant (`values`, `status`, `job`, and the summary's columns once it succeeded, or
        `error` once it failed)."""
        return self._json("GET", self._sweep_path(sweep_id))

    def wait_sweep(
        self, sweep_id: str, progress: Progress | None = None, poll: float = 0.5, timeout: float | None = None
    ) -> dict:
        """Wait until every variant has finished, asking every `poll` seconds, and return the
        sweep. A variant that failed is a row with its `error`: the others go on.
        `progress(fraction, sweep)` is called with each sweep polled; `TimeoutError` after
        `timeout` seconds."""
        return self._poll(
            lambda: self.sweep(sweep_id),
            lambda s: s["finished"],
            progress,
            poll,
            timeout,
            lambda s: f"sweep {sweep_id} is still at {s['counts']}",
        )

    def cancel_sweep(self, sweep_id: str) -> dict:
        """Cancel every variant of the sweep that has not finished; returns the sweep."""
        return self._json("DELETE", self._sweep_path(sweep_id))

    def delete_sweep(self, sweep_id: str) -> None:
        """Remove a finished sweep with its jobs and files (409 while a variant has not finished)."""
        self._send("DELETE", self._sweep_path(sweep_id), params={"purge": "true"})

    def run_sweep(
        self,
        case: dict | str | os.PathLike | Case,
        parameters: dict[str, list],
        progress: Progress | None = None,
        timeout: float | None = None,
    ) -> list[dict]:
        """Submit a sweep (see `submit_sweep`), wait for it (see `wait_sweep`) and return its
        table, a row per variant in the order of the parameters' combinations."""
        sweep_id = self.submit_sweep(case, parameters)["id"]
        return self.wait_sweep(sweep_id, progress=progress, timeout=timeout)["rows"]

    # -- calibrations and optimisations: each a job, so `wait`, `job` and `cancel` take its id too

    def submit_calibration(self, request: dict) -> dict:
        """Queue a fit of a case's parameters to a measured record, on the workers. `request` is
        that of a local `percussim.calibrate`: `{"case", "record", "parameters": {PATH: [low,
        high]}}`, with the case as for `submit` and the record a `Record`, its JSON
        (`{"quantity", "x", "time", "values"}`, or `time_start` and `sample_rate` instead of
        `time`, and a `time_offset`) or the path of a CSV record (read here: one that
        is not a record raises `percussim.CaseError` naming its line before anything is sent).
        Returns the study's record (`id`, `status` "queued", ...); raises `Refused` naming each
        offending field."""
        record = request["record"]
        if isinstance(record, (str, os.PathLike)):
            from percussim.solver.record import read_record

            record = read_record(record)
        if not isinstance(record, dict):
            record = record.model_dump(mode="json", exclude_none=True)
        return self._json(
            "POST", "/v1/calibrations", json=request | {"case": _case_json(request["case"]), "record": record}
        )

    def calibration(self, study_id: str) -> dict:
        """The calibration's record, with its `fit` once it has succeeded (None before)."""
        return self._json("GET", f"/v1/calibrations/{quote(study_id, safe='')}")

    def calibrate(self, request: dict, progress: Progress | None = None, timeout: float | None = None) -> dict:
        """Submit a calibration (see `submit_calibration`), wait for it (see `wait`) and return
        its fit, as a local `percussim.calibrate` returns it."""
        study_id = self.submit_calibration(request)["id"]
        return self._answer(study_id, self.calibration, "fit", progress, timeout)

    def submit_signal_match(self, request: dict) -> dict:
        """Queue a signal match on the workers. `request` is that of a local
        `percussim.signal_match`: `{"case": the pile (case JSON or the path of its file), "record":
        {"x", "time", "force", "velocity"} or the path of a CSV record (read here), "parameters":
        {PATH: [low, high]} or none for the default}`. Returns the study's record; raises `Refused`
        naming each offending field."""
        record = request["record"]
        if isinstance(record, (str, os.PathLike)):
            from percussim.solver.signal_match import read_pile_record

            record = read_pile_record(Path(record).read_text()).model_dump(mode="json")
        return self._json(
            "POST", "/v1/signal-matches", json=request | {"case": _case_json(request["case"]), "record": record}
        )

    def signal_match(self, study_id: str) -> dict:
        """The signal match's record, with its `match` once it has succeeded (None before)."""
        return self._json("GET", f"/v1/signal-matches/{quote(study_id, safe='')}")

    def match(self, request: dict, progress: Progress | None = None, timeout: float | None = None) -> dict:
        """Submit a signal match (see `submit_signal_match`), wait for it (see `wait`) and return
        the match, as a local `percussim.signal_match` returns it."""
        study_id = self.submit_signal_match(request)["id"]
        return self._answer(study_id, self.signal_match, "match", progress, timeout)

    def submit_optimization(self, request: dict) -> dict:
        """Queue an optimisation on the workers. `request` is that of a local `percussim.optimize`:
        `{"case", "variables": {PATH: [low, high]}, "objective": {"maximize" or "minimize":
        QUANTITY}, "limits": {QUANTITY: {"max": v} or {"min": v}}, "max_evaluations": N}`, with
        the case as for `submit`. Returns the study's record; raises `Refused` naming each
        offending field."""
        return self._json("POST", "/v1/optimizations", json=request | {"case": _case_json(request["case"])})

    def optimization(self, study_id: str) -> dict:
        """The optimisation's record, with its `optimum` once it has succeeded (None before)."""
        return self._json("GET", f"/v1/optimizations/{quote(study_id, safe='')}")

    def optimize(self, request: dict, progress: Progress | None = None, timeout: float | None = None) -> dict:
        """Submit an optimisation (see `submit_optimization`), wait for it (see `wait`) and return
        its optimum, as a local `percussim.optimize` returns it."""
        study_id = self.submit_optimization(request)["id"]
        return self._answer(study_id, self.optimization, "optimum", progress, timeout)

    # -- the pile studies: each a job, its rows beside its record once it has succeeded

    def submit_bearing_graph(self, request: dict) -> dict:
        """Queue a bearing graph or an inspector's chart on the workers. `request` is that of a local
        `percussim.bearing_graph`: `{"case", "capacity": [N, ...]}` (or `"stroke": [m, ...]`, the case
        giving striker.stroke), with `"toe_share"` if not the case's own and the case as for
        `submit`. Returns the study's record; raises `Refused` naming each offending field."""
        return self._json("POST", "/v1/bearing-graphs", json=request | {"case": _case_json(request["case"])})

    def bearing_graph(self, study_id: str) -> dict:
        """The bearing graph's record, with its `rows` (and the rest of its answer) once it has
        succeeded."""
        return self._json("GET", f"/v1/bearing-graphs/{quote(study_id, safe='')}")

    def run_bearing_graph(self, request: dict, progress: Progress | None = None, timeout: float | None = None) -> dict:
        """Submit a bearing graph (see `submit_bearing_graph`), wait for it (see `wait`) and return
        it: its record with a row per capacity or stroke, as a local `percussim.bearing_graph`
        returns them."""
        return self._answer(self.submit_bearing_graph(request)["id"], self.bearing_graph, None, progress, timeout)

    def submit_drivability(self, request: dict) -> dict:
        """Queue a drivability on the workers. `request` is that of a local `percussim.drivability`:
        `{"case", "soil"}`, the case as for `submit` and the soil its JSON or the path of a soil
        JSON file (docs/piling.md). Returns the study's record; raises `Refused` naming each
        offending field."""
        soil = request["soil"]
        if isinstance(soil, (str, os.PathLike)):
            soil = json.loads(Path(soil).read_bytes())
        return self._json("POST", "/v1/drivability", json={"case": _case_json(request["case"]), "soil": soil})

    def drivability(self, study_id: str) -> dict:
        """The drivability's record, with its `rows`, `total_blows`, `driving_time` and
        `refusal_depth` once it has succeeded."""
        return self._json("GET", f"/v1/drivability/{quote(study_id, safe='')}")

    def run_drivability(self, request: dict, progress: Progress | None = None, timeout: float | None = None) -> dict:
        """Submit a drivability (see `submit_drivability`), wait for it (see `wait`) and return it:
        its record with its rows and totals, as a local `percussim.drivability` returns them."""
        return self._answer(self.submit_drivability(request)["id"], self.drivability, None, progress, timeout)

    def _answer(
        self,
        study_id: str,
        view: Callable[[str], dict],
        name: str | None,
        progress: Progress | None,
        timeout: float | None,
    ) -> dict:
        """The study's answer `name` from its `view` (the view itself for None), once `wait` has
        seen it succeed."""
        self.wait(study_id, progress=progress, timeout=timeout)
        found = view(study_id)
        return found if name is None else found[name]

    @staticmethod
    def _poll(
        fetch: Callable[[], dict],
        finished: Callable[[dict], bool],
        progress: Progress | None,
        poll: float,
        timeout: float | None,
        still: Callable[[dict], str],
    ) -> dict:
        """`fetch()` every `poll` seconds until what it returns is `finished`, which is returned;
        `progress(fraction, record)` with each; `TimeoutError` (`still(record)` says how far) after
        `timeout` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            record = fetch()
            if progress is not None:
                progress(record["progress"], record)
            if finished(record):
                return record
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError(f"{still(record)} after {timeout} s")
            time.sleep(poll)

    # -- HTTP

    @staticmethod
    def _job_path(job_id: str) -> str:
        return f"/v1/jobs/{quote(job_id, safe='')}"

    @staticmethod
    def _sweep_path(sweep_id: str) -> str:
        return f"/v1/sweeps/{quote(sweep_id, safe='')}"

    def _result_path(self, job_id: str) -> str:
        return f"{self._job_path(job_id)}/result.h5"

    def _json(self, method: str, path: str, **kwargs) -> Any:
        return self._send(method, path, **kwargs).json()

    def _send(self, method: str, path: str, stream: bool = False, **kwargs) -> httpx.Response:
        """The answer to a call, once it is not a 503 or has been retried `retries` times;
        an error answer raised as its `ServiceError`. A streamed answer is the caller's to close."""
        request = self._http.build_request(method, path, **kwargs)
        retried = 0
        while True:
            try:
                answer = self._http.send(request, stream=stream)
            except httpx.TransportError as error:
                raise ServiceError(f"cannot reach the percussim service at {self.url}: {error}") from None
            # A 503 from POST /v1/jobs is safe to repeat: the service queued nothing.
            if answer.status_code == 503 and retried < self.retries:
                answer.close()
                time.sleep(_retry_after(answer))
                retried += 1
                continue
            if answer.is_error:
                answer.read()
                answer.close()
                raise _error(answer)
            return answer
