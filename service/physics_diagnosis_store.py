"""The physics diagnosis on stored data: what a physics model gets wrong, and why.

:func:`wearcast.statistics.physics_diagnosis.diagnose_physics` scores each cause of the
physical catalogue (flange wear against the tread, friction level, running-direction share,
patch model, wear law, traction, rail state, curve classes; ``catalogue_for`` the model's own
friction, law and options as the nulls) out of sample with folds grouped by vehicle. Its
``simulate`` is the model's whole-vehicle run: the stored run for the null, one new run per
catalogue value to the model's simulated mileage (a flange factor above 1 at the wear scale
1 / factor, ``PhysicsCause.run_scale``). The rail state runs on the vehicle's rail worn by its own
traffic on the model's classes (``physics.rail_tonnage``: the catalogue's tonnages from one
chain of rail steps, computed once per diagnosis); the curve classes re-bin the route's
stored segments (``route_store.rebinned_classes``), skipped when the route was stored as
classes. That is several loop runs, so the diagnosis is a job (``physics_diagnosis``); the
request waits for it like the build (:mod:`wearcast.service.physics_jobs`).

Measured: the model's calibration measurements, plus those the request's ``filter`` selects
(as the hybrid diagnosis adds its calibration set), averaged per vehicle and mileage.
``save_as`` stores the model extended by the verdict's cause: the loop run with the fitted
parameter value and the scale refitted on all the measurements, a new physics model with
``derived_from`` and ``extension``.
"""

from __future__ import annotations

from typing import Any

import pandas as pd
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import measurement_store
from wearcast.service import models_db as db
from wearcast.service import physics_model_store as store
from wearcast.service.db import SessionFactory, transaction
from wearcast.service.diagnosis_schemas import DiagnoseIn, DiagnosisOut
from wearcast.service.errors import Unprocessable
from wearcast.service.job_store import JobControl, default_timeout, queue_job
from wearcast.service.physics_schemas import MAX_STEPS_PER_RUN
from wearcast.service.route_store import rebinned_classes
from wearcast.statistics.physics_causes import (
    CURVE_CLASSES_PARAMETER,
    NO_SEGMENTS,
    catalogue_for,
)
from wearcast.statistics.physics_diagnosis import (
    NULL_TEST,
    PhysicsDiagnosis,
    diagnose_physics,
)
from wearcast.statistics.physics_model import VehicleSeries, calibrate_scale
from wearcast.statistics.routes import DEFAULT_N_CLASS

KIND = "physics_diagnosis"


def _friction(state: dict[str, Any]) -> float:
    from wearcast.physics.vehicle_wear_simulation import vehicle_bogies

    given = state["options"].get("friction")
    return float(given) if given is not None else float(
        vehicle_bogies(state["vehicle"])[0][0].friction)


def _adhesion_torque_nm(state: dict[str, Any]) -> float | None:
    """2 mu Q r of the vehicle's motor axle [N m] (None without a motor bogie): the scale of
    the traction cause's torques."""
    from wearcast.physics.vehicle_wear_simulation import vehicle_bogies

    motors = [b for b, _ in vehicle_bogies(state["vehicle"], _friction(state))
              if b.bogie_type == "motor"]
    if not motors:
        return None
    b = motors[0]
    return 2.0 * b.friction * b.wheel_load_n * b.wheel_radius_m


def catalogue(state: dict[str, Any], segments: list[Any] | None = None) -> tuple[Any, ...]:
    """The catalogue with the model's own values as the nulls; with the route's ``segments``
    also the curve-classes cause around the model's own number of classes."""
    opts = state["options"]
    sim_spec = state.get("simulation_spec") or {}
    nulls = {"law": state["law"], "forward_share": opts.get("forward_share", 0.5),
             "flange_wear_factor": opts.get("flange_wear_factor", 1.0),
             "patch_width": opts.get("patch_width", "hertz"),
             "traction_torque_nm": opts.get("traction_torque_nm") or 0.0,
             "rail_tonnage_mt": sim_spec.get("rail_tonnage_mt") or 0.0}
    n_class = (int(sim_spec.get("curve_classes") or DEFAULT_N_CLASS) if segments else None)
    cat = catalogue_for(_friction(state), nulls, _adhesion_torque_nm(state), n_class)
    return tuple(c for c in cat if c.name not in _skipped(segments, state))


def _segments(session: Session, model: Any) -> list[Any] | None:
    """The segments of the model's route (None when it was stored as classes)."""
    route = session.get(db.Route, model.route_id)
    return None if route is None or not route.segments else list(route.segments)


#: Why the rail-state cause is skipped for a model on stored rails.
ON_STORED_RAILS = ("the model runs on stored measured rails (rail_id / high_rail_id / "
                   "low_rail_id): the rail-step model wears the preset's nominal rail, not them")


