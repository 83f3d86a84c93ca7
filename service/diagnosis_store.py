"""The discrepancy finder on stored data: gather a model's inputs, diagnose, save the extension.

The finder is :func:`wearcast.statistics.discrepancy.diagnose` (residuals, the cause
catalogue scored out of sample with grouped folds, tested against resampled nuisance-only
datasets, margin over the runner-up); this module
only collects what it reads from storage:

* the measurements the request's ``filter`` selects (profiles with wear areas, default all),
  plus the model's calibration measurements (flagged via ``calibration_wheel_ids``; the finder
  refits every extension's scale, so they inform it without favouring it);
* their wear curves (on the model's grid) and covariates (standard fields and any extra
  column of the import, e.g. ``depot``);
* the routes they ran on (a measurement's ``route_id`` is a stored route's id or name; the
  calibration measurements without one ran on the calibration route) with their attributes;
* the model's curve-radius table.

Measurements that cannot be used (no wear areas, a route that is not stored) are left out
and counted in the answer's ``excluded``.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy import insert, select
from sqlalchemy.orm import Session

from wearcast.service import measurement_store, model_loading, model_store, route_store
from wearcast.service import models_db as db
from wearcast.service.diagnosis_schemas import DiagnoseIn, DiagnosisOut
from wearcast.service.errors import NotFound, Unprocessable, from_value_error
from wearcast.statistics import discrepancy, discrepancy_report, extension, hybrid
from wearcast.statistics.causes import CATALOGUE
from wearcast.statistics.json_values import json_value

#: Columns of ``calibration_frame`` that are not covariates the finder should see twice.
_STANDARD = {"measurement_id", "wheel_id", "vehicle_id", "bogie_type", "axle", "side",
             "mileage_km", "measured_on", "route_id", "running_mode", "instrument_id",
             "load_t", "kind", "flange_area_mm2", "tread_area_mm2", "sd_mm", "sh_mm", "qr_mm"}


@dataclass(frozen=True)
class DiagnosisRun:
    """A diagnosis and what it was computed from (for saving the extended model)."""

    diagnosis: discrepancy.Diagnosis
    model: hybrid.HybridModel
    row: db.Model
    measurement_ids: list[int]
    excluded: dict[str, int]
    expected_progression: dict[str, Any] | None = None


def _covariates(session: Session, ids: list[int]) -> pd.DataFrame:
    """The extra (non-standard) covariate columns of the measurements, by id."""
    records: list[dict[str, Any]] = []
    for start in range(0, len(ids), 900):
        chunk = ids[start:start + 900]
        for mid, cov in session.execute(select(db.Measurement.id, db.Measurement.covariates)
                                        .where(db.Measurement.id.in_(chunk))):
            records.append({"measurement_id": mid, **{k: v for k, v in (cov or {}).items()
                                                      if k not in _STANDARD}})
    return pd.DataFrame(records) if records else pd.DataFrame(columns=["measurement_id"])


def _route_names(session: Session, raw: pd.Series, calibration_route: str,
                 in_calibration: np.ndarray) -> tuple[np.ndarray, dict[str, db.Route]]:
    """Route name per measurement (None when not stored) and the stored routes by name."""
    rows: dict[str, db.Route] = {}
    by_raw: dict[str, str | None] = {}
    names = []
    for value, calibrating in zip(raw.tolist(), in_calibration.tolist(), strict=True):
        if value is None or (isinstance(value, float) and np.isnan(value)):
            names.append(calibration_route if calibrating else None)
            continue
        key = str(value)
        if key not in by_raw:
            found = route_store.find_route(session, key)
            by_raw[key] = None if found is None else found.name
            if found is not None:
                rows[found.name] = found
        names.append(by_raw[key])
    cal_row = route_store.find_route(session, calibration_route)
    if cal_row is not None:
        rows[cal_row.name] = cal_row
    return np.array(names, dtype=object), rows


def run_diagnosis(session: Session, model_id: int, body: DiagnoseIn) -> DiagnosisRun:
    """Gather the model's inputs from storage and run the discrepancy finder."""
    row = model_loading.get_model_row(session, model_id)
    inputs = model_loading.model_inputs(session, model_id)
    if not isinstance(inputs.model, hybrid.HybridModel):
        base = row.spec.get("derived_from")
        raise Unprocessable("model_id", f"model {model_id} is already an extended model; "
                            f"diagnose the calibrated model it came from ({base})")
    model = inputs.model
    if body.causes is not None:
        known = [c.code for c in CATALOGUE]
        for i, code in enumerate(body.causes):
            if code not in known:
                raise Unprocessable(f"causes[{i}]", f"unknown cause {code!r}; known: "
                                    f"{', '.join(known)}")
    calibration_route = session.get(db.Route, row.route_id)
    if calibration_route is None:  # pragma: no cover - a foreign key keeps it
        raise Unprocessable("model_id", "the model's calibration route is gone")
    link = db.ModelCalibrationMeasurement
    cal_ids = set(session.scalars(select(link.measurement_id).where(link.model_id == model_id)))
    filter_ = dict(body.filter)
    filter_.setdefault("kind", "profile")
    matched = set(measurement_store.matching_ids(session, filter_, "filter"))
    if body.filter and not matched:  # not silently the calibration set alone
        raise Unprocessable("filter", "no profile measurements match the filter")
    ids = sorted(matched | cal_ids)
    frame, curves = measurement_store.calibration_frame(session, ids)
    if frame.empty:
        raise Unprocessable("filter", "no profile measurements match the filter")
    excluded: Counter[str] = Counter()
    in_cal = frame["measurement_id"].isin(cal_ids).to_numpy()
    names, route_rows = _route_names(session, frame["route_id"], calibration_route.name, in_cal)
    has_areas = (frame["flange_area_mm2"].notna() & frame["tread_area_mm2"].notna()).to_numpy()
    has_route = np.array([n is not None for n in names])
    excluded["no wear areas (parameter-only or unreadable profile)"] += int((~has_areas).sum())
    excluded["route_id is not a stored route"] += int((has_areas & ~has_route).sum())
    keep = has_areas & has_route
    frame = frame[keep].reset_index(drop=True)
    frame["route"] = names[keep]
    kept_curves = [c for c, k in zip(curves, keep, strict=True) if k]
    extra = _covariates(session, frame["measurement_id"].astype(int).tolist())
    if len(extra.columns) > 1:
        frame = frame.merge(extra, on="measurement_id", how="left")
    grid = model.grid_y_mm.size
    wear_curves = None
    if kept_curves and all(c is not None and c.size == grid for c in kept_curves):
        wear_curves = np.nan_to_num(np.vstack(kept_curves), nan=0.0)
    routes = {name: route_store.to_domain(r) for name, r in route_rows.items()}
    attributes = {name: dict(r.attributes or {}) for name, r in route_rows.items()}
    cal_wheels = set(frame.loc[frame["measurement_id"].isin(cal_ids), "wheel_id"])
    if frame["wheel_id"].nunique() < 2:
        raise Unprocessable("filter", "the finder needs measurements of at least two wheels "
                            "(it scores every cause on wheels it was not fitted on)")
    expected = None
    if body.expected_progression_simulations is not None:
        expected = progression_of_simulations(session, body.expected_progression_simulations)
    if body.expected_progression is not None:
        from wearcast.statistics.discrepancy_progression import ExpectedProgression

        given = body.expected_progression
        try:
            expected = ExpectedProgression.from_areas(
                given.mileage_km, {(a.bogie_type, a.wheelset, a.region): a.areas_mm2
                                   for a in given.areas}, source="request")
        except ValueError as exc:
            raise from_value_error(exc) from exc
    try:
        diagnosis = discrepancy.diagnose(
            model, frame, wear_curves, routes, inputs.table, calibration_wheel_ids=cal_wheels,
            route_attributes=attributes, expected_progression=expected, causes=body.causes,
            seed=body.seed)
    except ValueError as exc:
        raise from_value_error(exc, "filter") from exc
    return DiagnosisRun(diagnosis, model, row, frame["measurement_id"].astype(int).tolist(),
                        {k: v for k, v in excluded.items() if v},
                        None if expected is None else expected.describe())


