"""Bodies of ``/v1/rails``: measured rail heads, their frame facts and head wear measures."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, Field

from wearcast.physics.profiles.measured_rail import RailKind
from wearcast.physics.rail_head_wear import RailHeadWear
from wearcast.service.readers.miniprof_rail import GaugeSide, NotRailKind


class RailFrameOut(BaseModel):
    """The rail frame of a measured head [mm]: y lateral (gauge side negative), z up, the
    instrument's origin kept (mirrored / sign-fixed only, ``gauge_side``/``y_down``); the top
    of the head, the gauge point 14 mm below it, the head width there (both sides measured)."""

    gauge_side: GaugeSide
    gauge_side_source: str
    y_down: bool
    top_mm: tuple[float, float]
    gauge_point_mm: tuple[float, float] | None
    head_width_mm: float | None
    gauge_depth_mm: float
    field_depth_mm: float
    inclination: float | None = Field(description=(
        "laying inclination stated at import (slope; None: the vehicle's when used)"))
    contact_shift_mm: tuple[float, float] | None = Field(default=None, description=(
        "(dy, dz) from this frame to the contact frame that curve-radius tables and "
        "simulations report rail positions in (top at z = 0, gauge point at the 60E1 gauge "
        "point y = -35.981, before the inclination)"))


class RailOut(BaseModel):
    """A stored rail. ``x_mm``/``y_mm`` (with ``include_points``) are the file's own numbers,
    every point; ``rail_y_mm``/``rail_z_mm`` the measured points in the rail frame (points a
    file note says were added left out)."""

    id: int
    name: str
    source_file: str
    part: int | None
    kind: RailKind
    origin: Literal["instrument", "drawing"]
    layout: str
    measured_on: dt.date | None
    instrument_serial: str | None
    n_points: int
    added_points: list[int]
    point_notes: list[dict[str, object]]
    header: dict[str, str]
    frame: RailFrameOut
    wear: RailHeadWear
    warnings: list[str]
    instrument_wear_mm: dict[str, float] = Field(default_factory=dict, description=(
        "W1/W2/W3 as the file's header gives them (the instrument's own, against its own "
        "reference), where it holds numbers"))
    raw_path: str | None = Field(default=None, description=(
        "the uploaded file, under the service's raw directory (content-addressed)"))
    created_at: dt.datetime | None = None
    x_mm: list[float] | None = None
    y_mm: list[float] | None = None
    rail_y_mm: list[float] | None = None
    rail_z_mm: list[float] | None = None


class RailSkippedOut(BaseModel):
    """A profile of an uploaded file that is not imported as a rail, and why."""

    part: int | None
    kind: NotRailKind
    reason: str


class RailImportOut(BaseModel):
    """``POST /v1/rails/import``: what the file held. ``created`` rails are new;
    ``duplicates`` were stored before (same file content and part; nothing new is written);
    ``skipped`` profiles are not rails; ``warnings`` per file, part and line."""

    file_name: str
    sha256: str
    created: list[RailOut]
    duplicates: list[RailOut]
    skipped: list[RailSkippedOut]
    warnings: list[str]
