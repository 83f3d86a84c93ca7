"""Request and response bodies of physics models (``POST /v1/models`` with ``kind:
"physics"``) and of the jobs that build and diagnose them.

A physics model is the whole-vehicle wear loop (``physics.vehicle_wear_simulation``: every
wheel of every bogie, both running directions, averaged as measured) of a vehicle preset on
a stored route's curve classes with a wear law, and one wear-coefficient scale fitted to the
measured Sd/Sh/qR the calibration filter selects (``statistics.physics_model``).
"""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from pydantic import BaseModel, Discriminator, Field, JsonValue, Tag, field_validator

from wearcast.physics.class_contacts import PatchWidth
from wearcast.physics.vehicles import preset_names
from wearcast.physics.wear_distribution import Application
from wearcast.physics.wear_laws import LawName
from wearcast.service.job_schemas import JobStatusOut
from wearcast.service.model_schemas import ModelIn
from wearcast.service.profile_schemas import TrackRailIdsIn
from wearcast.service.schema_base import Filter, Strict

#: Largest simulated mileage of a physics model's run [km].
MAX_SIMULATED_KM = 1_000_000.0
#: The most steps one loop run may take (a request's ``simulation.max_steps`` is at most this;
#: the physics diagnosis allows it to every catalogue run).
MAX_STEPS_PER_RUN = 400
#: Largest rail tonnage a physics model's run takes (rail steps are bounded) [Mt].
MAX_RAIL_TONNAGE_MT = 30.0
#: Most curve classes a route's segments are binned into for a physics model [-].
MAX_CURVE_CLASSES = 20


class PhysicsCalibrationIn(Strict):
    """The measured wheels the wear-coefficient scale is calibrated on: the filter of the
    hybrid model's calibration (any measurement field or covariate, ``mileage_km_min`` ...;
    profile and parameter-only measurements both count: their Sd/Sh/qR are used)."""

    route_id: int | Annotated[str, Field(max_length=200)] | None = Field(default=None,
        description="the model's route_id may be given here instead (as for hybrid models)")
    filter: Filter = Field(default_factory=dict)


class PhysicsSimulationIn(Strict):
    """Options of the whole-vehicle run (bounded; the defaults suit a calibration)."""

    depth_per_step_mm: float = Field(default=0.8, ge=0.05, le=5.0, description=(
        "D_step: largest normal wear depth of any wheel per step [mm] (seed 003 eq. 2: 0.2; "
        "physics.adaptive_step); the Aosta run's FT and qR losses at 3,600 km change by "
        "12.5 % from 0.8 to 0.4 mm, 5.8 % from 0.4 to 0.2 mm and 1.6 % from 0.2 to 0.1 mm "
        "(benchmarks/validate_aosta_measured.py): the wear scale absorbs a coarse step's "
        "uniform part; step_convergence halves it until the change is < 2 %"))
    mileage_km: float | None = Field(default=None, gt=0, le=MAX_SIMULATED_KM, description=(
        "simulated mileage [km]; default: twice the furthest calibration mileage, run "
        "further (up to max_mileage_km) when the fitted scale needs more"))
    max_mileage_km: float = Field(default=MAX_SIMULATED_KM, gt=0, le=MAX_SIMULATED_KM,
                                  description=(
        "the automatic mileage never exceeds this [km]"))
    max_steps: int = Field(default=200, ge=1, le=MAX_STEPS_PER_RUN,
                           description="most steps of one run")
    step_convergence: bool = Field(default=False, description=(
        "halve D_step (twice at most) until FT and qR at the end change by < 2 % of their "
        "loss (physics.step_convergence); up to three runs"))
    forward_share: float = Field(default=0.5, ge=0, le=1, description=(
        "share of the mileage run with axle 1 leading (0.5: reverses at the termini)"))
    flange_wear_factor: float = Field(default=1.0, ge=0, le=10, description=(
        "factor on the wear of flange patches (lubrication < 1)"))
    friction: float | None = Field(default=None, gt=0, lt=1.5, description=(
        "wheel-rail friction replacing the preset's"))
    patch_width: PatchWidth = "hertz"
    application: Application = "global"
    traction_torque_nm: float | None = Field(default=None, ge=-50_000, le=50_000, description=(
        "driving (+) or braking (-) torque on every axle of the motor bogies [N m], held over "
        "the whole route (the line's mean tractive effort); default: the preset's (none)"))
    rail_tonnage_mt: float | None = Field(default=None, ge=0, le=MAX_RAIL_TONNAGE_MT,
                                          description=(
        "run on the rail worn by the vehicle's own passages on the route to this tonnage "
        "[Mt] (the rail-step model of seed 003 §6.1, physics.rail_tonnage); default: new"))
    curve_classes: int | None = Field(default=None, ge=1, le=MAX_CURVE_CLASSES, description=(
        "bin the route's segments into this many radius and cant classes instead of the "
        "stored route's (7); the route must have been stored with its segments"))


