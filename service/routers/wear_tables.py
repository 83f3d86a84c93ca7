"""``/v1/wear-tables``: curve-radius tables of wear measures (CSV upload or computed).

Computing a table runs the quasi-static curving of the physics core (about a second): the
endpoint is a plain ``def``, so FastAPI runs it in its threadpool, off the event loop.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Form, Request, UploadFile

from wearcast.service import wear_table_jobs, wear_table_store
from wearcast.service.deps import SessionDep
from wearcast.service.errors import Unprocessable
from wearcast.service.routers.jobs import JobOut, job_out
from wearcast.service.wear_table_schemas import (
    WearTableComputeIn,
    WearTableContactsOut,
    WearTableOut,
)

router = APIRouter(tags=["wear tables"])


@router.post("/wear-tables", response_model=WearTableOut, status_code=201)
def upload_wear_table(session: SessionDep, file: Annotated[UploadFile, File()],
                      name: Annotated[str | None, Form()] = None) -> WearTableOut:
    data = file.file.read(wear_table_store.MAX_TABLE_BYTES + 1)
    if len(data) > wear_table_store.MAX_TABLE_BYTES:
        raise Unprocessable("file", "the table is larger than 20 MB")
    row = wear_table_store.upload_wear_table(session, data, file.filename or "table.csv", name)
    return wear_table_store.wear_table_out(session, row)


@router.post("/wear-tables/compute", response_model=WearTableOut, status_code=201)
def compute_wear_table(body: WearTableComputeIn, session: SessionDep) -> WearTableOut:
    """Build a table with the physics core for a vehicle preset and a route (or radii)."""
    row = wear_table_store.compute_wear_table(session, body)
    return wear_table_store.wear_table_out(session, row)


@router.post("/wear-tables/jobs", response_model=JobOut, status_code=202)
def compute_wear_table_job(body: WearTableComputeIn, session: SessionDep,
                           request: Request) -> JobOut:
    """Build a table as a background job (the body of ``/wear-tables/compute``); poll
    ``GET /v1/jobs/{id}``: once ``done`` its ``result`` names the stored table."""
    row = wear_table_jobs.submit(session, request.app.state.simulations, body)
    return job_out(row)


@router.get("/wear-tables/{table_id}", response_model=WearTableOut)
def get_wear_table(table_id: int, session: SessionDep) -> WearTableOut:
    row = wear_table_store.get_wear_table(session, table_id, "table_id")
    return wear_table_store.wear_table_out(session, row)


@router.get("/wear-tables/{table_id}/contacts", response_model=WearTableContactsOut)
def get_wear_table_contacts(table_id: int, session: SessionDep) -> WearTableContactsOut:
    """The raw per-contact quantities behind a computed table."""
    return wear_table_store.wear_table_contacts(session, table_id)
