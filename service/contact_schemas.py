"""Schemas of ``POST /v1/contact``: the loaded wheel-rail contact at given poses
(``physics.contact.pose_contact``)."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field, model_validator

from wearcast.physics.contact.fastsim import Bound
from wearcast.physics.contact.normal_contact import NormalMethod
from wearcast.physics.profiles.rails import RailName
from wearcast.physics.vocabulary import Side
from wearcast.service.profile_schemas import MeasuredProfilesIn
from wearcast.service.schema_base import FieldsError, Strict, at_most_one

#: Most poses in one request (2-9 ms of one core each with auto, bem-coarse, kp or hertz on
#: S1002/60E1; the fine ``bem`` is held to the ``max_fine_bem_poses`` setting).
MAX_POSES = 100
#: Largest SIMPACK profile file accepted [characters].
MAX_PROFILE_FILE_CHARS = 2_000_000


class ProfileFileIn(Strict):
    """A profile file sent as text: SIMPACK/CONTACT ``.prw`` (wheel) or ``.prr`` (rail)."""

    format: Literal["simpack"] = "simpack"
    text: str = Field(min_length=1, max_length=MAX_PROFILE_FILE_CHARS)


class PoseIn(Strict):
    shift_mm: float = Field(ge=-25, le=25, description=(
        "lateral shift of the wheelset [mm], positive towards the left rail"))
    yaw_rad: float = Field(default=0.0, ge=-0.05, le=0.05, description=(
        "yaw [rad], positive turning the front to the left"))
    roll_rad: float | None = Field(default=None, ge=-0.1, le=0.1, description=(
        "roll [rad], positive when the left wheel rises; null solves it with both wheels "
        "touching their rails"))
    wheel_load_n: float = Field(default=10_000.0, gt=0, le=500_000, description=(
        "vertical force of the wheel on its rail [N]"))


class ContactIn(MeasuredProfilesIn):
    """The wheel: S1002 by default, or a stored measurement (``measurement_id``, ``wheel_id``),
    a profile in the request (``profile``) or a SIMPACK ``.prw`` file (``wheel_file``); the
    rail: ``rail`` by name (60E1, 60E2), a stored rail (``rail_id``) or a SIMPACK ``.prr``
    file (``rail_file``), inclined by ``inclination`` (give 0 for a file that is already
    canted, as CONTACT's MBench_UIC60_v3.prr)."""

    wheel_file: ProfileFileIn | None = None
    rail: RailName = "60E1"
    rail_file: ProfileFileIn | None = None
    inclination: float = Field(default=1.0 / 40.0, ge=0, le=0.1, description=(
        "rail inclination as a slope (1/40 = 0.025)"))
    nominal_radius_mm: float = Field(default=460.0, ge=200, le=800, description=(
        "wheel radius at the tape circle [mm]"))
    side: Side = "left"
    poses: list[PoseIn] = Field(min_length=1, max_length=MAX_POSES)
    speed_m_s: float = Field(default=2.0, gt=0, le=100)
    friction: float = Field(default=0.3, gt=0, le=1)
    shear_modulus_mpa: float = Field(default=82_000.0, gt=1_000, le=300_000)
    poisson: float = Field(default=0.28, ge=0, lt=0.5)
    normal_method: NormalMethod = Field(
        default="auto", description=(
            "normal problem: auto (Hertz where the patch is elliptic, else the coarse "
            "boundary-element solution), bem, bem-coarse, kp (Kik-Piotrowski), hertz"))
    fastsim_grid: int = Field(default=40, ge=8, le=100)
    traction_bound: Bound = "parabolic"

    @model_validator(mode="after")
    def _one_wheel_one_rail(self) -> ContactIn:
        others = [k for k in ("wheel_id", "measurement_id", "profile")
                  if getattr(self, k) is not None]
        if self.wheel_file is not None and others:
            raise FieldsError(["wheel_file", *others],
                              f"give at most one of wheel_file, {', '.join(others)}")
        at_most_one(self, "rail_file", "rail_id")
        return self


class ContactOut(BaseModel):
    wheel: dict[str, Any]
    rail: dict[str, Any]
    side: Side
    inclination: float
    nominal_radius_mm: float
    method: str
    poses: list[dict[str, Any]] = Field(description=(
        "per pose: shift_mm, yaw_rad, roll_rad (as given or solved), roll_solved, "
        "wheel_load_n, approach_mm (vertical), vertical_force_n, lateral_force_n, n_patches, "
        "patches (field side first: y_wheel_mm, y_track_mm, contact_angle_rad, "
        "normal_force_n, fx_n, fs_n, mz_nmm, xi, eta, phi_per_mm, peak_pressure_mpa, "
        "area_mm2, a_mm, b_mm, normal_method); forces on the rail, F_s towards the wheel's "
        "field side"))