def progression_of_simulations(session: Session, ids: list[int]) -> Any:
    """The expected progression of stored, finished wear-loop simulations (404 for an unknown
    id, 422 for one not done)."""
    from wearcast.statistics.discrepancy_progression import (
        SimulatedWheel,
        progression_from_simulations,
    )

    wheels = []
    for sim_id in dict.fromkeys(ids):
        row = session.get(db.Simulation, sim_id)
        if row is None or "kind" in (row.spec or {}):
            raise NotFound("expected_progression_simulations",
                           f"no simulation with id {sim_id}")
        if row.status != "done" or not row.result:
            raise Unprocessable("expected_progression_simulations",
                                f"simulation {sim_id} is {row.status}, not done")
        res, spec = row.result, row.spec
        wheels.append(SimulatedWheel(str(spec.get("bogie_type", "trailer")),
                                     int(spec.get("axle", 1)), np.asarray(res["y_mm"], float),
                                     np.asarray(res["profiles_mm"], float),
                                     np.asarray(res["mileage_km"], float)))
    source = "wear-loop simulations " + ", ".join(str(i) for i in dict.fromkeys(ids))
    try:
        return progression_from_simulations(wheels, source)
    except ValueError as exc:
        raise from_value_error(exc, "expected_progression_simulations") from exc


