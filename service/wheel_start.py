"""Where a wheel's prediction or remaining mileage starts: its position, and its measured state
(Sd/Sh/qR and wear areas) from a stored measurement, its latest profile or an uploaded
profile.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.errors import NotFound, Unprocessable
from wearcast.service.prediction_schemas import PredictIn
from wearcast.service.reprofiling_schemas import ReprofilingIn


def _latest_profile(session: Session, wheel_id: str) -> tuple[db.Wheel, db.Measurement]:
    """The wheel and its latest profile measurement (with or without wear areas: a shape
    flagged against its reference still has its measured Sd/Sh/qR)."""
    wheel = session.get(db.Wheel, wheel_id)
    if wheel is None:
        raise NotFound("wheel_id", f"no wheel {wheel_id!r}")
    latest = session.scalar(
        select(db.Measurement).where(db.Measurement.wheel_id == wheel_id,
                                     db.Measurement.kind == "profile")
        .order_by(db.Measurement.mileage_km.desc(), db.Measurement.id.desc()).limit(1))
    if latest is None:
        raise Unprocessable("wheel_id", f"wheel {wheel_id!r} has no measured profile to start "
                            "from")
    return wheel, latest


@dataclass(frozen=True)
class WheelStart:
    """Where a wheel's remaining mileage starts: its position and latest measured state."""

    bogie_type: str
    axle: int
    side: str
    mileage_km: float = 0.0
    measurement_id: int | None = None
    areas_mm2: dict[str, float] | None = None
    covariates: dict[str, Any] | None = None
    #: measured Sd/Sh/qR [mm] the prediction starts from
    parameters: dict[str, float] | None = None
    notes: tuple[str, ...] = ()


def _measured_state(sd: float | None, sh: float | None, qr: float | None,
                    flange: float | None, tread: float | None, reference: str,
                    fits: bool | None) -> tuple[dict[str, float] | None, dict[str, float],
                                                tuple[str, ...]]:
    """Start parameters, start areas and notes of a measured state."""
    notes: list[str] = []
    parameters = None
    if None not in (sd, sh, qr) and all(math.isfinite(float(v)) for v in (sd, sh, qr)):  # type: ignore[arg-type]
        parameters = {"sd_mm": float(sd), "sh_mm": float(sh), "qr_mm": float(qr)}  # type: ignore[arg-type]
    else:
        notes.append("the measurement has no complete Sd/Sh/qR: the model's own are used")
    if flange is None or tread is None:
        areas = {"flange": 0.0, "tread": 0.0}
        why = ("its shape does not fit its reference " + reference if fits is False
               else "it has no wear areas")
        notes.append(f"wear areas start at 0 ({why}); Sd/Sh/qR start from the measured values")
    else:
        areas = {"flange": max(0.0, float(flange)), "tread": max(0.0, float(tread))}
    return parameters, areas, tuple(notes)


def _profile_start(body: ReprofilingIn | PredictIn) -> WheelStart:
    """Start state of an uploaded profile: placed by its datum, wear against its reference."""
    from wearcast.service.importing import _process_arrays
    from wearcast.service.reference_store import ReferenceSpec

    profile = body.profile
    assert profile is not None
    if len(profile.y_mm) != len(profile.z_mm):
        raise Unprocessable("profile.z_mm", f"has {len(profile.z_mm)} values, y_mm "
                            f"{len(profile.y_mm)}")
    from wearcast.physics.profiles.references import canonical_s1002_name

    name = canonical_s1002_name(profile.reference_profile)
    if name is None:
        raise Unprocessable("profile.reference_profile", "only the built-in S1002 family is "
                            "accepted here; store the profile to use an uploaded reference")
    p = _process_arrays(np.asarray(profile.y_mm, float), np.asarray(profile.z_mm, float),
                        ReferenceSpec(name, "builtin"), True)
    if isinstance(p, str):
        raise Unprocessable("profile.y_mm", f"not a usable wheel profile: {p}")
    fits = bool(p.reference_fits)
    parameters, areas, notes = _measured_state(
        p.sd_mm, p.sh_mm, p.qr_mm, p.flange_area_mm2 if fits else None,
        p.tread_area_mm2 if fits else None, name, fits)
    return WheelStart(str(body.bogie_type), int(body.axle or 1), str(body.side),
                      float(profile.mileage_km), None, areas, None, parameters, notes)


def wheel_start(session: Session | None, body: ReprofilingIn | PredictIn) -> WheelStart:
    """The wheel's position from the request, or with ``wheel_id`` / ``measurement_id``
    from storage (its latest / that measured profile as the start state: measured Sd/Sh/qR
    and wear areas), or an uploaded ``profile``; needs a session only for stored starts."""
    if body.profile is not None:
        return _profile_start(body)
    if body.wheel_id is None and body.measurement_id is None:
        return WheelStart(str(body.bogie_type), int(body.axle or 1), str(body.side))
    assert session is not None
    if body.measurement_id is not None:
        latest = session.get(db.Measurement, body.measurement_id)
        if latest is None:
            raise NotFound("measurement_id", f"no measurement {body.measurement_id}")
        wheel = session.get(db.Wheel, latest.wheel_id)
        assert wheel is not None
    else:
        assert body.wheel_id is not None
        wheel, latest = _latest_profile(session, body.wheel_id)
    for name, given, stored in (("bogie_type", body.bogie_type, wheel.bogie_type),
                                ("axle", body.axle, wheel.axle),
                                ("side", body.side, wheel.side)):
        if given is not None and given != stored:
            raise Unprocessable(name, f"wheel {wheel.wheel_id!r} has {name} {stored!r}")
    covariates = {key: value for key in ("load_t", "running_mode", "instrument_id")
                  if (value := getattr(latest, key, None)) is not None}
    parameters, areas, notes = _measured_state(
        latest.sd_mm, latest.sh_mm, latest.qr_mm, latest.flange_area_mm2,
        latest.tread_area_mm2, latest.reference_profile, latest.reference_fits)
    return WheelStart(
        wheel.bogie_type, int(wheel.axle), wheel.side, float(latest.mileage_km), latest.id,
        areas, covariates, parameters, notes)
