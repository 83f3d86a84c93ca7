"""``/v1/models``: calibrate a hybrid model, read it, predict, remaining mileage, pictures,
diagnose (the discrepancy finder) and its HTML report.

Calibration and the pictures are plain ``def`` endpoints: FastAPI runs them in its
threadpool, off the event loop. Predict and reprofiling run there too, in one hop each, and
return their answer serialised (see ``_in_session`` and ``_json``).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import HTMLResponse
from pydantic import BaseModel, ValidationError
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

from wearcast.service import diagnosis_store, model_store, pictures
from wearcast.service.db import Database
from wearcast.service.deps import SessionDep
from wearcast.service.errors import Unprocessable, validation_items
from wearcast.service.pictures import ImageFormat
from wearcast.service.schemas import (
    BogieType,
    DiagnoseIn,
    DiagnosisOut,
    ModelIn,
    ModelOut,
    PredictIn,
    PredictionOut,
    ReprofilingIn,
    ReprofilingOut,
    Side,
)

router = APIRouter(tags=["models"])
QueryAxle = Annotated[int, Query(ge=1, le=2, description="1 or 2")]


@router.post("/models", response_model=ModelOut, status_code=201)
def create_model(body: ModelIn, session: SessionDep) -> ModelOut:
    return model_store.model_out(session, model_store.create_model(session, body))


@router.get("/models/{model_id}", response_model=ModelOut)
def get_model(model_id: int, session: SessionDep) -> ModelOut:
    return model_store.model_out(session, model_store.get_model_row(session, model_id))


def _json(out: BaseModel) -> Response:
    """The answer, already validated by its schema, serialised once.

    Returning a Response spares FastAPI a second validation of the model (run in the
    threadpool for plain ``def`` endpoints) before the same serialisation; the
    ``response_model`` still documents the answer.
    """
    return Response(content=out.model_dump_json(), media_type="application/json")


def _in_session(request: Request, call: Callable[[Session], BaseModel]) -> Response:
    """``call`` with a session of its own, its answer serialised (runs in the threadpool)."""
    database: Database = request.app.state.database
    with database.session_factory() as session:
        return _json(call(session))


# Predict and reprofiling are the hot paths: a few milliseconds of CPU each. They run in the
# threadpool like the plain ``def`` endpoints, but in a single hop: a ``def`` endpoint with
# the session dependency takes three (open the session, the endpoint, close the session).
@router.post("/models/{model_id}/predict", response_model=PredictionOut)
async def predict(model_id: int, body: PredictIn, request: Request) -> Response:
    return await run_in_threadpool(
        _in_session, request, lambda s: model_store.predict(s, model_id, body))


@router.post("/models/{model_id}/reprofiling", response_model=ReprofilingOut)
async def reprofiling(model_id: int, body: ReprofilingIn, request: Request) -> Response:
    return await run_in_threadpool(
        _in_session, request, lambda s: model_store.reprofiling(s, model_id, body))


@router.get("/models/{model_id}/pictures/wear-area", response_class=Response,
            responses={200: {"content": {"image/svg+xml": {}, "image/png": {}}}})
def wear_area_picture(model_id: int, session: SessionDep, route_id: str,
                      bogie_type: BogieType, axle: QueryAxle, side: Side,
                      wheel_id: str | None = None,
                      max_mileage_km: Annotated[float | None, Query(gt=0, le=5e6)] = None,
                      format: ImageFormat = "svg") -> Response:
    """Wear area over mileage: prediction corridor and measured points (seed 001 Fig. 11)."""
    image = pictures.wear_area_picture(session, model_id, route_id=route_id,
                                       bogie_type=bogie_type, axle=axle, side=side,
                                       wheel_id=wheel_id, max_mileage_km=max_mileage_km,
                                       fmt=format)
    return Response(content=image, media_type=pictures.MEDIA_TYPES[format])


@router.get("/models/{model_id}/pictures/profile", response_class=Response,
            responses={200: {"content": {"image/svg+xml": {}, "image/png": {}}}})
def profile_picture(model_id: int, session: SessionDep, route_id: str,
                    bogie_type: BogieType, axle: QueryAxle, side: Side,
                    mileage_km: Annotated[float, Query(ge=0, le=5e6)],
                    wheel_id: str | None = None, format: ImageFormat = "svg") -> Response:
    """Predicted worn profile vs reference and measured profiles (seed 001 Figs. 12–14)."""
    image = pictures.profile_picture(session, model_id, route_id=route_id,
                                     bogie_type=bogie_type, axle=axle, side=side,
                                     mileage_km=mileage_km, wheel_id=wheel_id, fmt=format)
    return Response(content=image, media_type=pictures.MEDIA_TYPES[format])


@router.post("/models/{model_id}/diagnose", response_model=DiagnosisOut)
def diagnose(model_id: int, body: DiagnoseIn, session: SessionDep,
             format: Literal["json", "html"] = "json") -> Response:
    """What the calibrated model gets wrong, the cause, the extension and its gain.

    ``?format=html`` returns the HTML report instead (figures included); ``save_as`` in the
    body stores the model extended by the verdict's cause as a new model.
    """
    if format == "html":
        return HTMLResponse(diagnosis_store.report_html(session, model_id, body))
    return _json(diagnosis_store.diagnose(session, model_id, body))


@router.get("/models/{model_id}/diagnose/report", response_class=HTMLResponse)
def diagnose_report(model_id: int, session: SessionDep,
                    filter: Annotated[str | None, Query(description=(
                        "the diagnose filter as a JSON object"))] = None,
                    cause: str | None = None, seed: Annotated[int, Query(ge=0)] = 0
                    ) -> HTMLResponse:
    """The diagnosis as a self-contained HTML report (residuals against the named
    covariate, predicted vs measured wear areas before and after the extension)."""
    body = DiagnoseIn(filter=_filter_from_query(filter), seed=seed)
    return HTMLResponse(diagnosis_store.report_html(session, model_id, body, cause))


def _filter_from_query(raw: str | None) -> dict:
    if raw is None or not raw.strip():
        return {}
    try:
        value = json.loads(raw)
    except json.JSONDecodeError as exc:
        raise Unprocessable("filter", f"not valid JSON: {exc}") from exc
    if not isinstance(value, dict):
        raise Unprocessable("filter", "must be a JSON object of field -> value(s)")
    try:
        return DiagnoseIn(filter=value).filter
    except ValidationError as exc:
        raise Unprocessable("filter", validation_items(exc.errors())[0]["reason"]) from exc
