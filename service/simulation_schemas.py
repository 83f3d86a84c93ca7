"""Request and response bodies of wear-loop simulations (``/v1/simulations``).
"""

from __future__ import annotations

import datetime as dt
from typing import Any

from pydantic import Field, model_validator

from wearcast.physics.class_contacts import PatchWidth
from wearcast.physics.vocabulary import (
    Axle,
    BogieType,
    Direction,
    Side,
)
from wearcast.physics.wear_distribution import Application, SmoothingMethod
from wearcast.physics.wear_laws import LawName
from wearcast.physics.wear_loop import StepMode
from wearcast.service.job_schemas import JobStatusOut
from wearcast.service.profile_schemas import TrackRailsIn
from wearcast.service.schema_base import Strict, exactly_one


class SimulationClassIn(Strict):
    radius_m: float | None = Field(default=None, gt=0, le=1e6, description="null = tangent")
    direction: Direction = "left"
    cant_mm: float = Field(default=0.0, ge=0, le=250)
    speed_kmh: float | None = Field(default=None, gt=0, le=500)
    share: float = Field(default=1.0, ge=0, le=1)


class StepsIn(Strict):
    """Wheel steps: ``adaptive`` (max depth per step, seed 003's D_step) or ``fixed`` km."""

    mode: StepMode = "adaptive"
    count: int = Field(default=20, ge=1, le=200, description="number of wheel steps")
    depth_per_step_mm: float | None = Field(default=None, gt=0, le=5)
    step_km: float | None = Field(default=None, gt=0, le=1e6)
    max_step_km: float | None = Field(default=None, gt=0, le=1e7)
    contact_update_depth_mm: float | None = Field(default=None, ge=0, le=5)


class SmoothingIn(Strict):
    method: SmoothingMethod = "moving_average"
    window_mm: float | None = Field(default=None, gt=0, le=50)


class SimulationIn(TrackRailsIn):
    """``POST /v1/simulations``: the wear loop of one wheel over a route's curve classes."""

    name: str | None = Field(default=None, max_length=200)
    vehicle: str = Field(min_length=1, max_length=50, description="vehicle preset")
    bogie_type: BogieType = "trailer"
    route_id: int | str | None = None
    classes: list[SimulationClassIn] | None = Field(default=None, min_length=1,
                                                    max_length=200)
    law: LawName = "archard_kth"
    application: Application = "global"
    patch_width: PatchWidth = Field(default="hertz", description=(
        "contact patch width: hertz (the curving model's ellipse) or kik_piotrowski (widened to "
        "the unsmoothed gap: conformal flange-root patches become wide and mild)"))
    steps: StepsIn = Field(default_factory=StepsIn)
    axle: Axle = 1
    side: Side = "right"
    smoothing: SmoothingIn | None = None
    unbalanced_acceleration_m_s2: float = Field(default=0.58, ge=0, le=2)
    tangent_speed_kmh: float = Field(default=100.0, gt=0, le=500)

    @model_validator(mode="after")
    def _one_route(self) -> SimulationIn:
        exactly_one(self, "route_id", "classes")
        return self


class SimulationOut(JobStatusOut):
    spec: dict[str, Any]
    created_at: dt.datetime | None = None
    started_at: dt.datetime | None = None
    finished_at: dt.datetime | None = None
    result: dict[str, Any] | None = None
