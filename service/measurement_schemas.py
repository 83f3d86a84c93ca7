"""Request and response bodies of measurements (``/v1/measurements``) and of their imports.
"""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any

from pydantic import BaseModel, Field, model_validator

from wearcast.physics.vocabulary import (
    Axle,
    BogieType,
    RunningMode,
    Side,
)
from wearcast.service.schema_base import (
    MAX_MILEAGE_KM,
    MAX_PROFILE_POINTS,
    FieldsError,
    FilterValue,
    IsoDate,
    Strict,
)


class ReportedParameters(Strict):
    sd_mm: float | None = None
    sh_mm: float | None = None
    qr_mm: float | None = None


class MeasurementIn(Strict):
    """One measurement: a profile (``y_mm``/``z_mm``) or the parameters only."""

    wheel_id: str = Field(min_length=1, max_length=200)
    vehicle_id: str = Field(min_length=1, max_length=200)
    bogie_type: BogieType
    axle: Axle
    side: Side
    mileage_km: float = Field(ge=0, le=MAX_MILEAGE_KM)
    measured_on: IsoDate | None = None
    route_id: int | Annotated[str, Field(max_length=200)] | None = None
    running_mode: RunningMode | None = None
    instrument_id: str | None = Field(default=None, max_length=200)
    load_t: float | None = Field(default=None, ge=0, le=1000)
    reference_profile: str = Field(default="S1002", max_length=100)
    covariates: dict[str, FilterValue] = Field(default_factory=dict, max_length=100)
    diameter_mm: float | None = Field(default=None, gt=0, le=2000)
    # at least 10 points, published as minItems so the contract says what the check below says
    y_mm: list[float] | None = Field(default=None, min_length=10, max_length=MAX_PROFILE_POINTS)
    z_mm: list[float] | None = Field(default=None, min_length=10, max_length=MAX_PROFILE_POINTS)
    sd_mm: float | None = None
    sh_mm: float | None = None
    qr_mm: float | None = None
    instrument_parameters: ReportedParameters | None = None

    @model_validator(mode="after")
    def _points_or_parameters(self) -> MeasurementIn:
        has_points = self.y_mm is not None or self.z_mm is not None
        has_params = any(v is not None for v in (self.sd_mm, self.sh_mm, self.qr_mm))
        if has_points:
            if self.y_mm is None or self.z_mm is None:
                raise FieldsError(["z_mm" if self.z_mm is None else "y_mm"],
                                  "y_mm and z_mm must be given together")
            if len(self.y_mm) != len(self.z_mm):
                raise FieldsError(["y_mm", "z_mm"],
                                  f"y_mm has {len(self.y_mm)} points, z_mm {len(self.z_mm)}")
            if len(self.y_mm) < 10:
                raise FieldsError(["y_mm", "z_mm"], "a profile needs at least 10 points")
        elif has_params:
            missing = [k for k in ("sd_mm", "sh_mm", "qr_mm") if getattr(self, k) is None]
            if missing:
                raise FieldsError(missing,
                                  "a parameter-only measurement needs sd_mm, sh_mm and qr_mm")
        else:
            raise FieldsError(["y_mm", "z_mm", "sd_mm", "sh_mm", "qr_mm"],
                              "give the profile (y_mm, z_mm) or the parameters (sd_mm, sh_mm, "
                             "qr_mm)")
        return self


class MeasurementOut(BaseModel):
    id: int
    batch_id: int | None
    wheel_id: str
    vehicle_id: str
    bogie_type: str
    axle: int
    side: str
    mileage_km: float
    kind: str
    measured_on: dt.date | None
    route_id: str | None
    running_mode: str | None
    instrument_id: str | None
    load_t: float | None
    diameter_mm: float | None = None
    reference_profile: str
    covariates: dict[str, Any]
    source_file: str | None
    source_line: int | None
    n_points: int
    flange_area_mm2: float | None
    tread_area_mm2: float | None
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    reported_sd_mm: float | None
    reported_sh_mm: float | None
    reported_qr_mm: float | None
    lateral_shift_mm: float | None
    vertical_shift_mm: float | None
    rotation_rad: float | None
    rms_residual_mm: float | None
    reference_fits: bool | None = Field(None, description="false: the shape does not fit "
                                        "reference_profile; no wear areas until one is given")
    placement: dict[str, Any] | None = Field(None, description="datum found/guessed, tilt, "
                                             "alignment kind")
    warnings: list[dict[str, Any]] | None = None
    y_mm: list[float] | None = None
    z_mm: list[float] | None = None


class MeasurementPage(BaseModel):
    total: int
    limit: int
    offset: int
    items: list[MeasurementOut]


class ImportOut(BaseModel):
    batch_id: int
    duplicate: bool = Field(description="true when this content or key was imported before")
    file_name: str
    records: int = Field(description="records read from the upload")
    created: int = Field(description="measurements stored by this batch")
    duplicates: int = Field(description="measurements already present, skipped")
    points: int
    warnings: list[dict[str, Any]] = Field(
        default_factory=list, description="per file and line: code, level (info | warning), "
        "message, wheel_id, mileage_km (at most 1000 listed)")
    warnings_total: int = 0
