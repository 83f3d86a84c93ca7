"""``/v1/reference-profiles`` (the catalogue: built-in S1002 family and user profiles),
``/v1/wheels/{wheel_id}/reference`` (re-take a wheel's wear against another reference) and
the measured-wheel pictures (``/v1/wheels/{wheel_id}/pictures/parameters``,
``/v1/measurements/{measurement_id}/pictures/profile``)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Request, Response
from pydantic import Field, model_validator

from wearcast.service import models_db as db
from wearcast.service import reference_store, wheel_pictures, wheel_reference
from wearcast.service.deps import SessionDep
from wearcast.service.errors import NotFound
from wearcast.service.float32_blobs import floats_of
from wearcast.service.picture_cache import NOT_MODIFIED, picture_response
from wearcast.service.pictures import MEDIA_TYPES, ImageFormat
from wearcast.service.schema_base import MAX_PROFILE_POINTS, FieldsError, Strict

router = APIRouter(tags=["reference profiles"])


class ReferenceIn(Strict):
    """A reference profile: points in the wheel frame [mm] (y from the tape circle, back
    face at -70, z up, 0 at the tape circle), or the points of a stored measurement (a
    measured new wheel) named by ``measurement_id``."""

    name: str = Field(min_length=1, max_length=100)
    y_mm: list[float] | None = Field(None, min_length=20, max_length=MAX_PROFILE_POINTS)
    z_mm: list[float] | None = Field(None, min_length=20, max_length=MAX_PROFILE_POINTS)
    measurement_id: int | None = None
    description: str | None = Field(None, max_length=500)

    @model_validator(mode="after")
    def _one_source(self) -> ReferenceIn:
        points = self.y_mm is not None or self.z_mm is not None
        if points == (self.measurement_id is not None):
            raise FieldsError(["y_mm", "z_mm", "measurement_id"],
                              "give either y_mm and z_mm, or measurement_id")
        if points and (self.y_mm is None or self.z_mm is None):
            raise FieldsError(["z_mm" if self.z_mm is None else "y_mm"],
                              "y_mm and z_mm go together")
        return self


class WheelReferenceIn(Strict):
    reference_profile: str = Field(min_length=1, max_length=100, description=(
        "a catalogue name (S1002, S1002/31.5 …), an uploaded reference, or 'own' for the "
        "wheel's first measurement"))


@router.get("/reference-profiles")
def list_reference_profiles(session: SessionDep) -> list[dict[str, Any]]:
    return reference_store.list_references(session)


@router.post("/reference-profiles", status_code=201)
def create_reference_profile(body: ReferenceIn, session: SessionDep) -> dict[str, Any]:
    if body.measurement_id is not None:
        m = session.get(db.Measurement, body.measurement_id)
        if m is None or m.kind != "profile" or m.y_mm is None or m.z_mm is None:
            raise NotFound("measurement_id", f"no profile measurement with id "
                           f"{body.measurement_id}")
        y, z = floats_of(m.y_mm).tolist(), floats_of(m.z_mm).tolist()
        source = f"measurement {m.id} ({m.source_file or 'api'})"
    else:
        assert body.y_mm is not None and body.z_mm is not None
        y, z, source = body.y_mm, body.z_mm, "points"
    return reference_store.create_reference(session, body.name, y, z, body.description,
                                            source)


@router.put("/wheels/{wheel_id}/reference")
def set_wheel_reference(wheel_id: str, body: WheelReferenceIn,
                        session: SessionDep) -> dict[str, Any]:
    return wheel_reference.apply_reference(session, wheel_id, body.reference_profile)


_IMAGE: dict[int | str, dict[str, Any]] = {
    200: {"content": {"image/svg+xml": {}, "image/png": {}}}, **NOT_MODIFIED}


# The pictures answer with a strong ETag of their inputs (304 to a matching If-None-Match)
# and are drawn once per inputs (wearcast.service.picture_cache).
@router.get("/wheels/{wheel_id}/pictures/parameters", response_class=Response,
            responses=_IMAGE)
def wheel_parameters_picture(
        wheel_id: str, session: SessionDep, request: Request, model_id: int,
        route_id: str | None = None,
        horizon_km: Annotated[float | None, Query(gt=0)] = None,
        format: ImageFormat = "svg") -> Response:
    """Sd, Sh, qR against mileage: measured points, predicted P10–P90 band, limits and the
    crossing. ``route_id`` is required for a hybrid model; a physics model runs on its own
    route (give none or that one)."""
    job = wheel_pictures.wheel_parameter_job(session, model_id, wheel_id=wheel_id,
                                             route_id=route_id, horizon_km=horizon_km,
                                             fmt=format)
    return picture_response(request, job, MEDIA_TYPES[format])


@router.get("/measurements/{measurement_id}/pictures/profile", response_class=Response,
            responses=_IMAGE)
def measurement_profile_picture(measurement_id: int, session: SessionDep, request: Request,
                                format: ImageFormat = "svg") -> Response:
    """The measured profile over its reference, the wear area shaded."""
    job = wheel_pictures.measurement_profile_job(session, measurement_id, fmt=format)
    return picture_response(request, job, MEDIA_TYPES[format])
