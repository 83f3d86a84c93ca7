"""A stored wheel measurement as the physics' wheel profile (curve-radius tables, simulations).

The stored points are read, placed in the wheel frame as their wear was (by the instrument's
datum where the import found one, else by the free fit to the reference, which the answer
says) and handed to the physics as a ``MeasuredWheel``; the measurement itself is not changed.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sqlalchemy.orm import Session

from wearcast.physics.profiles.measured_wheel import MeasuredWheel
from wearcast.service import models_db as db
from wearcast.service.errors import NotFound, Unprocessable


def measured_wheel(session: Session, measurement_id: int, field: str = "measurement_id"
                   ) -> tuple[MeasuredWheel, dict[str, Any]]:
    """(the wheel, what it was taken from) for a stored profile measurement.

    404 naming ``field`` when there is no such measurement; 422 when it has no profile or the
    profile cannot serve as a wheel (too short a range, too few points).
    """
    from wearcast.service.reference_store import height_of, stored_reference_spec
    from wearcast.statistics.processing import process_profile

    m = session.get(db.Measurement, measurement_id)
    if m is None:
        raise NotFound(field, f"no measurement {measurement_id}")
    if m.kind != "profile" or m.y_mm is None or m.z_mm is None:
        raise Unprocessable(field, f"measurement {measurement_id} has no profile points "
                                   f"(kind {m.kind!r})")
    y = np.frombuffer(m.y_mm, "<f4").astype(float)
    z = np.frombuffer(m.z_mm, "<f4").astype(float)
    datum = (m.placement or {}).get("alignment") == "datum"
    height = height_of(stored_reference_spec(session, m.reference_profile))
    try:
        p = process_profile(y, z, reference_height=height,
                            alignment="datum" if datum else "free")
        wheel = MeasuredWheel(f"{m.wheel_id} at {m.mileage_km:,.0f} km (measurement "
                              f"{measurement_id})", p.y_aligned_mm, p.z_aligned_mm)
    except ValueError as exc:
        raise Unprocessable(field, f"measurement {measurement_id}: {exc}") from None
    info = {"measurement_id": measurement_id, "wheel_id": m.wheel_id,
            "mileage_km": m.mileage_km, "source_file": m.source_file,
            "reference_profile": m.reference_profile,
            "placement": ("instrument datum (vertical shift only)" if datum else
                          "free fit to the reference (no datum found at import)"),
            "y_range_mm": [float(wheel.y_mm[0]), float(wheel.y_mm[-1])],
            "on": "every wheel of every wheelset"}
    return wheel, info
