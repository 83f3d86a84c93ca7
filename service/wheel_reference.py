"""A wheel's profile measurements re-taken against another reference profile.

``PUT /v1/wheels/{wheel_id}/reference`` and the import's own-baseline wheels
(reference ``own``: the wheel's first profile measurement) call :func:`apply_reference`: wear
curve, wear areas, reference fit, placement and the reference-dependent warnings of every
profile measurement of the wheel are recomputed from its stored points
(:mod:`wearcast.service.import_pool`, :mod:`wearcast.service.measurement_rows`); the points and
what the import found in the file (header, datum, cleaning) are kept.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.errors import NotFound, Unprocessable
from wearcast.service.float32_blobs import from_f32
from wearcast.service.import_pool import process_with_reference
from wearcast.service.measurement_rows import measurement_warnings, wear_columns
from wearcast.service.readers.records import ProfileRecord
from wearcast.service.reference_store import is_own_baseline, own_baseline_spec, resolve_reference


def apply_reference(session: Session, wheel_id: str, name: str, *, commit: bool = True
                    ) -> dict[str, Any]:
    """Re-take every profile measurement of a wheel against the reference ``name`` (a
    catalogue name, an uploaded reference, or ``own`` for the wheel's first measurement):
    wear curve, areas, reference fit and warnings are recomputed; the points are not
    touched. Returns a summary per measurement."""
    if session.get(db.Wheel, wheel_id) is None:
        raise NotFound("wheel_id", f"wheel {wheel_id!r} is not stored")
    if is_own_baseline(name):
        found = own_baseline_spec(session, wheel_id)
        if found is None:
            raise Unprocessable("reference_profile", f"wheel {wheel_id!r} has no profile "
                                "measurement to serve as its own baseline")
        spec, baseline_id = found
        stored_name = f"own:{baseline_id}"
    else:
        spec = resolve_reference(session, name)
        stored_name = spec.name
    rows = session.scalars(select(db.Measurement).where(
        db.Measurement.wheel_id == wheel_id, db.Measurement.kind == "profile")
        .order_by(db.Measurement.mileage_km)).all()
    out = []
    for m in rows:
        y, z = from_f32(m.y_mm), from_f32(m.z_mm)
        datum = bool((m.placement or {}).get("alignment") == "datum")
        p = process_with_reference(np.asarray(y), np.asarray(z), spec, datum)
        if isinstance(p, str):
            raise Unprocessable("reference_profile", f"measurement {m.id} cannot be taken "
                                f"against {stored_name}: {p}")
        p = p._replace(reference=stored_name)
        for key, value in wear_columns(p).items():
            setattr(m, key, value)
        m.lateral_shift_mm, m.vertical_shift_mm = p.lateral_shift_mm, p.vertical_shift_mm
        m.rotation_rad, m.rms_residual_mm = p.rotation_rad, p.rms_residual_mm
        m.placement = p.placement
        # what the import found in the file (header, datum, cleaning) stays; the reference
        # fit and the wear alignment are taken anew
        redone = ("reference_mismatch", "wear_alignment")
        kept = [w for w in (m.warnings or []) if w.get("code") not in redone]
        record = ProfileRecord(meta=_meta_stub(m), y_mm=np.asarray(y), z_mm=np.asarray(z))
        m.warnings = kept + [w for w in measurement_warnings(record, p)
                             if w["code"] in redone] or None
        out.append({"measurement_id": m.id, "mileage_km": m.mileage_km,
                    "reference_profile": stored_name, "reference_fits": m.reference_fits,
                    "flange_area_mm2": m.flange_area_mm2, "tread_area_mm2": m.tread_area_mm2,
                    "warnings": m.warnings or []})
    if commit:
        session.commit()
    return {"wheel_id": wheel_id, "reference_profile": stored_name, "measurements": out}


def _meta_stub(m: db.Measurement) -> Any:
    """The metadata a stored measurement's warnings are worded from (wheel, mileage, reference)."""
    from wearcast.service.readers.records import MeasurementMeta

    wheel = m.wheel_id
    return MeasurementMeta(wheel_id=wheel, vehicle_id="", bogie_type="motor", axle=1,
                           side="left", mileage_km=m.mileage_km,
                           reference_profile=m.reference_profile)
