"""Diagnoses of hybrid models as background jobs, when the request asks for it.

``POST /v1/models/{id}/diagnose`` answers a hybrid model's diagnosis on the request (about a
second); with ``Prefer: respond-async`` (or ``Prefer: wait=N``, RFC 7240) it is queued as a
job (spec ``kind`` ``diagnosis``) on the app's job runner — recovered after a crash,
cancellable, time-limited and counted in the key's quota like every job — and answered like a
physics diagnosis (``physics_jobs.answer``): 200 with the diagnosis when it ends within the
wait, else 202 with the job, whose ``result`` (``GET /v1/jobs/{id}``) is the diagnosis.
"""

from __future__ import annotations

import logging
from typing import Any

from sqlalchemy.orm import Session

from wearcast.service import job_store
from wearcast.service.db import SessionFactory

log = logging.getLogger(__name__)
#: ``spec["kind"]`` of a hybrid diagnosis job.
KIND = "diagnosis"


def wants_job(prefer_header: str) -> bool:
    """Whether the request's ``Prefer`` header asks for asynchronous handling or a wait."""
    prefer = prefer_header.lower()
    return "respond-async" in prefer or "wait" in prefer


def submit(session: Session, runner: Any, model_id: int, body: Any) -> int:
    """Queue the diagnosis of a stored hybrid model (404 naming ``model_id`` when there is
    none; 429 at the key's job quota); the job id."""
    from wearcast.service import model_loading

    model_loading.get_model_row(session, model_id)
    runner.check_quota(session)
    row = job_store.queue_job(session, f"diagnosis of model {model_id}",
                              {"kind": KIND, "model_id": model_id,
                               "request": body.model_dump(mode="json")},
                              timeout_s=job_store.default_timeout())
    runner.submit(row.id)
    return int(row.id)


def run_diagnosis_job(factory: SessionFactory, job_id: int, spec: dict[str, Any],
                      on_progress: Any = None, control: Any = None) -> None:
    """Diagnose the model of a claimed job (and store the extension when asked)."""
    from wearcast.service import diagnosis_store
    from wearcast.service.diagnosis_schemas import DiagnoseIn

    control = control or job_store.JobControl(factory, job_id, None)
    job_store.set_job(factory, job_id, progress=0.0, message="diagnosing")

    def compute() -> dict[str, Any]:
        body = DiagnoseIn.model_validate(spec["request"])
        with factory() as session:
            out = diagnosis_store.diagnose(session, int(spec["model_id"]), body)
            return out.model_dump(mode="json")

    job_store.complete_job(factory, job_id, control, compute, kind="diagnosis", logger=log)
