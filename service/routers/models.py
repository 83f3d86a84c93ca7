"""``/v1/models``: calibrate a hybrid model, read it, predict, remaining mileage, pictures,
diagnose (the discrepancy finder) and its HTML report.

Calibration and the pictures are plain ``def`` endpoints: FastAPI runs them in its
threadpool, off the event loop. Predict and reprofiling are the hot paths: once a worker has
read a model and a route they run on the event loop without touching the database, and
return their answer serialised by orjson (see ``predict`` below).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import orjson
from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import HTMLResponse
from pydantic import BaseModel, ValidationError
from starlette.concurrency import run_in_threadpool

from wearcast.physics.vocabulary import BogieType, Side
from wearcast.service import (
    diagnosis_jobs,
    diagnosis_store,
    model_loading,
    model_store,
    physics_diagnosis_store,
    physics_jobs,
    physics_model_store,
    pictures,
    prediction_store,
    reprofiling_store,
    wheel_start,
)
from wearcast.service.db import Database
from wearcast.service.deps import SessionDep
from wearcast.service.diagnosis_schemas import DiagnoseIn, DiagnosisOut
from wearcast.service.errors import Unprocessable, validation_items
from wearcast.service.job_store import default_timeout, queue_job
from wearcast.service.model_schemas import ModelOut
from wearcast.service.physics_schemas import (
    JobAccepted,
    ModelCreateIn,
    PhysicsModelIn,
    PhysicsPredictionOut,
)
from wearcast.service.picture_cache import NOT_MODIFIED, picture_response
from wearcast.service.pictures import ImageFormat
from wearcast.service.prediction_schemas import PredictIn, PredictionOut
from wearcast.service.reprofiling_schemas import ReprofilingIn, ReprofilingOut
from wearcast.service.routers.measurements import parse_filter_json

router = APIRouter(tags=["models"])
QueryAxle = Annotated[int, Query(ge=1, le=2, description="1 or 2")]


_JOB_ANSWER: dict[int | str, dict[str, Any]] = {
    202: {"model": JobAccepted, "description": (
        "the work still runs as a job after the request's wait (setting job_wait_s, header "
        "Prefer: respond-async | wait=N): poll GET /v1/jobs/{id} (Location) for its result")}}


@router.post("/models", response_model=ModelOut, status_code=201, responses=_JOB_ANSWER)
def create_model(body: ModelCreateIn, session: SessionDep, request: Request) -> Any:
    """Calibrate a model.

    ``kind`` omitted or ``hybrid``: seed 001's hybrid model, calibrated at once (201).
    ``kind: "physics"``: the whole-vehicle wear loop of ``vehicle`` on ``route_id``'s curve
    classes with ``law``, its wear-coefficient scale fitted to the measured Sd/Sh/qR that
    ``calibration.filter`` selects. The request is validated at once (422/404 naming the
    field); the build runs as a job (``physics_model``) and the request waits for it: 201
    with the model when it ends within the wait, else 202 with the job, whose ``result``
    (``GET /v1/jobs/{id}``) names ``model_id`` once done; 422 when the run failed.
    """
    if isinstance(body, PhysicsModelIn):
        runner = request.app.state.jobs
        runner.check_quota(session)
        spec = physics_model_store.prepare(session, body)
        row = queue_job(session, body.name, spec, timeout_s=default_timeout())
        runner.submit(row.id)
        return physics_jobs.answer(request.app.state.database.session_factory, row.id,
                                   physics_jobs.wait_seconds(request), 201)
    return model_store.model_out(session, model_store.create_model(session, body))


@router.get("/models/{model_id}", response_model=ModelOut)
def get_model(model_id: int, session: SessionDep) -> Response:
    return _json(model_store.model_out_cached(session, model_id))


async def _physics(request: Request, model_id: int) -> bool:
    """Whether a model is a physics model (404 when there is none); read from the database
    once per process (a model's kind never changes), then from memory on the event loop."""
    url = _database_url(request)
    known = physics_model_store.known_kind(url, model_id)
    if known is None:
        known = await run_in_threadpool(_read_kind, request, url, model_id)
    return known


def _read_kind(request: Request, url: str, model_id: int) -> bool:
    with request.app.state.database.session_factory() as session:
        return physics_model_store.remember_kind(url, model_id,
                                                 physics_model_store.is_physics(session,
                                                                                model_id))


def _physics_answer(request: Request, model_id: int, body: Any, what: str) -> Response:
    with request.app.state.database.session_factory() as session:
        fn = physics_model_store.predict if what == "predict" else \
            physics_model_store.reprofiling
        return _bytes(orjson.dumps(fn(session, model_id, body)))


def _json(out: BaseModel) -> Response:
    """The answer, already validated by its schema, serialised once.

    Returning a Response spares FastAPI a second validation of the model (run in the
    threadpool for plain ``def`` endpoints) before the same serialisation; the
    ``response_model`` still documents the answer.
    """
    return Response(content=out.model_dump_json(), media_type="application/json")


def _bytes(content: bytes) -> Response:
    return Response(content=content, media_type="application/json")


def _database_url(request: Request) -> str:
    return str(request.app.state.database.engine.url)


def _predict_loading(request: Request, model_id: int, body: PredictIn) -> Response:
    """Predict with its inputs (and a measured start) read from the database (threadpool)."""
    database: Database = request.app.state.database
    with database.session_factory() as session:
        inputs, route = model_loading.load_inputs(session, model_id, body.route_id, body.route)
        start = wheel_start.wheel_start(session, body) if body.measured_start else None
    return _bytes(prediction_store.predict_json(inputs, route, model_id, body, start))


def _reprofiling_loading(request: Request, model_id: int, body: ReprofilingIn) -> Response:
    """Reprofiling with its inputs (and the wheel's latest state) read from the database."""
    database: Database = request.app.state.database
    with database.session_factory() as session:
        inputs, route = model_loading.load_inputs(session, model_id, body.route_id, body.route)
        start = wheel_start.wheel_start(session, body)
    return _bytes(reprofiling_store.reprofiling_json(inputs, route, model_id, body, start))


# Predict and reprofiling are the hot paths: about a millisecond of CPU each. When the model
# and the route are in process memory (every request after a worker's first), they are
# computed right here on the event loop, without a database session or a threadpool hop
# (the hop costs more CPU than it could save: the computation holds the GIL). Otherwise (the
# first request, a wheel's latest state) the database is read in the threadpool.
def _hot_inputs(request: Request, model_id: int, body: PredictIn | ReprofilingIn
                ) -> tuple[model_loading.ModelInputs, model_loading.RouteInputs] | None:
    """The model's and the route's inputs from process memory, or None (not read yet, or a
    stored start: a wheel's latest state is always read)."""
    if body.wheel_id is not None or body.measurement_id is not None:
        return None
    return model_loading.cached_inputs(_database_url(request), model_id, body.route_id,
                                       body.route)


@router.post("/models/{model_id}/predict", response_model=PredictionOut | PhysicsPredictionOut)
async def predict(model_id: int, body: PredictIn, request: Request) -> Response:
    """Predict a wheel position at mileages. A physics model answers
    ``PhysicsPredictionOut`` (Sd/Sh/qR P10/P50/P90 per mileage, on its own route)."""
    if await _physics(request, model_id):
        return await run_in_threadpool(_physics_answer, request, model_id, body, "predict")
    cached = _hot_inputs(request, model_id, body)
    if cached is None:
        return await run_in_threadpool(_predict_loading, request, model_id, body)
    start = wheel_start.wheel_start(None, body) if body.profile is not None else None
    return _bytes(prediction_store.predict_json(*cached, model_id, body, start))


@router.post("/models/{model_id}/reprofiling", response_model=ReprofilingOut)
async def reprofiling(model_id: int, body: ReprofilingIn, request: Request) -> Response:
    """Mileage at which the first limit is crossed (P10/P50/P90). A physics model follows
    its wheel position's series at its P90/P50/P10 wear scales (plus ``kind``,
    ``wear_scale``)."""
    if await _physics(request, model_id):
        return await run_in_threadpool(_physics_answer, request, model_id, body,
                                       "reprofiling")
    cached = _hot_inputs(request, model_id, body)
    if cached is None:
        return await run_in_threadpool(_reprofiling_loading, request, model_id, body)
    start = wheel_start.wheel_start(None, body)
    return _bytes(reprofiling_store.reprofiling_json(*cached, model_id, body, start))


_IMAGE: dict[int | str, dict[str, Any]] = {
    200: {"content": {"image/svg+xml": {}, "image/png": {}}}, **NOT_MODIFIED}


# The pictures answer with a strong ETag of their inputs (304 to a matching If-None-Match)
# and are drawn once per inputs (wearcast.service.picture_cache).
@router.get("/models/{model_id}/pictures/wear-area", response_class=Response,
            responses=_IMAGE)
def wear_area_picture(model_id: int, session: SessionDep, request: Request, route_id: str,
                      bogie_type: BogieType, axle: QueryAxle, side: Side,
                      wheel_id: str | None = None,
                      max_mileage_km: Annotated[float | None, Query(gt=0, le=5e6)] = None,
                      format: ImageFormat = "svg") -> Response:
    """Wear area over mileage: prediction corridor and measured points (seed 001 Fig. 11).
    Not for a physics model (422): it predicts Sd/Sh/qR, not region wear areas."""
    _no_physics_picture(session, model_id, "wear-area")
    job = pictures.wear_area_job(session, model_id, route_id=route_id,
                                 bogie_type=bogie_type, axle=axle, side=side,
                                 wheel_id=wheel_id, max_mileage_km=max_mileage_km, fmt=format)
    return picture_response(request, job, pictures.MEDIA_TYPES[format])


@router.get("/models/{model_id}/pictures/profile", response_class=Response,
            responses=_IMAGE)
def profile_picture(model_id: int, session: SessionDep, request: Request, route_id: str,
                    bogie_type: BogieType, axle: QueryAxle, side: Side,
                    mileage_km: Annotated[float, Query(ge=0, le=5e6)],
                    wheel_id: str | None = None, format: ImageFormat = "svg") -> Response:
    """Predicted worn profile vs reference and measured profiles (seed 001 Figs. 12–14).
    Not for a physics model (422): its run keeps the worn profiles at its end only."""
    _no_physics_picture(session, model_id, "profile")
    job = pictures.profile_job(session, model_id, route_id=route_id, bogie_type=bogie_type,
                               axle=axle, side=side, mileage_km=mileage_km,
                               wheel_id=wheel_id, fmt=format)
    return picture_response(request, job, pictures.MEDIA_TYPES[format])


@router.post("/models/{model_id}/diagnose", response_model=DiagnosisOut,
             responses={200: {"content": {"text/html": {}}}, **_JOB_ANSWER})
def diagnose(model_id: int, body: DiagnoseIn, session: SessionDep, request: Request,
             format: Literal["json", "html"] = "json") -> Response:
    """What the calibrated model gets wrong, the cause, the extension and its gain.

    ``?format=html`` returns the HTML report instead (figures included); ``save_as`` in the
    body stores the model extended by the verdict's cause as a new model.

    A physics model is diagnosed with the physical catalogue
    (``statistics.physics_diagnosis``: one loop run per catalogue value) as a job
    (``physics_diagnosis``): 200 with the diagnosis when it ends within the request's wait,
    else 202 with the job (its ``result`` is the diagnosis); no HTML report (422). A hybrid
    model's diagnosis runs on the request unless ``Prefer: respond-async`` or ``wait=N`` asks
    for a job (``diagnosis_jobs``), answered the same way.
    """
    if physics_model_store.is_physics(session, model_id):
        if format == "html":
            raise Unprocessable("format", "a physics model's diagnosis has no HTML report; "
                                "ask for json")
        job_id = physics_diagnosis_store.submit(session, request.app.state.jobs, model_id,
                                                body)
        return physics_jobs.answer(request.app.state.database.session_factory, job_id,
                                   physics_jobs.wait_seconds(request), 200)
    if format == "html":
        return HTMLResponse(diagnosis_store.report_html(session, model_id, body))
    if diagnosis_jobs.wants_job(request.headers.get("prefer", "")):
        job_id = diagnosis_jobs.submit(session, request.app.state.jobs, model_id, body)
        return physics_jobs.answer(request.app.state.database.session_factory, job_id,
                                   physics_jobs.wait_seconds(request), 200)
    return _json(diagnosis_store.diagnose(session, model_id, body))


@router.get("/models/{model_id}/diagnose/report", response_class=HTMLResponse)
def diagnose_report(model_id: int, session: SessionDep,
                    filter: Annotated[str | None, Query(description=(
                        "the diagnose filter as a JSON object"))] = None,
                    cause: str | None = None, seed: Annotated[int, Query(ge=0)] = 0
                    ) -> HTMLResponse:
    """The diagnosis as a self-contained HTML report (residuals against the named
    covariate, predicted vs measured wear areas before and after the extension)."""
    if physics_model_store.is_physics(session, model_id):
        raise Unprocessable("model_id", "a physics model's diagnosis has no HTML report: "
                            "POST /v1/models/{id}/diagnose answers it as JSON")
    body = DiagnoseIn(filter=_filter_from_query(filter), seed=seed)
    return HTMLResponse(diagnosis_store.report_html(session, model_id, body, cause))


def _filter_from_query(raw: str | None) -> dict:
    if raw is None or not raw.strip():
        return {}
    value = parse_filter_json(raw)
    try:
        return DiagnoseIn(filter=value).filter
    except ValidationError as exc:
        raise Unprocessable("filter", validation_items(exc.errors())[0]["reason"]) from exc


def _no_physics_picture(session: SessionDep, model_id: int, picture: str) -> None:
    if physics_model_store.is_physics(session, model_id):
        why = ("it predicts Sd/Sh/qR, not region wear areas" if picture == "wear-area" else
               "its run keeps the worn profiles at its end only, not at every mileage")
        raise Unprocessable("model_id", f"model {model_id} is a physics model: no {picture} "
                            f"picture ({why}); GET /v1/wheels/{{wheel_id}}/pictures/"
                            f"parameters?model_id={model_id} draws its Sd/Sh/qR")
