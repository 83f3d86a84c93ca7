"""Pictures a planner reads for one measured wheel (matplotlib, Agg; SVG or PNG bytes).

* ``parameter_history_figure``: Sd, Sh and qR against mileage — the wheel's measured points,
  the predicted P10–P90 band and P50 line from its latest measurement on (the reprofiling
  model's corridor, :func:`wearcast.statistics.reprofiling.parameter_corridor`), the limits
  drawn, and the limit crossing marked (the predicted P50 crossing, or the measured point
  already past a limit);
* ``measured_profile_figure``: one measured profile over the reference it was taken against
  (after the reported vertical alignment; the stored points are not moved), the wear area
  shaded, material above the reference hatched, and the wear curve with its areas.

The builders are pure (arrays in, bytes out); the ``*_job`` functions load what they need
from storage and name the builder and its inputs, which the HTTP routes key, cache and answer
conditionally (:mod:`wearcast.service.picture_cache`); the ``*_picture`` functions return the
bytes.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import model_loading, reprofiling_store, wheel_start
from wearcast.service import models_db as db
from wearcast.service.errors import NotFound
from wearcast.service.picture_cache import PictureJob, render
from wearcast.service.pictures import ImageFormat, _render
from wearcast.service.reprofiling_schemas import ReprofilingIn
from wearcast.statistics.reprofiling import ParameterCorridor

#: (column, label, limit key, "min"/"max") of the three panels.
PANELS = (("sd_mm", "flange thickness Sd [mm]", "sd_min_mm", "min"),
          ("sh_mm", "flange height Sh [mm]", "sh_max_mm", "max"),
          ("qr_mm", "flange slope qR [mm]", "qr_min_mm", "min"))
_LIMIT_NAME = {"sd_min_mm": "sd", "sh_max_mm": "sh", "qr_min_mm": "qr"}


def parameter_history_figure(measured: pd.DataFrame, corridor: ParameterCorridor | None,
                             start_mileage_km: float, limits: dict[str, float],
                             crossing: dict[str, Any], *, title: str,
                             fmt: ImageFormat = "svg") -> bytes:
    """Sd/Sh/qR [mm] against mileage [km] for one wheel.

    ``measured``: columns ``mileage_km, sd_mm, sh_mm, qr_mm``; ``corridor``: the predicted
    band from ``start_mileage_km`` on (None: no prediction); ``limits``: ``sd_min_mm``,
    ``sh_max_mm``, ``qr_min_mm``; ``crossing``: ``governing_limit``, ``mileage_km`` (P10/
    P50/P90 absolute, None when not reached) and ``crossed_limits`` (measured past, mm).
    """
    figure = Figure(figsize=(8.0, 8.0))
    axes = figure.subplots(3, 1, sharex=True)
    crossed = crossing.get("crossed_limits") or {}
    governing = crossing.get("governing_limit")
    p50 = (crossing.get("mileage_km") or {}).get("p50")
    for i, (ax, (column, label, key, kind)) in enumerate(zip(axes, PANELS, strict=True)):
        limit = float(limits[key])
        ax.axhline(limit, color="tab:red", linewidth=1.2, linestyle="--",
                   label=f"limit {kind} {limit:g} mm")
        if corridor is not None:
            s = (start_mileage_km + corridor.mileage_km) / 1000.0
            band = corridor.parameters_mm[:, :, i]
            ax.fill_between(s, np.min(band, axis=0), np.max(band, axis=0), color="tab:blue",
                            alpha=0.2, label="predicted P10–P90")
            ax.plot(s, band[1], color="tab:blue", linewidth=1.2, label="predicted P50")
        if not measured.empty:
            values = measured[column].to_numpy(float)
            km = measured["mileage_km"].to_numpy(float) / 1000.0
            past = values < limit if kind == "min" else values > limit
            ax.plot(km[~past], values[~past], "o", color="black", markersize=4,
                    label="measured")
            if past.any():
                ax.plot(km[past], values[past], "X", color="tab:red", markersize=9,
                        label="measured past the limit")
        name = _LIMIT_NAME[key]
        if name in crossed:
            ax.annotate(f"crossed by {crossed[name]:.2f} mm",
                        xy=(start_mileage_km / 1000.0, limit), xytext=(8, 8),
                        textcoords="offset points", color="tab:red", fontsize=8)
        if governing == name and p50 is not None and not crossed:
            ax.axvline(p50 / 1000.0, color="tab:red", linewidth=0.8)
            ax.plot([p50 / 1000.0], [limit], marker="*", color="tab:red", markersize=12,
                    label=f"predicted crossing {p50:,.0f} km (P50)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("mileage [1000 km]")
    figure.suptitle(title, fontsize=10)
    return _render(figure, fmt)


def measured_profile_figure(y_mm: np.ndarray, z_mm: np.ndarray, reference_y_mm: np.ndarray,
                            reference_z_mm: np.ndarray, grid_y_mm: np.ndarray,
                            wear_mm: np.ndarray, *, reference: str, areas: tuple[float, float],
                            fits: bool, notes: list[str], title: str,
                            fmt: ImageFormat = "svg") -> bytes:
    """A measured profile (after its reported vertical alignment) over its reference, the
    wear area shaded (hatched red: material above the reference), and the wear curve."""
    figure = Figure(figsize=(8.0, 6.5))
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    top.plot(reference_y_mm, reference_z_mm, color="grey", linestyle="--",
             label=f"reference {reference}")
    top.plot(y_mm, z_mm, color="black", linewidth=0.9, label="measured (aligned vertically)")
    z_ref = np.interp(grid_y_mm, reference_y_mm, reference_z_mm, left=np.nan, right=np.nan)
    ok = np.isfinite(wear_mm) & np.isfinite(z_ref)
    worn = z_ref - wear_mm
    top.fill_between(grid_y_mm, worn, z_ref, where=ok & (wear_mm >= 0), color="tab:orange",
                     alpha=0.5, label="wear area")
    top.fill_between(grid_y_mm, worn, z_ref, where=ok & (wear_mm < 0), facecolor="none",
                     edgecolor="tab:red", hatch="////", label="material above the reference")
    top.invert_xaxis()  # flange on the right, as the seeds show the wheel
    top.set_ylabel("z [mm]")
    top.grid(alpha=0.3)
    top.legend(fontsize=8)
    flange, tread = areas
    verdict = "fits its reference" if fits else "does NOT fit its reference (flagged)"
    bottom.axhline(0.0, color="grey", linewidth=0.8)
    bottom.plot(grid_y_mm, wear_mm, color="tab:orange")
    bottom.axvline(-30.0, color="grey", linestyle=":", linewidth=0.8)
    bottom.set_title(f"flange {flange:.1f} mm², tread {tread:.1f} mm² — {verdict}",
                     fontsize=9)
    bottom.set_xlabel("y [mm] (negative towards the flange)")
    bottom.set_ylabel("wear w [mm]")
    bottom.grid(alpha=0.3)
    if notes:
        figure.subplots_adjust(bottom=0.17)
        figure.text(0.01, 0.005, "\n".join(notes)[:400], fontsize=6, va="bottom")
    figure.suptitle(title, fontsize=10)
    return _render(figure, fmt)


def _wheel_measured(session: Session, wheel_id: str) -> pd.DataFrame:
    rows = session.execute(
        select(db.Measurement.mileage_km, db.Measurement.sd_mm, db.Measurement.sh_mm,
               db.Measurement.qr_mm).where(db.Measurement.wheel_id == wheel_id)
        .order_by(db.Measurement.mileage_km)).all()
    frame = pd.DataFrame(rows, columns=["mileage_km", "sd_mm", "sh_mm", "qr_mm"])
    return frame.dropna()


def wheel_parameter_picture(session: Session, model_id: int, *, wheel_id: str,
                            route_id: int | str, horizon_km: float | None = None,
                            fmt: ImageFormat = "svg") -> bytes:
    """Sd/Sh/qR of a stored wheel against mileage with the model's prediction from its
    latest measured profile on (see :func:`parameter_history_figure`)."""
    return render(wheel_parameter_job(session, model_id, wheel_id=wheel_id,
                                      route_id=route_id, horizon_km=horizon_km, fmt=fmt))


def _physics_parameter_job(session: Session, model_id: int, *, wheel_id: str,
                           route_id: int | str | None, horizon_km: float | None,
                           fmt: ImageFormat) -> PictureJob:
    """:func:`wheel_parameter_job` of a physics model: its wheel position's series at the
    P10/P50/P90 wear scales from the wheel's latest measurement on."""
    from wearcast.service import physics_model_store
    from wearcast.statistics.physics_model import QUANTITIES, predict_position

    body = ReprofilingIn(route_id=route_id, wheel_id=wheel_id)
    answer = physics_model_store.reprofiling(session, model_id, body)
    model = physics_model_store.load(session, model_id)
    remaining = answer["remaining_km"]["p90"] or answer["remaining_km"]["p50"]
    top = horizon_km or (1.3 * remaining if remaining else 300_000.0)
    corridor = None
    start_km = float(answer["start_mileage_km"])
    if not answer["crossed_limits"]:
        grid = np.linspace(0.0, top, 61)
        pred = predict_position(model.series, list(model.scales), grid,
                                bogie_type=answer["bogie_type"], axle=answer["axle"],
                                side=answer["side"], start_km=start_km,
                                start=answer["start_parameters_mm"])
        params = np.stack([pred[q] for q in QUANTITIES], axis=-1)[::-1]  # high scale first
        corridor = ParameterCorridor(grid, params, pred["extrapolated"])
    measured = _wheel_measured(session, wheel_id)
    p50 = answer["mileage_km"]["p50"]
    title = (f"wheel {wheel_id}: physics model {model_id} on route {answer['route']}; "
             + ("reprofiling now" if answer["crossed_limits"] else
                f"reprofiling at {p50:,.0f} km (P50)" if p50 is not None
                else "no limit within the horizon"))
    return PictureJob(parameter_history_figure,
                      (measured, corridor, start_km, answer["limits"], answer),
                      {"title": title, "fmt": fmt})


