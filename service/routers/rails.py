"""``/v1/rails``: measured rail heads (MiniProf ``.ban`` and rail parts of ``.mpt``).

``POST /v1/rails/import`` takes one rail file (multipart ``file``) with optional form fields
``name``, ``gauge_side`` (``negative_x``/``positive_x``: which instrument-X side faces the
track centre, when the file does not tell), ``inclination`` (laying slope, ``1/40``) and
``reference`` (``60E1``, ``UIC60``, ``60E2`` or ``rail:<id>``). Wheel files belong to
``POST /v1/measurements/import``; a rail has no wheel, bogie or mileage, hence its own
endpoint. ``GET /v1/rails`` and ``GET /v1/rails/{id}`` answer with the rail frame and the head
wear (``?reference=`` to take it against another head).
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Form, Query, UploadFile

from wearcast.service import rail_store
from wearcast.service.deps import SessionDep, SettingsDep
from wearcast.service.errors import Unprocessable
from wearcast.service.rail_schemas import RailImportOut, RailOut
from wearcast.service.readers.miniprof_rail import GaugeSide

router = APIRouter(tags=["rails"])


@router.post("/rails/import", response_model=RailImportOut)
def import_rail(
    session: SessionDep, settings: SettingsDep,
    file: Annotated[UploadFile, File(description="MiniProf rail file (.ban, .mpt)")],
    name: Annotated[str | None, Form(max_length=200)] = None,
    gauge_side: Annotated[GaugeSide | None, Form(description=(
        "instrument-X side of the gauge face (default: from the file)"))] = None,
    inclination: Annotated[str | None, Form(description="laying inclination, e.g. 1/40")]
    = None,
    reference: Annotated[str, Form(description="60E1, UIC60, 60E2 or rail:<id>")] = "60E1",
) -> RailImportOut:
    """Import the rail profiles of a MiniProf file; a repeated file creates nothing."""
    data = file.file.read(rail_store.MAX_RAIL_FILE_BYTES + 1)
    if len(data) > rail_store.MAX_RAIL_FILE_BYTES:
        raise Unprocessable("file", "the file is larger than 20 MB")
    return rail_store.import_rail_file(
        session, data, file.filename or "upload.ban", name=name, gauge_side=gauge_side,
        inclination=rail_store.parse_inclination(inclination), reference=reference,
        raw_dir=settings.raw_dir)


@router.get("/rails", response_model=list[RailOut])
def list_rails(session: SessionDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100,
               offset: Annotated[int, Query(ge=0)] = 0,
               reference: str | None = None) -> list[RailOut]:
    """Stored rails in import order, with their head wear."""
    return rail_store.list_rails(session, limit, offset, reference)


@router.get("/rails/{rail_id}", response_model=RailOut)
def get_rail(rail_id: int, session: SessionDep, reference: str | None = None,
             include_points: bool = False) -> RailOut:
    """One rail: frame, head wear (against ``reference``, default the rail's), points."""
    row = rail_store.get_rail_row(session, rail_id)
    return rail_store.rail_out(session, row, reference, include_points)
