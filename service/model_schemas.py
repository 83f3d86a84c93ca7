"""Request and response bodies of stored models (``POST/GET /v1/models``).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field

from wearcast.physics.vocabulary import RunningMode
from wearcast.physics.vocabulary import WearMeasure as Measure
from wearcast.service.schema_base import Filter, StoredId, Strict


class CalibrationIn(Strict):
    route_id: int | str
    filter: Filter = Field(default_factory=dict)


class ModelIn(Strict):
    """A hybrid model (seed 001): calibrated on profile measurements with a curve-radius
    table. ``kind`` may be omitted (hybrid is the default)."""

    kind: Literal["hybrid"] = "hybrid"
    name: str = Field(min_length=1, max_length=200)
    measure: Measure
    running_mode: RunningMode
    wear_table_id: StoredId
    calibration: CalibrationIn


class PhysicsModelSummary(BaseModel):
    """``ModelOut.physics`` of a physics model."""

    vehicle: str
    law: str
    route_id: int
    options: dict[str, Any] = Field(description="VehicleWearOptions of the run")
    wear_scale: float = Field(description="fitted wear-coefficient scale c [-]")
    wear_scale_p10: float
    wear_scale_p90: float
    spread: dict[str, Any] = Field(description="how P10/P90 were derived (method, log_sigma, "
                                   "per-vehicle scales)")
    rms_mm: float = Field(description="RMS error of the fitted FT/FH/qR points [mm]")
    at_reach: bool = Field(description="the fit ended at the largest scale the run reaches")
    calibrated_on: dict[str, Any] = Field(description=(
        "filter, n_measurements, measurement_ids, vehicles, n_points and the vehicle-averaged "
        "series (vehicle, distance_km, FT_mm, FH_mm, QR_mm, n_wheels) the scale was fitted "
        "to"))
    series: dict[str, Any] = Field(description=(
        "vehicle means of the run at scale c: mileage_km (wheel km), ft_mm, fh_mm, qr_mm"))
    errors: dict[str, Any] = Field(description=(
        "per_vehicle and overall: n, bias_mm, rms_mm, measured and simulated loss per "
        "1,000 km, per quantity (FT_mm, FH_mm, QR_mm)"))
    simulation: dict[str, Any] = Field(description=(
        "the run: simulated mileage, steps, D_step, contact updates and fallbacks, elapsed_s, "
        "step_convergence, runs made"))
    warnings: list[str] = Field(default_factory=list)
    rails: dict[str, Any] = Field(default_factory=dict, description=(
        "the stored rails the run is on, per request field (rail_id, high_rail_id, "
        "low_rail_id): rail_id, name, kind, stated inclination; empty: the preset's nominal "
        "rail"))


class ModelOut(BaseModel):
    """A stored model. ``kind``: ``hybrid`` (seed 001's statistical model), ``extended`` (a
    hybrid model extended by the discrepancy finder) or ``physics`` (the whole-vehicle wear
    loop with a calibrated wear-coefficient scale: ``measure``, ``running_mode`` and
    ``wear_table_id`` are null, ``physics`` holds the calibration; a physics model saved by
    a diagnosis also has ``derived_from`` and ``extension``)."""

    id: int
    name: str
    measure: str | None
    running_mode: str | None
    wear_table_id: int | None
    route_id: int
    calibration: dict[str, Any]
    n_calibration_measurements: int
    summary: dict[str, Any]
    kind: Literal["hybrid", "extended", "physics"] = "hybrid"
    derived_from: int | None = None
    extension: dict[str, Any] | None = None
    physics: PhysicsModelSummary | None = None
