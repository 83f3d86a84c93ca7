"""``/v1/wear-tables``: curve-radius tables of wear measures (CSV upload)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Form, UploadFile

from wearcast.service import wear_table_store
from wearcast.service.deps import SessionDep
from wearcast.service.errors import Unprocessable
from wearcast.service.schemas import WearTableOut

router = APIRouter(tags=["wear tables"])


@router.post("/wear-tables", response_model=WearTableOut, status_code=201)
def upload_wear_table(session: SessionDep, file: Annotated[UploadFile, File()],
                      name: Annotated[str | None, Form()] = None) -> WearTableOut:
    data = file.file.read(wear_table_store.MAX_TABLE_BYTES + 1)
    if len(data) > wear_table_store.MAX_TABLE_BYTES:
        raise Unprocessable("file", "the table is larger than 20 MB")
    row = wear_table_store.upload_wear_table(session, data, file.filename or "table.csv", name)
    return wear_table_store.wear_table_out(session, row)


@router.get("/wear-tables/{table_id}", response_model=WearTableOut)
def get_wear_table(table_id: int, session: SessionDep) -> WearTableOut:
    row = wear_table_store.get_wear_table(session, table_id, "table_id")
    return wear_table_store.wear_table_out(session, row)
