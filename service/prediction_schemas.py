"""Request and response bodies of wear predictions (``POST /v1/models/{id}/predict``).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, field_validator, model_validator

from wearcast.physics.vocabulary import (
    Axle,
    BogieType,
    Side,
)
from wearcast.service.profile_schemas import MeasuredProfileIn
from wearcast.service.route_schemas import RouteSpec
from wearcast.service.schema_base import MAX_MILEAGE_KM, FieldsError, StoredId, Strict, at_most_one


def check_one_route(body: Any) -> None:
    """A request names its route by ``route_id`` or gives it inline (``route``), not both;
    neither: a physics model runs on its own route, a hybrid model answers 422 route_id."""
    at_most_one(body, "route_id", "route")


def check_wheel_start(body: Any) -> None:
    """A request starts from at most one of ``wheel_id``, ``measurement_id``, ``profile``,
    and without a stored one (``wheel_id``/``measurement_id``) gives the wheel's position."""
    at_most_one(body, "wheel_id", "measurement_id", "profile")
    stored = body.wheel_id is not None or body.measurement_id is not None
    missing = [k for k in ("bogie_type", "axle", "side") if getattr(body, k) is None]
    if not stored and missing:
        raise FieldsError(missing, "give wheel_id or measurement_id, or bogie_type, axle and "
                          "side")


class RouteRef(Strict):
    route_id: int | str | None = None
    route: RouteSpec | None = None

    @model_validator(mode="after")
    def _one_route(self) -> RouteRef:
        check_one_route(self)
        return self


class PredictIn(RouteRef):
    bogie_type: BogieType | None = None
    axle: Axle | None = None
    side: Side | None = None
    wheel_id: str | None = Field(None, description="start from the wheel's latest measured "
                                 "profile; mileage_km then counts from that measurement")
    measurement_id: StoredId | None = Field(None, description="start from this measurement")
    profile: MeasuredProfileIn | None = Field(None, description="start from this profile")
    covariates: dict[str, Any] | None = Field(default=None, description=(
        "the wheel's covariates for an extended model (load_t, running_mode, ...)"))
    mileage_km: list[float] = Field(min_length=1, max_length=1000)

    @model_validator(mode="after")
    def _start(self) -> PredictIn:
        check_wheel_start(self)
        return self

    @property
    def measured_start(self) -> bool:
        return any(v is not None for v in (self.wheel_id, self.measurement_id, self.profile))

    @field_validator("mileage_km")
    @classmethod
    def _non_negative(cls, values: list[float]) -> list[float]:
        for i, value in enumerate(values):
            if value < 0:
                raise ValueError(f"mileage_km[{i}] = {value} is negative")
            if value > MAX_MILEAGE_KM:
                raise ValueError(f"mileage_km[{i}] = {value:g} is beyond {MAX_MILEAGE_KM:g} km")
        return values


class QuantileValues(BaseModel):
    p10: float
    p50: float
    p90: float


class PredictionAt(BaseModel):
    mileage_km: float
    flange_area_mm2: QuantileValues
    tread_area_mm2: QuantileValues
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    extrapolated: bool
    wear_mm: list[float | None]
    z_mm: list[float | None]


class PredictionOut(BaseModel):
    model_id: int
    route: str
    bogie_type: str
    axle: int
    side: str
    weighted_measure: dict[str, float]
    rates_mm2_per_km: dict[str, QuantileValues]
    start_areas_mm2: dict[str, float]
    y_mm: list[float]
    reference_z_mm: list[float]
    points: list[PredictionAt]
    start_mileage_km: float | None = None
    start_measurement_id: int | None = None
    start_parameters_mm: dict[str, float] | None = None
    start_notes: list[str] = Field(default_factory=list)
