"""Request bodies of the planning endpoints (fleets, vehicles, lathe plans)."""

from __future__ import annotations

from typing import Any

from pydantic import Field

from wearcast.service.schema_base import IsoDate, StoredId, Strict


class _Strict(Strict):
    """Planning bodies: the shared strict base (NaN and infinities are refused too)."""


class FleetIn(_Strict):
    """A fleet: its limit overrides (``sd_min_mm``, ``scrap_diameter_mm``, ...) and the
    vehicles that belong to it."""

    limits: dict[str, float] = Field(default_factory=dict)
    vehicles: list[str] = Field(default_factory=list)


class VehicleIn(_Strict):
    """Planning attributes of a vehicle: its mileage per day [km/day] and its fleet."""

    km_per_day: float | None = Field(default=None, gt=0, le=5000)
    fleet_id: str | None = Field(default=None, min_length=1, max_length=200)


class PlanIn(_Strict):
    """A lathe plan request.

    ``model_id`` and ``route_id`` name a calibrated model that forecasts the wheels with
    fewer than two measurements since turning; ``target_flange_thicknesses_mm`` the
    S1002 flange thicknesses a wheel may be turned to (32.5 = S1002 itself).
    """

    fleet_id: str | None = None
    start: IsoDate | None = None
    horizon_weeks: int = Field(default=26, ge=1, le=260)
    capacity_per_week: int = Field(default=4, ge=0, le=10_000)
    fixed_interval_km: float = Field(default=150_000.0, gt=0, le=5e6)
    model_id: StoredId | None = None
    route_id: int | str | None = None
    target_flange_thicknesses_mm: list[float] = Field(
        default_factory=lambda: [32.5, 31.5, 30.5, 29.5, 28.5], min_length=1, max_length=12)
    keep_diameter_differences: bool = Field(default=True, description=(
        "keep each bogie's and vehicle's wheelset diameters within the fleet's limits: deepen "
        "cuts, add companion turnings in the same week, or turn a bogie's wheelsets together "
        "(statistics.maintenance.lathe_plan); false plans each wheelset alone"))
    name: str | None = Field(default=None, max_length=200)

    def spec(self) -> dict[str, Any]:
        return self.model_dump(mode="json")
