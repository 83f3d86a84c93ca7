"""Curve-radius table builds as background jobs (``POST /v1/wear-tables/jobs``).

The request is the one of ``POST /v1/wear-tables/compute``; what can be checked without the
physics (the vehicle preset, the route, a measured wheel or rail) is checked at once (4xx
naming the field), the build runs on the app's job runner (recovered after a crash, cancelled
or timed out like every job) and its result names the stored table:
``{"wear_table_id": ..., "n_rows": ...}`` (``GET /v1/jobs/{id}``).
"""

from __future__ import annotations

import logging
from typing import Any

from sqlalchemy.orm import Session

from wearcast.service import job_store, wear_table_store
from wearcast.service.db import SessionFactory
from wearcast.service.wear_table_schemas import WearTableComputeIn

log = logging.getLogger(__name__)
#: ``spec["kind"]`` of a table-build job.
KIND = "wear_table"


def submit(session: Session, runner: Any, body: WearTableComputeIn) -> Any:
    """Check the request, store it as a queued job and hand it to the runner (429 naming
    ``job_quota_per_key`` when the key holds its quota). Returns the job row."""
    runner.check_quota(session)
    wear_table_store.check_compute_request(session, body)
    row = job_store.queue_job(session, body.name,
                              {"kind": KIND, "request": body.model_dump(mode="json")},
                              timeout_s=job_store.default_timeout())
    runner.submit(row.id)
    return row


def run_wear_table_job(factory: SessionFactory, job_id: int, spec: dict[str, Any],
                       on_progress: Any = None, control: Any = None) -> None:
    """Build and store the table of a claimed job; its result names the table."""
    control = control or job_store.JobControl(factory, job_id, None)
    job_store.set_job(factory, job_id, progress=0.0, message="solving the curving")

    def compute() -> dict[str, Any]:
        body = WearTableComputeIn.model_validate(spec["request"])
        with factory() as session:
            row = wear_table_store.compute_wear_table(session, body)
            return {"wear_table_id": int(row.id), "n_rows": int(row.n_rows)}

    job_store.complete_job(factory, job_id, control, compute, kind="wear-table build",
                           logger=log)
