"""``/v1/measurements``: batch import (multipart), one measurement as JSON, filtered listing."""

from __future__ import annotations

import json
from typing import Annotated, Any

from fastapi import APIRouter, File, Header, Query, Request, Response, UploadFile

from wearcast.service import importing, measurement_store
from wearcast.service.deps import SessionDep, SettingsDep
from wearcast.service.errors import Unprocessable
from wearcast.service.json_response import json_response
from wearcast.service.measurement_schemas import (
    ImportOut,
    MeasurementIn,
    MeasurementOut,
    MeasurementPage,
)

router = APIRouter(tags=["measurements"])

RESERVED = {"limit", "offset", "filter", "include_points"}
MAX_MANIFEST_BYTES = 50 * 1024 * 1024


@router.post("/measurements/import", response_model=ImportOut)
def import_measurements(
    session: SessionDep, settings: SettingsDep,
    file: Annotated[UploadFile, File(description="long CSV, parameter CSV, MiniProf or zip")],
    manifest: Annotated[UploadFile | None, File(description="manifest for MiniProf files")]
    = None,
    idempotency_key: Annotated[str | None, Header(alias="Idempotency-Key")] = None,
) -> ImportOut:
    manifest_bytes = None
    if manifest is not None:
        manifest_bytes = manifest.file.read(MAX_MANIFEST_BYTES + 1)
        if len(manifest_bytes) > MAX_MANIFEST_BYTES:
            raise Unprocessable("manifest", "larger than 50 MB")
    result = importing.import_upload(
        session, settings.raw_dir, file.file, file.filename or "upload",
        manifest=manifest_bytes, manifest_name=manifest.filename if manifest else None,
        idempotency_key=idempotency_key, chunk_size=settings.import_chunk_size)
    return ImportOut(**result.as_dict())


@router.post("/measurements", response_model=MeasurementOut, status_code=201)
def create_measurement(body: MeasurementIn, session: SessionDep) -> MeasurementOut:
    return measurement_store.create(session, body)


def parse_filter_json(raw: str) -> dict[str, Any]:
    """A ``?filter=<json>`` query parameter: a JSON object of field: value(s) (422 naming
    ``filter`` otherwise)."""
    try:
        parsed = json.loads(raw)
    except json.JSONDecodeError as exc:
        raise Unprocessable("filter", f"not valid JSON: {exc.msg}") from exc
    if not isinstance(parsed, dict):
        raise Unprocessable("filter", "must be a JSON object of field: value(s)")
    return parsed


def query_filter(request: Request, filter_json: str | None) -> dict[str, Any]:
    """The ``filter`` of a listing: ``?filter=<json>`` merged with ``?field=value`` params
    (repeat a parameter for a list of accepted values)."""
    out: dict[str, Any] = {}
    if filter_json:
        out.update(parse_filter_json(filter_json))
    for name in request.query_params:
        if name not in RESERVED:
            values = request.query_params.getlist(name)
            out[name] = values if len(values) > 1 else values[0]
    return out


@router.get("/measurements", response_model=MeasurementPage)
def list_measurements(
    request: Request, session: SessionDep,
    limit: Annotated[int, Query(ge=1, le=1000)] = 100,
    offset: Annotated[int, Query(ge=0)] = 0,
    filter: Annotated[str | None, Query(description="JSON object field -> value(s)")] = None,
    include_points: bool = False,
) -> Response:
    total, items = measurement_store.page(session, query_filter(request, filter), limit,
                                          offset, include_points)
    return json_response(MeasurementPage(total=total, limit=limit, offset=offset,
                                         items=items))


@router.get("/measurements/{measurement_id}", response_model=MeasurementOut)
def get_measurement(measurement_id: int, session: SessionDep) -> Response:
    return json_response(measurement_store.get(session, measurement_id))