class PhysicsModelIn(TrackRailIdsIn):
    """``POST /v1/models`` with ``kind: "physics"``: with ``rail_id`` / ``high_rail_id`` /
    ``low_rail_id`` (:class:`TrackRailIdsIn`, the rules of ``POST /v1/simulations``) the run,
    its calibration and every diagnosis run are on those stored rails (not with
    ``simulation.rail_tonnage_mt``: the rail-step model wears the nominal rail)."""

    kind: Literal["physics"]
    name: str = Field(min_length=1, max_length=200)
    vehicle: str = Field(min_length=1, max_length=50, description=(
        "vehicle preset (physics/vehicles.py): its whole vehicle's bogies (the Minuetto: two "
        "motor and two trailer bogies; other presets one of each)"),
        json_schema_extra={"enum": list[JsonValue](preset_names())})  # refused by _preset
    route_id: int | Annotated[str, Field(max_length=200)] | None = Field(default=None,
        description="a stored route (id or name): its curve classes are simulated")
    law: LawName = Field(default="usfd", description=(
        "wear law (physics/wear_laws.py); default seed 003's USFD, as the Aosta validation"))
    calibration: PhysicsCalibrationIn = Field(default_factory=PhysicsCalibrationIn)
    simulation: PhysicsSimulationIn = Field(default_factory=PhysicsSimulationIn)

    @field_validator("vehicle")
    @classmethod
    def _preset(cls, name: str) -> str:
        if name not in preset_names():
            raise ValueError(f"unknown vehicle preset {name!r}; known: "
                             f"{', '.join(preset_names())}")
        return name


def _model_kind(value: Any) -> str:
    kind = value.get("kind", "hybrid") if isinstance(value, dict) else getattr(
        value, "kind", "hybrid")
    return f"kind={kind}"


#: The body of ``POST /v1/models``: a hybrid model (``kind`` omitted or ``hybrid``) or a
#: physics model (``kind: physics``). Tags are stripped from error locations
#: (``errors.validation_items``), so a 422 names the body's own field.
ModelCreateIn = Annotated[
    Annotated[ModelIn, Tag("kind=hybrid")] | Annotated[PhysicsModelIn, Tag("kind=physics")],
    Discriminator(_model_kind, custom_error_type="model_kind",
                  custom_error_message="kind must be hybrid or physics")]


class PhysicsPointOut(BaseModel):
    """One mileage of a physics prediction: Sd/Sh/qR [mm] at the P50 wear scale, their
    P10/P50/P90, the vehicle mean (all wheels, P50 scale) and whether the run was continued
    past its end to reach it."""

    mileage_km: float
    sd_mm: float
    sh_mm: float
    qr_mm: float
    quantiles: dict[str, dict[str, float]]
    vehicle_mean_mm: dict[str, float]
    extrapolated: bool


class PhysicsPredictionOut(BaseModel):
    """``POST /v1/models/{id}/predict`` of a physics model."""

    model_id: int
    kind: Literal["physics"] = "physics"
    route: str
    bogie_type: str
    axle: int
    side: str
    wear_scale: dict[str, float] = Field(description="P10/P50/P90 wear-coefficient scales")
    spread_method: str
    points: list[PhysicsPointOut]
    start_mileage_km: float | None = None
    start_measurement_id: int | None = None
    start_parameters_mm: dict[str, float] | None = None
    start_notes: list[str] = Field(default_factory=list)


class JobAccepted(JobStatusOut):
    """202: the work runs as a job; poll ``GET /v1/jobs/{id}`` (``result`` once done)."""

    kind: str
    created_at: dt.datetime | None = None
    result: dict[str, Any] | None = None