def _skipped(segments: list[Any] | None, state: dict[str, Any]) -> dict[str, str]:
    """Causes the model cannot be extended by, with the reason."""
    out = {} if segments else {"curve_classes": NO_SEGMENTS}
    if state.get("track_rails"):
        out["rail_state"] = ON_STORED_RAILS
    return out


def submit(session: Session, runner: Any, model_id: int, body: DiagnoseIn) -> int:
    """Validate a physics diagnosis and queue it; the job id."""
    model = store.load(session, model_id)
    for field in ("expected_progression", "expected_progression_simulations"):
        if getattr(body, field) is not None:
            raise Unprocessable(field, "a physics model's diagnosis simulates the progression "
                                "itself; this field is for hybrid models")
    segments = _segments(session, model)
    names = [c.name for c in catalogue(model.state, segments)] + list(
        _skipped(segments, model.state))
    if body.causes is not None:
        for i, code in enumerate(body.causes):
            if code not in names:
                raise Unprocessable(f"causes[{i}]", f"unknown cause {code!r} of the physics "
                                    f"catalogue; known: {', '.join(names)}")
    link = db.ModelCalibrationMeasurement
    ids = set(session.scalars(select(link.measurement_id).where(link.model_id == model_id)))
    if body.filter:
        matched = set(measurement_store.matching_ids(session, dict(body.filter), "filter"))
        if not matched:  # not silently the calibration set alone
            raise Unprocessable("filter", "no measurements match the filter")
        ids |= matched
    if not ids:
        raise Unprocessable("filter", "no measurements to diagnose")
    measured, used = _by_ids(session, sorted(ids))
    if measured["vehicle"].nunique() < 2:
        raise Unprocessable("filter", "the physics diagnosis needs measurements of at least "
                            "two vehicles (it scores every cause on a vehicle it was not "
                            "fitted on)")
    runner.check_quota(session)
    spec = {"kind": KIND, "model_id": model_id, "request": body.model_dump(mode="json"),
            "measured": measured.to_dict(orient="records"), "measurement_ids": used}
    row = queue_job(session, f"diagnose model {model_id}", spec, timeout_s=default_timeout())
    runner.submit(row.id)
    return row.id


def _by_ids(session: Session, ids: list[int]) -> tuple[pd.DataFrame, list[int]]:
    from wearcast.statistics.physics_model import measured_vehicle_means

    frame, _ = measurement_store.calibration_frame(session, ids)
    usable = (frame["sd_mm"].notna() & frame["qr_mm"].notna()).to_numpy()
    frame = frame[usable].reset_index(drop=True)
    if frame.empty:
        raise Unprocessable("filter", "no measurement with Sd and qR to diagnose")
    return measured_vehicle_means(frame), frame["measurement_id"].astype(int).tolist()


def run_diagnosis_job(factory: SessionFactory, job_id: int, spec: dict[str, Any],
                      control: JobControl) -> dict[str, Any]:
    """The diagnosis job's work; its result is the ``DiagnosisOut`` of the request."""
    with factory() as session:
        model = store.load(session, int(spec["model_id"]))
        model_spec = session.scalar(select(db.Model.spec).where(db.Model.id == model.id)) or {}
        segments = _segments(session, model)
    state = model.state
    request = DiagnoseIn.model_validate(spec["request"])
    cat = catalogue(state, segments)
    if request.causes is not None:
        cat = tuple(c for c in cat if c.name in request.causes)
    n_runs = sum(len(c.values) - 1 for c in cat) + (1 if request.save_as else 0)
    done = [0]
    simulated_km = float(state["simulation"]["mileage_km"])
    route = {"classes": state["resolved_classes"], "km": simulated_km}
    contacts: dict = {}  # first contact updates shared by the runs (same new profile)
    # the worn rails of the rail-state cause, computed once (one chain of rail steps) on the
    # model's own classes
    own_tonnage = state["simulation_spec"].get("rail_tonnage_mt") or 0.0
    tonnages = sorted({*(v for c in cat if c.parameter == "rail_tonnage_mt" for v in c.values
                         if v), *([own_tonnage] if own_tonnage else [])})
    rails: dict[float, Any] = {}

    def classes_for(params: dict[str, Any]) -> list[dict[str, Any]]:
        n_class = params.pop(CURVE_CLASSES_PARAMETER, None)
        if n_class is None:
            return route["classes"]
        assert segments is not None  # the cause is in the catalogue only with segments
        return rebinned_classes(segments, int(n_class))

    made: dict[str, Any] = {}  # the runs of this job by their parameters: save_as's run of
    # the verdict's value is the diagnosis's own run when that value is a catalogue value

    def simulate(params: Any) -> Any:
        params = dict(params)
        if not params:
            return model.series
        key = repr(sorted(params.items()))
        if key not in made:
            made[key] = run(params)
        return made[key]

    def run(params: dict[str, Any]) -> Any:
        label = ", ".join(f"{k}={v}" for k, v in params.items())

        def progress(km: float) -> None:
            control.progress(min(0.95, (done[0] + km / simulated_km) / max(n_runs, 1)),
                             f"run {done[0] + 1}/{n_runs} ({label}): {km:,.0f} km")

        if params.get("rail_tonnage_mt", own_tonnage) and not rails and tonnages:
            control.progress(min(0.95, done[0] / max(n_runs, 1)),
                             f"rails worn to {', '.join(f'{t:g}' for t in tonnages)} Mt")
            rails.update(store.worn_rails(state["vehicle"], route["classes"], state["law"],
                                          state["simulation_spec"], tonnages))
        classes = classes_for(params)
        # a catalogue value that wears more slowly needs more steps to the model's mileage than
        # the model's own run took: every catalogue run may take up to the request bound
        spec_run = {**state["simulation_spec"], "max_steps": MAX_STEPS_PER_RUN}
        sim = store.run_loop(state["vehicle"], classes, state["law"], spec_run, simulated_km,
                             params, progress, contact_cache=contacts, rails=rails,
                             track_rails=state.get("track_rails"))
        done[0] += 1
        return sim

    measured = pd.DataFrame(spec["measured"])
    diagnosis = diagnose_physics(simulate, measured, catalogue=cat, seed=request.seed,
                                 skipped=_skipped(segments, state))
    saved, reason = None, None
    if request.save_as is not None:
        saved, reason = _save(factory, model, model_spec, diagnosis, request.save_as,
                              spec, route["classes"], simulate, segments)
    return _out(model.id, diagnosis, saved, reason, factory).model_dump(mode="json")


