"""``/v1/jobs``: every background job (simulations, coefficient fits, table builds, physics
models and their diagnoses) in one list, one job's status and progress (with the small
result of a table build or a physics job), and cancelling a job (its owner's key or an admin
key)."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Path, Query, Request, Response
from pydantic import Field
from sqlalchemy import select

from wearcast.service import job_store
from wearcast.service import models_db as db
from wearcast.service.deps import SessionDep
from wearcast.service.errors import ApiError, NotFound
from wearcast.service.job_schemas import JobStatusOut
from wearcast.service.json_response import json_response

router = APIRouter(tags=["jobs"])
JobId = Annotated[int, Path(ge=1, le=2**63 - 1)]


JobKind = Literal["simulation", "coefficient_fit", "wear_table", "diagnosis",
                  "physics_model", "physics_diagnosis"]
#: Kinds whose (small) result ``GET /v1/jobs/{id}`` carries: the table built
#: (``wear_table_id``, ``n_rows``), a hybrid diagnosis, the physics model built (``model_id``,
#: ``model``) or its diagnosis (the ``DiagnosisOut`` of the model's diagnose).
RESULT_KINDS = ("wear_table", "diagnosis", "physics_model", "physics_diagnosis")


class JobOut(JobStatusOut):
    kind: JobKind
    owner_key_id: int | None = None
    attempts: int = 0
    cancel_requested: bool = False
    timeout_s: float | None = None
    created_at: dt.datetime | None = None
    started_at: dt.datetime | None = None
    finished_at: dt.datetime | None = None
    heartbeat_at: dt.datetime | None = None
    result: dict[str, Any] | None = Field(default=None, description=(
        "wear_table, physics_model and physics_diagnosis jobs once done: {wear_table_id, "
        "n_rows}, {model_id, model} or the diagnosis (simulations and fits: "
        "GET /v1/simulations/{id}, /v1/coefficient-fits/{id})"))


def job_out(row: Any, with_result: bool = False) -> JobOut:
    """The job's status as answered by ``/v1/jobs`` (its result only with ``with_result``)."""
    kind: JobKind = (row.spec or {}).get("kind") or "simulation"
    result = row.result if with_result and kind in RESULT_KINDS and row.status == "done" \
        else None
    return JobOut(id=row.id, kind=kind, name=row.name, status=row.status, result=result,
                  progress=float(row.progress), message=row.message, error=row.error,
                  owner_key_id=row.owner_key_id, attempts=row.attempts or 0,
                  cancel_requested=bool(row.cancel_requested), timeout_s=row.timeout_s,
                  created_at=row.created_at, started_at=row.started_at,
                  finished_at=row.finished_at, heartbeat_at=row.heartbeat_at)


@router.get("/jobs", response_model=list[JobOut])
def list_jobs(session: SessionDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100,
              status: Literal["queued", "running", "done", "failed", "cancelled"] | None
              = None) -> Response:
    """The newest jobs first, without their results."""
    query = select(db.Simulation).order_by(db.Simulation.id.desc()).limit(limit)
    if status is not None:
        query = query.where(db.Simulation.status == status)
    return json_response([job_out(r) for r in session.scalars(query)])


@router.get("/jobs/{job_id}", response_model=JobOut)
def get_job(job_id: JobId, session: SessionDep) -> Response:
    row = session.get(db.Simulation, job_id)
    if row is None:
        raise NotFound("job_id", f"no job with id {job_id}")
    return json_response(job_out(row, with_result=True))


@router.post("/jobs/{job_id}/cancel", response_model=JobOut)
def cancel_job(job_id: JobId, session: SessionDep, request: Request) -> JobOut:
    """Cancel a queued job at once, a running one at its next step (``cancel_requested``
    until then); a job that has ended is answered as it is (409)."""
    row = session.get(db.Simulation, job_id)
    if row is None:
        raise NotFound("job_id", f"no job with id {job_id}")
    principal = request.state.principal
    if row.owner_key_id not in (None, principal.key_id) and "admin" not in principal.scopes:
        raise ApiError(403, "job_id", "only the key that submitted the job, or an admin key, "
                       "may cancel it")
    if row.status not in job_store.ACTIVE:
        raise ApiError(409, "job_id", f"the job has already ended ({row.status})")
    row = job_store.cancel(session, job_id)
    return job_out(row)
