"""The jobs of physics models (build, diagnosis): run one, and answer a request when it ends.

Both are rows of the ``simulations`` table (spec ``kind`` ``physics_model`` or
``physics_diagnosis``), run by the app's job runner like simulations and coefficient fits
(claim, heartbeat, cancel, time limit, recovery: :mod:`wearcast.service.job_store`). Their
result is small and is read by ``GET /v1/jobs/{id}``.

A request that queued one waits for it (:func:`answer`) up to ``job_wait_s`` (setting,
default 300 s) or what its ``Prefer`` header asks (RFC 7240: ``respond-async`` = do not wait,
``wait=N`` seconds): the finished job's answer (201 model / 200 diagnosis), a failed job's
error as a problem (422 when it names a field the client set), or 202 with the job. The
waiting request sleeps in the threadpool; the work runs on the job runner's workers.
"""

from __future__ import annotations

import logging
import re
import time
from typing import Any

from fastapi import Request
from fastapi.responses import JSONResponse
from sqlalchemy import select

from wearcast.service import models_db as db
from wearcast.service.db import SessionFactory
from wearcast.service.errors import ApiError
from wearcast.service.job_store import ACTIVE, JobControl, complete_job
from wearcast.service.physics_schemas import JobAccepted

log = logging.getLogger(__name__)
#: Longest wait a Prefer header may ask for [s].
MAX_WAIT_S = 3600.0
POLL_S = 0.1


def run_physics_job(factory: SessionFactory, job_id: int, spec: dict[str, Any],
                    control: JobControl) -> None:
    """Run a claimed physics job to its end; never raises for a failing job
    (``job_store.complete_job``)."""
    def compute() -> Any:
        if spec["kind"] == "physics_model":
            from wearcast.service.physics_model_store import run_build

            return run_build(factory, job_id, spec, control)
        from wearcast.service.physics_diagnosis_store import run_diagnosis_job

        return run_diagnosis_job(factory, job_id, spec, control)

    complete_job(factory, job_id, control, compute, kind=f"{spec.get('kind')} job",
                 logger=log)


def wait_seconds(request: Request) -> float:
    """How long to wait for a job: the ``Prefer`` header's ``respond-async`` (0) or
    ``wait=N``, else the ``job_wait_s`` setting."""
    prefer = request.headers.get("prefer", "").lower()
    if "respond-async" in prefer:
        return 0.0
    found = re.search(r"wait\s*=\s*(\d+(?:\.\d+)?)", prefer)
    if found:
        return min(float(found.group(1)), MAX_WAIT_S)
    return float(request.app.state.settings.job_wait_s)


def _accepted(row: Any) -> JSONResponse:
    body = JobAccepted(id=row.id, kind=row.spec.get("kind"), name=row.name, status=row.status,
                       progress=float(row.progress), message=row.message, error=row.error,
                       created_at=row.created_at)
    return JSONResponse(status_code=202, content=body.model_dump(mode="json"),
                        headers={"Location": f"/v1/jobs/{row.id}"})


def _failure(job_id: int, error: str) -> ApiError:
    """A failed job as a problem: 422 naming a field when its error names one."""
    text = error.partition(": ")[2] or error
    field, sep, reason = text.partition(": ")
    known = ("simulation", "route_id", "law", "vehicle", "calibration", "filter", "causes")
    if sep and field.split(".")[0] in known and " " not in field:
        return ApiError(422, field, f"{reason} (job {job_id})", job_id=job_id)
    return ApiError(422, "simulation", f"the job failed: {error} (job {job_id}); change "
                    "the simulation options or the measurements", job_id=job_id)


def answer(factory: SessionFactory, job_id: int, wait_s: float, status: int) -> Any:
    """The job's result as a (status) answer once it is done within ``wait_s``; the job
    (202) while it runs; a failed job's error (422)."""
    deadline = time.monotonic() + wait_s
    while True:
        with factory() as session:
            row = session.get(db.Simulation, job_id)
            assert row is not None
            if row.status == "done":
                result = session.scalar(select(db.Simulation.result)
                                        .where(db.Simulation.id == job_id))
                return JSONResponse(status_code=status, content=_final(result, job_id),
                                    headers={"X-Job-ID": str(job_id)})
            if row.status in ("failed", "cancelled"):
                raise _failure(job_id, row.error or row.status)
            if row.status in ACTIVE and time.monotonic() >= deadline:
                return _accepted(row)
        time.sleep(POLL_S)


def _final(result: dict[str, Any] | None, job_id: int) -> dict[str, Any]:
    """What the request answers when the job is done: the model (a build) or the
    diagnosis, with the job's id."""
    result = result or {}
    if "model" in result and "verdict" not in result:
        return {**result["model"], "job_id": job_id}
    return {**result, "job_id": job_id}
