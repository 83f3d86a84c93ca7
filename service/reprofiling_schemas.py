"""Request and response bodies of the reprofiling forecast (``POST /v1/models/{id}/reprofiling``).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, model_validator

from wearcast.physics.vocabulary import (
    Axle,
    BogieType,
    Side,
)
from wearcast.service.prediction_schemas import check_one_route, check_wheel_start
from wearcast.service.profile_schemas import MeasuredProfileIn
from wearcast.service.route_schemas import RouteSpec
from wearcast.service.schema_base import StoredId, Strict


class Limits(Strict):
    sd_min_mm: float | None = Field(default=None, gt=0)
    sh_max_mm: float | None = Field(default=None, gt=0)
    qr_min_mm: float | None = Field(default=None, gt=0)


class ReprofilingIn(Strict):
    route_id: int | str | None = None
    route: RouteSpec | None = None
    wheel_id: str | None = Field(None, description="start from the wheel's latest measured "
                                 "profile (its Sd/Sh/qR and wear areas)")
    measurement_id: StoredId | None = Field(None, description="start from this measurement")
    profile: MeasuredProfileIn | None = Field(None, description="start from this profile")
    bogie_type: BogieType | None = None
    axle: Axle | None = None
    side: Side | None = None
    limits: Limits | None = None
    covariates: dict[str, Any] | None = None

    @model_validator(mode="after")
    def _check(self) -> ReprofilingIn:
        check_one_route(self)
        check_wheel_start(self)
        return self


class OptionalQuantiles(BaseModel):
    p10: float | None
    p50: float | None
    p90: float | None


class ReprofilingOut(BaseModel):
    """Mileages in km; ``None`` = no limit reached within the search horizon (see reason)."""

    model_id: int
    route: str
    wheel_id: str | None
    bogie_type: str
    axle: int
    side: str
    start_mileage_km: float
    start_measurement_id: int | None
    start_areas_mm2: dict[str, float]
    remaining_km: OptionalQuantiles
    mileage_km: OptionalQuantiles
    governing_limit: str | None
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    extrapolated: bool
    reason: str | None
    limits: dict[str, float]
    crossed_limits: dict[str, float] = Field(
        default_factory=dict, description="limits the measured start is already past, and by "
        "how much [mm]; remaining_km is then 0")
    start_parameters_mm: dict[str, float] | None = Field(
        None, description="measured Sd/Sh/qR the prediction starts from")
    start_notes: list[str] = Field(default_factory=list)
