"""The ``measurements`` row of an imported record: its columns and the warnings it keeps.

A parameter record keeps its Sd/Sh/qR. A profile keeps the file's points (little-endian float32
blobs, :mod:`wearcast.service.float32_blobs`), its processed wear curve, wear areas, placement
and recomputed Sd/Sh/qR (:mod:`wearcast.service.import_pool`); a shape that does not fit its
declared reference (:mod:`wearcast.statistics.reference_check`) keeps no wear curve or areas,
so it stays out of wear statistics until a reference that fits is given.

The warnings say what the import had to find, guess or drop: header Sd/Sh/qR farther than
:data:`HEADER_TOLERANCE_MM` from the points' values, a reference mismatch, the datum found or
guessed (MiniProf profiles placed by the instrument's own datum), the wear alignment, and the
points dropped by cleaning.
"""

from __future__ import annotations

import math
from typing import Any

from wearcast.service.float32_blobs import f32
from wearcast.service.import_pool import submit_profiles
from wearcast.service.import_registry import ImportRegistry
from wearcast.service.import_worker import Processed, finite_or_none
from wearcast.service.readers.bundle import Record
from wearcast.service.readers.records import ParameterRecord, ProfileRecord

#: Header Sd/Sh/qR farther than this [mm] from the recomputed ones are reported.
HEADER_TOLERANCE_MM = 0.3


def measurement_row(record: Record, batch_id: int | None, registry: ImportRegistry,
                    processed: Processed | None = None) -> dict[str, Any]:
    """The ``measurements`` row of one record.

    ``processed`` is the profile's (processed profile, measured Sd/Sh/qR) when already
    computed (see :func:`~wearcast.service.import_pool.submit_profiles`); otherwise it is
    computed here.
    """
    meta = record.meta
    row: dict[str, Any] = {
        "batch_id": batch_id, "wheel_id": meta.wheel_id, "mileage_km": float(meta.mileage_km),
        "measured_on": meta.measured_on, "route_id": registry.route_name(meta.route_id),
        "running_mode": meta.running_mode, "instrument_id": meta.instrument_id,
        "load_t": meta.load_t, "reference_profile": meta.reference_profile,
        "diameter_mm": meta.diameter_mm,
        "covariates": dict(meta.covariates), "source_file": meta.source_file or None,
        "source_line": meta.source_line,
    }
    empty = dict.fromkeys(
        ("y_mm", "z_mm", "wear_mm", "wear_grid_start_mm", "wear_grid_step_mm",
         "flange_area_mm2", "tread_area_mm2", "lateral_shift_mm", "vertical_shift_mm",
         "rotation_rad", "rms_residual_mm", "instrument_parameters", "reported_sd_mm",
         "reported_sh_mm", "reported_qr_mm"))
    row.update(empty)
    if isinstance(record, ParameterRecord):
        row.update(kind="parameters", n_points=0, sd_mm=float(record.sd_mm),
                   sh_mm=float(record.sh_mm), qr_mm=float(record.qr_mm),
                   reported_sd_mm=float(record.sd_mm), reported_sh_mm=float(record.sh_mm),
                   reported_qr_mm=float(record.qr_mm))
        return row
    p = processed if processed is not None else submit_profiles([record], registry)()[0]
    reported = record.instrument_parameters or {}
    row.update(
        kind="profile", n_points=int(len(record.y_mm)), y_mm=f32(record.y_mm),
        z_mm=f32(record.z_mm), **wear_columns(p),
        sd_mm=finite_or_none(p.sd_mm), sh_mm=finite_or_none(p.sh_mm),
        qr_mm=finite_or_none(p.qr_mm),
        lateral_shift_mm=p.lateral_shift_mm, vertical_shift_mm=p.vertical_shift_mm,
        rotation_rad=p.rotation_rad, rms_residual_mm=p.rms_residual_mm,
        instrument_parameters=dict(reported) or None,
        reported_sd_mm=finite_or_none(reported.get("sd_mm")),
        reported_sh_mm=finite_or_none(reported.get("sh_mm")),
        reported_qr_mm=finite_or_none(reported.get("qr_mm")),
        placement=p.placement,
        warnings=measurement_warnings(record, p) or None,
    )
    return row


