"""Request and response bodies of curve-radius wear tables (``/v1/wear-tables``).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, model_validator

from wearcast.physics.wear_tables import ContactModel
from wearcast.service.profile_schemas import TrackRailsIn
from wearcast.service.schema_base import Strict, exactly_one


class WearTableRowOut(BaseModel):
    bogie_type: str
    wheelset: str
    rail: str
    radius_m: float | None
    region: str
    measure: str
    value: float


class WearTableOut(BaseModel):
    id: int
    name: str
    source: str
    sha256: str
    n_rows: int
    kind: str = "uploaded"
    spec: dict[str, Any] | None = None
    rows: list[WearTableRowOut] | None = None


class VehiclePairIn(Strict):
    """Two presets: the motor bogie of one and the trailer bogie of another (or the same)."""

    motor: str = Field(min_length=1, max_length=50, description="preset for the motor bogie")
    trailer: str = Field(min_length=1, max_length=50, description="preset for the trailer bogie")


class RadiusIn(Strict):
    radius_m: float | None = Field(gt=0, le=1e6, description="radius [m]; null = tangent")
    cant_mm: float = Field(default=0.0, ge=0, le=250, description="cant [mm]")
    speed_kmh: float | None = Field(default=None, gt=0, le=500, description=(
        "speed [km/h]; null = from the unbalanced lateral acceleration"))
    share: float | None = Field(default=None, ge=0, le=1, description="share of the route [-]")


class WearTableComputeIn(TrackRailsIn):
    """``POST /v1/wear-tables/compute``: a table from the physics core (quasi-static curving).

    ``vehicle`` is a preset name (motor and trailer variants) or ``{motor, trailer}`` preset
    names; the radii come from a stored route's classes (``route_id``: id or name) or are
    given (``radii``), exactly one of them. A tangent row is always computed.
    """

    name: str = Field(min_length=1, max_length=200)
    vehicle: str | VehiclePairIn
    route_id: int | str | None = None
    radii: list[RadiusIn] | None = Field(default=None, min_length=1, max_length=200)
    unbalanced_acceleration_m_s2: float = Field(default=0.58, ge=0, le=2, description=(
        "a_nc for classes without a speed [m/s²] (seed 001: 0.58)"))
    friction: float | None = Field(default=None, gt=0, le=1, description=(
        "wheel-rail friction coefficient (default: the preset's)"))
    tangent_speed_kmh: float = Field(default=100.0, gt=0, le=500)
    max_speed_kmh: float | None = Field(default=None, gt=0, le=500)
    contact_model: ContactModel = Field(
        default="table", description=(
            "contacts the wear measures come from: the contact table's Hertz ellipses at the "
            "curving equilibrium (`table`); the one contact pipeline's patches (non-Hertzian "
            "where the patch is not elliptic) at that same pose, where its forces need not "
            "balance (`pipeline`, about 0.1 s per class); or the pipeline's patches at the "
            "equilibrium of the pipeline's own forces (`pipeline_equilibrium`, 1-12 s per "
            "class, minutes for a route: send it as a job)"))

    @model_validator(mode="after")
    def _one_source(self) -> WearTableComputeIn:
        exactly_one(self, "route_id", "radii")
        return self


class WearTableContactsOut(BaseModel):
    """The raw per-contact quantities behind a computed table, one record per bogie type,
    curve class, axle, side and contact patch (units in the column names)."""

    wear_table_id: int
    n_contacts: int
    columns: list[str]
    contacts: list[dict[str, Any]]