def wheel_parameter_job(session: Session, model_id: int, *, wheel_id: str,
                        route_id: int | str | None, horizon_km: float | None = None,
                        fmt: ImageFormat = "svg") -> PictureJob:
    """Inputs of :func:`parameter_history_figure` read from storage for a stored wheel."""
    from wearcast.service.errors import Unprocessable
    from wearcast.service.physics_model_store import is_physics

    if session.get(db.Wheel, wheel_id) is None:
        raise NotFound("wheel_id", f"no wheel {wheel_id!r}")
    if is_physics(session, model_id):
        return _physics_parameter_job(session, model_id, wheel_id=wheel_id,
                                      route_id=route_id, horizon_km=horizon_km, fmt=fmt)
    if route_id is None:
        raise Unprocessable("route_id", "a hybrid model needs the route the wheel runs on")
    body = ReprofilingIn(route_id=route_id, wheel_id=wheel_id)
    inputs, route = model_loading.load_inputs(session, model_id, route_id, None)
    start = wheel_start.wheel_start(session, body)
    answer = reprofiling_store.reprofiling_payload(inputs, route, model_id, body, start)
    remaining = answer["remaining_km"]["p90"] or answer["remaining_km"]["p50"]
    top = horizon_km or (1.3 * remaining if remaining else 300_000.0)
    if not math.isfinite(top) or top <= 0:
        top = 300_000.0
    corridor = None
    if not answer["crossed_limits"]:
        corridor = reprofiling_store.parameter_corridor(inputs, route, body, start,
                                                        np.linspace(0.0, top, 61))
    measured = _wheel_measured(session, wheel_id)
    title = (f"wheel {wheel_id}: model {model_id} on route {route.name}; reprofiling "
             + ("now (" + ", ".join(f"{k} past by {v:.2f} mm" for k, v in
                                    answer["crossed_limits"].items()) + ")"
                if answer["crossed_limits"] else
                f"at {answer['mileage_km']['p50']:,.0f} km (P50)"
                if answer["mileage_km"]["p50"] is not None else "not within the horizon"))
    return PictureJob(parameter_history_figure,
                      (measured, corridor, start.mileage_km, answer["limits"], answer),
                      {"title": title, "fmt": fmt})