def wear_columns(p: Processed) -> dict[str, Any]:
    """Wear curve, areas and reference fit of a processed profile; a shape that does not
    fit its reference keeps no wear curve or areas (excluded from wear statistics)."""
    fits = bool(p.reference_fits)
    return {
        "wear_mm": f32(p.wear_mm) if fits else None,
        "wear_grid_start_mm": p.grid_start_mm, "wear_grid_step_mm": p.grid_step_mm,
        "flange_area_mm2": finite_or_none(p.flange_area_mm2) if fits else None,
        "tread_area_mm2": finite_or_none(p.tread_area_mm2) if fits else None,
        "reference_profile": p.reference, "reference_fits": fits,
    }


def _warning(code: str, level: str, message: str) -> dict[str, Any]:
    """One stored warning: a code, its level (``warning`` or ``info``) and the message."""
    return {"code": code, "level": level, "message": message}


def _datum_header_notes(header: dict[str, str] | None) -> list[str]:
    """What the file's own datum entries say (MiniProf ``Xoffset``/``Yoffset``, reference
    points): the exported points already carry the offsets the instrument software applied,
    so they are reported, not applied again."""
    if not header:
        return ["the file carries no datum offsets or reference points"]
    out = []
    offsets = {k: header[k] for k in ("Xoffset", "Yoffset") if k in header}
    if offsets:
        try:
            nonzero = {k: float(v) for k, v in offsets.items() if float(v) != 0.0}
        except ValueError:
            nonzero = {}
            out.append(f"unreadable datum offsets {offsets}")
        if nonzero:
            out.append("the file's datum offsets " + ", ".join(f"{k} = {v:g} mm" for k, v in
                                                                nonzero.items())
                       + " are taken as already applied to the exported points (check)")
        else:
            out.append("the file's datum offsets Xoffset/Yoffset are 0")
    refs = sorted(k for k in header if k.startswith("RefPoint"))
    if refs:
        out.append(f"{len(refs)} instrument reference points in the header "
                   f"({refs[0]} = {header[refs[0]]})")
    return out


def measurement_warnings(record: ProfileRecord, p: Processed) -> list[dict[str, Any]]:
    """What the import had to find, guess or drop for one profile (see the module docstring)."""
    out: list[dict[str, Any]] = []
    header = record.header_parameters
    if header is not None:
        recomputed = {"sd_mm": p.sd_mm, "sh_mm": p.sh_mm, "qr_mm": p.qr_mm}
        diffs = {k: float(header[k]) - v for k, v in recomputed.items() if math.isfinite(v)}
        if any(abs(d) > HEADER_TOLERANCE_MM for d in diffs.values()):
            what = ("the old-style template's placeholders" if header.get("placeholder")
                    else "the instrument's values")
            out.append(_warning("header_parameters", "warning", (
                f"header Sd/Sh/qR {float(header['sd_mm']):.2f}/{float(header['sh_mm']):.2f}/"
                f"{float(header['qr_mm']):.2f} mm ({what}) disagree with the points' "
                f"{p.sd_mm:.2f}/{p.sh_mm:.2f}/{p.qr_mm:.2f} mm by "
                + "/".join(f"{diffs.get(k, float('nan')):+.2f}" for k in recomputed)
                + f" mm (tolerance {HEADER_TOLERANCE_MM:g} mm); the points' values are stored")))
    if not p.reference_fits:
        out.append(_warning("reference_mismatch", "warning", (
            f"shape does not fit the declared reference {p.reference}: "
            + "; ".join(p.reference_reasons) + ". Stored and flagged; wear areas and wear "
            "curve are kept out of statistics until a reference is given "
            "(PUT /v1/wheels/{wheel_id}/reference)")))
    placement = p.placement or {}
    if placement.get("alignment") == "datum":
        found = placement.get("back_face_found")
        notes = list(placement.get("notes") or [])
        notes += _datum_header_notes(record.datum_header)
        out.append(_warning("datum_found" if found else "datum_guessed",
                            "info" if found else "warning", "; ".join(notes)))
        out.append(_warning("wear_alignment", "info", (
            f"wear taken against {p.reference} after a vertical shift of "
            f"{p.vertical_shift_mm:+.2f} mm on the unworn flange back (lateral shift "
            f"{p.lateral_shift_mm:.2f} mm, rotation {p.rotation_rad * 1e3:.2f} mrad, RMS "
            f"{p.rms_residual_mm:.2f} mm); the stored points are not moved")))
    if p.n_removed:
        out.append(_warning("points_dropped", "info", (
            f"cleaning dropped {p.n_removed} of {p.n_raw} points: "
            + "; ".join(p.cleaning_notes))))
    return out