def _save(factory: SessionFactory, model: Any, model_spec: dict[str, Any], diagnosis: Any,
          name: str, spec: dict[str, Any], classes: list[dict[str, Any]],
          simulate: Any, segments: list[Any] | None = None) -> tuple[int | None, str | None]:
    """Store the model extended by the verdict's cause (a new physics model)."""
    if diagnosis.verdict == "none":
        return None, "the verdict is 'none': no extension improves the model materially"
    if diagnosis.verdict == "ambiguous":
        return None, ("the verdict is 'ambiguous': no tested margin separates "
                      f"{', '.join(diagnosis.candidates)}; nothing to extend the model by")
    finding = diagnosis.finding(diagnosis.verdict)
    parameter, value = finding.extension["parameter"], finding.extension["value"]
    sim = simulate({parameter: value})
    series = VehicleSeries.from_simulation(sim) if not isinstance(sim, VehicleSeries) else sim
    measured = pd.DataFrame(spec["measured"])
    calibration = calibrate_scale(series, measured)
    state = model.state
    sim_spec = dict(state["simulation_spec"])
    law = state["law"]
    if parameter == "law":
        law = value
    elif parameter == CURVE_CLASSES_PARAMETER and value is None:
        pass  # the model's own classes fitted best (the null level)
    else:
        sim_spec[parameter] = value
    if parameter == CURVE_CLASSES_PARAMETER and value is not None:
        assert segments is not None
        classes = rebinned_classes(segments, int(value))  # the extended model's classes
    new_spec = {**model_spec, "law": law, "simulation": sim_spec, "vehicle": state["vehicle"],
                "route_db_id": model.route_id, "measured": spec["measured"],
                "measurement_ids": spec["measurement_ids"],
                "track_rails": state.get("track_rails")}
    info = dict(state["simulation"])
    info.update(elapsed_s=float(getattr(sim, "elapsed_s", 0.0)),
                steps=int(series.mileage_km.size - 1), runs=[])
    extension = {"cause": finding.cause, "parameter": parameter, "value": value,
                 "null_value": finding.extension.get("null_value"),
                 "gain": finding.gain.to_dict()}
    new_spec["resolved_classes"] = classes
    new_state = store.state_of(new_spec, series, calibration, info, [], extension)
    with transaction(factory) as session:
        row = store.store_model(session, name, new_spec, new_state, spec["measurement_ids"],
                                derived_from=model.id)
        session.flush()
        return row.id, None


def _out(model_id: int, diagnosis: PhysicsDiagnosis, saved: int | None, reason: str | None,
         factory: SessionFactory) -> DiagnosisOut:
    """The answer: the diagnosis as its core writes it (``PhysicsDiagnosis.to_dict``), the
    hybrid answer's ``selected`` (the verdict when it names a cause) and ``null_test``, and
    the service's own fields."""
    saved_model = None
    if saved is not None:
        with factory() as session:
            row = session.get(db.Model, saved)
            assert row is not None
            saved_model = store.model_out(session, row)
    named = diagnosis.verdict not in ("none", "ambiguous")
    return DiagnosisOut.model_validate({
        "model_id": model_id, **diagnosis.to_dict(),
        "selected": [diagnosis.verdict] if named else [], "null_test": NULL_TEST,
        "saved_model": saved_model, "save_reason": reason})