def measurement_profile_picture(session: Session, measurement_id: int,
                                fmt: ImageFormat = "svg") -> bytes:
    """One stored measurement over the reference its wear was taken against."""
    return render(measurement_profile_job(session, measurement_id, fmt))


def measurement_profile_job(session: Session, measurement_id: int,
                            fmt: ImageFormat = "svg") -> PictureJob:
    """Inputs of :func:`measured_profile_figure` for one stored measurement (processed
    again against its stored reference)."""
    from wearcast.service.measured_wheel_source import processed_measurement

    m, p, height = processed_measurement(session, measurement_id)
    ref_y = np.linspace(-70.0, 60.0, 651)
    ref_z = np.asarray(height(ref_y))
    check = p.reference_check
    fits = bool(check.fits) if check is not None else True
    notes = list(check.reasons) if check is not None else []
    title = (f"{m.wheel_id} at {m.mileage_km:,.0f} km ({m.source_file or 'api'}): Sd "
             f"{p.parameters.sd_mm:.2f}, Sh {p.parameters.sh_mm:.2f}, qR "
             f"{p.parameters.qr_mm:.2f} mm; shift {p.lateral_shift_mm:.2f} mm, vertical "
             f"{p.vertical_shift_mm:+.2f} mm, rotation {p.rotation_rad * 1e3:.2f} mrad")
    return PictureJob(measured_profile_figure,
                      (p.y_aligned_mm, p.z_aligned_mm, ref_y, ref_z, p.grid_y_mm, p.wear_mm),
                      {"reference": m.reference_profile,
                       "areas": (p.areas.flange_mm2, p.areas.tread_mm2), "fits": fits,
                       "notes": notes, "title": title, "fmt": fmt})