def save_extension(session: Session, run: DiagnosisRun, name: str
                   ) -> tuple[db.Model | None, str | None]:
    """Store the model extended by the verdict's cause as a new model.

    Returns (the new model row, None), (the row, a note on how to use it) for
    ``profile_misalignment`` (the saved model carries per-instrument corrections of the
    measurements, its rates are the base model's), or (None, why nothing was saved) when
    the verdict is ``none``.
    """
    diagnosis = run.diagnosis
    if diagnosis.verdict == "none":
        return None, "the verdict is 'none': no extension improves the model materially"
    if diagnosis.verdict == "ambiguous":
        return None, ("the verdict is 'ambiguous': no cause beats the runner-up by a tested "
                      f"margin (candidates: {', '.join(diagnosis.candidates)})")
    if diagnosis.verdict == "outside_catalogue":
        return None, ("the verdict is 'outside_catalogue': the residuals are structured ("
                      + ", ".join(u["by"] for u in diagnosis.unexplained)
                      + ") but no cause of the catalogue explains them")
    finding = diagnosis.finding(diagnosis.verdict)
    assert finding is not None
    extended = extension.apply_extension(run.model, finding)
    note = None
    if finding.cause == "profile_misalignment":
        params = finding.extension["parameters"]
        if "corrections" not in params:
            return None, ("profile_misalignment: no reference instrument among the "
                          "calibration measurements, so no correction could be fitted")
        note = (f"saved: the model predicts wear exactly as model {run.row.id}; it carries the "
                "per-instrument geometric corrections relative to instrument "
                f"{params['reference_instrument']!r} (extension.parameters.corrections). Apply "
                "them to that instrument's measured profiles or wear curves "
                "(wearcast.statistics.extension.correct_profile / correct_wear_curves) "
                "before comparing or recalibrating, and fix the instrument.")
    parent = run.row
    state = json_value(extended.to_dict(), infinity_as_text=True)
    measure = extended.measure if isinstance(extended, hybrid.HybridModel) else parent.measure
    spec = {"derived_from": parent.id, "cause": finding.cause,
            "calibration": parent.spec.get("calibration", {}),
            "diagnosis": {"verdict": diagnosis.verdict, "gain": finding.gain.to_dict(),
                          "n_measurements": diagnosis.n_measurements}}
    row = db.Model(name=name, measure=measure, running_mode=parent.running_mode,
                   wear_table_id=parent.wear_table_id, route_id=parent.route_id, spec=spec,
                   state=state)
    session.add(row)
    session.flush()
    ids = run.measurement_ids
    for start in range(0, len(ids), 5000):
        session.execute(insert(db.ModelCalibrationMeasurement),
                        [{"model_id": row.id, "measurement_id": m}
                         for m in ids[start:start + 5000]])
    session.commit()
    return row, note


def diagnosis_out(session: Session, model_id: int, run: DiagnosisRun,
                  saved: db.Model | None = None, save_reason: str | None = None
                  ) -> DiagnosisOut:
    """The answer: the diagnosis as its core writes it (``Diagnosis.to_dict``) and the
    service's own fields."""
    return DiagnosisOut.model_validate({
        "model_id": model_id, **run.diagnosis.to_dict(), "excluded": run.excluded,
        "expected_progression": run.expected_progression,
        "saved_model": None if saved is None else model_store.model_out(session, saved),
        "save_reason": save_reason})


def diagnose(session: Session, model_id: int, body: DiagnoseIn) -> DiagnosisOut:
    """``POST /v1/models/{id}/diagnose``: the diagnosis, and the extended model when asked."""
    run = run_diagnosis(session, model_id, body)
    saved, reason = (None, None)
    if body.save_as is not None:
        saved, reason = save_extension(session, run, body.save_as)
    return diagnosis_out(session, model_id, run, saved, reason)


def report_html(session: Session, model_id: int, body: DiagnoseIn,
                cause: str | None = None) -> str:
    """The HTML report of a diagnosis: verdict, findings, skipped causes and the figures
    (residuals against the named covariate, predicted vs measured before/after)."""
    run = run_diagnosis(session, model_id, body)
    if cause is not None and run.diagnosis.finding(cause) is None:
        raise Unprocessable("cause", f"no finding for cause {cause!r} in this diagnosis")
    figures = discrepancy_report.diagnosis_figures(run.diagnosis, cause)
    return discrepancy_report.report_html(run.diagnosis, figures)
