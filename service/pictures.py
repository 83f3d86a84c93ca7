"""Pictures of a model's predictions (matplotlib, Agg; SVG or PNG bytes).

* ``wear_area_figure``: wear area over mileage per region, the P10–P90 prediction corridor
  and the P50 line, with the measured points (seed 001 Fig. 11);
* ``profile_figure``: the predicted worn profile at a mileage against the reference (new)
  profile and measured profiles near that mileage, plus the wear curves (seed 001
  Figs. 12–14).

The figure builders are pure (arrays in, bytes out); ``wear_area_job``/``profile_job`` load
what they need from storage and name the builder and its inputs
(:class:`~wearcast.service.picture_cache.PictureJob`), which the HTTP routes key, cache and
answer conditionally (:mod:`wearcast.service.picture_cache`); ``wear_area_picture``/
``profile_picture`` return the bytes (CLI, demo).
Matplotlib's object API is used (no pyplot state), so pictures can be drawn from threads.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS
from wearcast.service import measurement_store, model_loading, prediction_store, route_store
from wearcast.service import models_db as db
from wearcast.service.picture_cache import PictureJob, render
from wearcast.statistics.hybrid_prediction import Prediction

ImageFormat = Literal["svg", "png"]
MEDIA_TYPES = {"svg": "image/svg+xml", "png": "image/png"}
REGION_COLOURS = {"flange": "tab:red", "tread": "tab:blue"}


def _render(figure: Figure, fmt: ImageFormat) -> bytes:
    FigureCanvasAgg(figure)
    buffer = io.BytesIO()
    figure.savefig(buffer, format=fmt, dpi=110, bbox_inches="tight")
    return buffer.getvalue()


def wear_area_figure(prediction: Prediction, measured: pd.DataFrame, *, title: str,
                     fmt: ImageFormat = "svg") -> bytes:
    """Wear area [mm²] against mileage [km]: corridor, median and measured points.

    ``measured`` has columns ``mileage_km, flange_area_mm2, tread_area_mm2`` (may be empty).
    """
    figure = Figure(figsize=(8.0, 4.2))
    axes = figure.subplots(1, 2, sharex=True)
    q = prediction.quantiles
    lo, mid, hi = q.index(min(q)), q.index(0.5), q.index(max(q))
    s_1000 = prediction.mileage_km / 1000.0
    for ax, region in zip(axes, REGIONS, strict=True):
        areas = getattr(prediction, f"{region}_area_mm2")
        colour = REGION_COLOURS[region]
        ax.fill_between(s_1000, areas[lo], areas[hi], color=colour, alpha=0.2,
                        label=f"prediction P{q[lo] * 100:.0f}–P{q[hi] * 100:.0f}")
        ax.plot(s_1000, areas[mid], color=colour, label="prediction P50")
        if not measured.empty:
            ax.plot(measured["mileage_km"] / 1000.0, measured[f"{region}_area_mm2"], "o",
                    color="black", markersize=3.5, label="measured")
        ax.set_title(f"{region} wear area")
        ax.set_xlabel("mileage [1000 km]")
        ax.set_ylabel("wear area [mm²]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    figure.suptitle(title, fontsize=10)
    return _render(figure, fmt)


def profile_figure(prediction: Prediction, measured_wear_mm: list[np.ndarray],
                   measured_labels: list[str], *, title: str, fmt: ImageFormat = "svg") -> bytes:
    """Reference, predicted worn and measured profiles z(y) [mm], and their wear curves.

    ``prediction`` holds one mileage; ``measured_wear_mm`` are wear curves on the
    prediction's grid (aligned measurements), drawn as reference − wear.
    """
    y = prediction.grid_y_mm
    z_ref = s1002_height_mm(y)
    figure = Figure(figsize=(8.0, 6.0))
    top, bottom = figure.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    top.plot(y, z_ref, color="grey", linestyle="--", label="reference (S1002)")
    bottom.axhline(0.0, color="grey", linestyle="--", linewidth=0.8)
    for wear, label in zip(measured_wear_mm, measured_labels, strict=True):
        top.plot(y, z_ref - wear, color="black", linewidth=0.7, alpha=0.6, label=label)
        bottom.plot(y, wear, color="black", linewidth=0.7, alpha=0.6)
    top.plot(y, prediction.z_mm[0], color="tab:red", linewidth=1.6,
             label=f"predicted at {prediction.mileage_km[0]:,.0f} km")
    bottom.plot(y, prediction.wear_mm[0], color="tab:red", linewidth=1.6)
    top.invert_xaxis()  # flange on the right, as the seed's figures show the wheel
    top.set_ylabel("z [mm]")
    top.legend(fontsize=8)
    top.grid(alpha=0.3)
    bottom.set_xlabel("y [mm] (negative towards the flange)")
    bottom.set_ylabel("wear w [mm]")
    bottom.grid(alpha=0.3)
    figure.suptitle(title, fontsize=10)
    return _render(figure, fmt)


def _position_measurements(session: Session, model_id: int, bogie_type: str, axle: int,
                           side: str, wheel_id: str | None,
                           route_keys: tuple[str, ...] = ()) -> pd.DataFrame:
    """Measured profiles to show beside a prediction.

    That wheel's measurements when ``wheel_id`` is given; otherwise every profile measured at
    that wheel position (bogie type, axle, side) on the predicted route (``route_keys``: the
    route's name and id as stored in the measurements), whether or not the model was calibrated
    on it, and when none was taken on that route, the model's calibration measurements at that
    position.
    """
    m, w = db.Measurement, db.Wheel
    base = (select(m.id).join(w, w.wheel_id == m.wheel_id).where(m.kind == "profile"))
    if wheel_id is not None:
        queries = [base.where(m.wheel_id == wheel_id)]
    else:
        position = base.where(w.bogie_type == bogie_type, w.axle == axle, w.side == side)
        link = db.ModelCalibrationMeasurement
        queries = [position.where(m.route_id.in_(route_keys)),
                   position.join(link, link.measurement_id == m.id).where(
                       link.model_id == model_id)]
    for query in queries:
        ids = list(session.scalars(query.order_by(m.mileage_km)))
        if ids:
            break
    frame, _ = measurement_store.calibration_frame(session, ids)
    return frame


def wear_area_picture(session: Session, model_id: int, *, route_id: int | str,
                      bogie_type: str, axle: int, side: str, wheel_id: str | None = None,
                      max_mileage_km: float | None = None, fmt: ImageFormat = "svg") -> bytes:
    """The wear-area picture's bytes (see :func:`wear_area_job`)."""
    return render(wear_area_job(session, model_id, route_id=route_id, bogie_type=bogie_type,
                                axle=axle, side=side, wheel_id=wheel_id,
                                max_mileage_km=max_mileage_km, fmt=fmt))


def wear_area_job(session: Session, model_id: int, *, route_id: int | str,
                  bogie_type: str, axle: int, side: str, wheel_id: str | None = None,
                  max_mileage_km: float | None = None, fmt: ImageFormat = "svg"
                  ) -> PictureJob:
    """Inputs of :func:`wear_area_figure` read from storage: the model's prediction at the
    wheel position on the route and the measured areas shown beside it."""
    loaded = model_loading.load_model(session, model_id)
    route, row = route_store.resolve(session, route_id, None)
    keys = (row.name, str(row.id)) if row else ()
    measured = _position_measurements(session, model_id, bogie_type, axle, side, wheel_id, keys)
    top = max_mileage_km or max(200_000.0, 1.15 * float(measured["mileage_km"].max())
                                if not measured.empty else 0.0)
    prediction = prediction_store.run_prediction(loaded, route, bogie_type=bogie_type, axle=axle,
                                                 side=side,
                                                 mileage_km=np.linspace(0.0, top, 41).tolist())
    who = wheel_id or f"{bogie_type} bogie, axle {axle}, {side}"
    title = f"model {loaded.row.name!r} on route {row.name if row else 'inline'}: {who}"
    return PictureJob(wear_area_figure, (prediction, measured), {"title": title, "fmt": fmt})


def profile_picture(session: Session, model_id: int, *, route_id: int | str,
                    bogie_type: str, axle: int, side: str, mileage_km: float,
                    wheel_id: str | None = None, window: float = 0.2,
                    fmt: ImageFormat = "svg") -> bytes:
    """The profile picture's bytes (see :func:`profile_job`)."""
    return render(profile_job(session, model_id, route_id=route_id, bogie_type=bogie_type,
                              axle=axle, side=side, mileage_km=mileage_km, wheel_id=wheel_id,
                              window=window, fmt=fmt))


def profile_job(session: Session, model_id: int, *, route_id: int | str,
                bogie_type: str, axle: int, side: str, mileage_km: float,
                wheel_id: str | None = None, window: float = 0.2,
                fmt: ImageFormat = "svg") -> PictureJob:
    """Inputs of :func:`profile_figure` read from storage: the predicted profile at
    ``mileage_km`` and the measured wear curves within ``window`` (a share of the mileage)
    of it."""
    loaded = model_loading.load_model(session, model_id)
    route, row = route_store.resolve(session, route_id, None)
    prediction = prediction_store.run_prediction(loaded, route, bogie_type=bogie_type, axle=axle,
                                                 side=side, mileage_km=[mileage_km])
    keys = (row.name, str(row.id)) if row else ()
    measured = _position_measurements(session, model_id, bogie_type, axle, side, wheel_id, keys)
    curves, labels = [], []
    if not measured.empty:
        near = measured[(measured["mileage_km"] - mileage_km).abs()
                        <= window * max(mileage_km, 1.0)].head(8)
        near, wear = measurement_store.calibration_frame(
            session, near["measurement_id"].astype(int).tolist())
        grid = prediction.grid_y_mm
        for (_, r), curve in zip(near.iterrows(), wear, strict=True):
            if curve is not None and curve.size == grid.size:
                curves.append(curve)
                labels.append(f"measured {r['wheel_id']} at {r['mileage_km']:,.0f} km")
    who = wheel_id or f"{bogie_type} bogie, axle {axle}, {side}"
    title = (f"model {loaded.row.name!r} on route {row.name if row else 'inline'}: {who}, "
             f"{mileage_km:,.0f} km")
    return PictureJob(profile_figure, (prediction, curves, labels),
                      {"title": title, "fmt": fmt})


def write_demo_pictures(out_dir: Path | str, *, model_id: int, predictions: list[Any],
                        session_factory: Callable[[], Session], fmt: ImageFormat = "svg",
                        max_pictures: int = 6) -> list[Path]:
    """Write wear-area and profile pictures for the wheel positions of ``predictions``.

    ``predictions`` are :class:`~wearcast.service.prediction_schemas.PredictionOut` (route,
    position and at least one mileage); one pair of pictures per distinct position, at most
    ``max_pictures`` positions. Returns the paths written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    seen: set[tuple[str, str, int, str]] = set()
    with session_factory() as session:
        for prediction in predictions:
            key = (prediction.route, prediction.bogie_type, prediction.axle, prediction.side)
            if key in seen or prediction.route == "inline" or len(seen) >= max_pictures:
                continue
            seen.add(key)
            stem = "{}_{}_axle{}_{}".format(*key)
            position = {"route_id": key[0], "bogie_type": key[1], "axle": key[2],
                        "side": key[3], "fmt": fmt}
            area = out / f"wear-area_{stem}.{fmt}"
            area.write_bytes(wear_area_picture(session, model_id, **position))
            profile = out / f"profile_{stem}.{fmt}"
            profile.write_bytes(profile_picture(
                session, model_id, mileage_km=float(prediction.points[-1].mileage_km),
                **position))
            written += [area, profile]
    return written
