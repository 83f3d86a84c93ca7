"""Physics models in storage: validate and queue the build, run it, read, predict, reprofiling.

A physics model (``POST /v1/models`` with ``kind: "physics"``) is the whole-vehicle wear loop
(:func:`wearcast.physics.vehicle_wear_simulation.simulate_vehicle_wear`) of a vehicle preset on
a stored route's curve classes with a wear law, and one wear-coefficient scale fitted to the
measured Sd/Sh/qR that the calibration filter selects (:mod:`wearcast.statistics.physics_model`).

* The request is validated completely before anything runs (422/404 naming the field):
  vehicle, route, law, options, and that the filter selects measurements with Sd and qR of
  at least one wheel beyond 0 km. The build then runs as a job (``physics_model`` in the
  ``simulations`` table, like coefficient fits): the loop to twice the furthest measured
  mileage (or ``simulation.mileage_km``), continued further (at most twice, from where it
  ended: ``continue_from``) when the fitted scale needs more, the scale fitted, compared
  per vehicle and quantity, the model row stored with its calibration measurements linked
  (measurements are only read).
* The stored state carries the run's per-wheel series, so predict and reprofiling need no
  new run: the wheel position's Sd/Sh/qR at wheel mileage m are the run's at c m (P10/P90
  from the vehicle-to-vehicle spread of c).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy import insert, select
from sqlalchemy.orm import Session

from wearcast.service import measurement_store, rail_store, route_store
from wearcast.service import models_db as db
from wearcast.service.cache import LruCache
from wearcast.service.db import SessionFactory, transaction
from wearcast.service.errors import NotFound, Unprocessable
from wearcast.service.job_store import JobControl, finite_json, resolve_classes
from wearcast.service.model_schemas import ModelOut, PhysicsModelSummary
from wearcast.service.physics_schemas import PhysicsModelIn
from wearcast.service.prediction_schemas import PredictIn
from wearcast.service.reprofiling_schemas import ReprofilingIn
from wearcast.statistics.physics_comparison import loss_rate_per_1000_km
from wearcast.statistics.physics_model import (
    QUANTITIES,
    VehicleSeries,
    calibrate_scale,
    first_crossing,
    measured_vehicle_means,
    predict_position,
)
from wearcast.statistics.profile_parameters import WheelLimits

KIND = "physics_model"
#: Runs of one build at most (the first and up to two longer ones).
MAX_RUNS = 3
#: Options of the run a request sets (``VehicleWearOptions`` fields).
OPTION_FIELDS = ("forward_share", "flange_wear_factor", "friction", "patch_width",
                 "application", "traction_torque_nm")


# --- validating and queueing ----------------------------------------------------------------

def _route_row(session: Session, body: PhysicsModelIn) -> db.Route:
    given, inner = body.route_id, body.calibration.route_id
    if given is None and inner is None:
        raise Unprocessable("route_id", "a physics model needs a stored route (id or name) "
                            "whose curve classes it simulates")
    ref = given if given is not None else inner
    assert ref is not None
    row = route_store.get_route(session, ref,
                                "route_id" if given is not None else "calibration.route_id")
    if given is not None and inner is not None:
        other = route_store.get_route(session, inner, "calibration.route_id")
        if other.id != row.id:
            raise Unprocessable("calibration.route_id", f"names route {other.name!r}, "
                                f"route_id {row.name!r}: give one route")
    return row


def measured_series(session: Session, filter_: dict[str, Any], field: str
                    ) -> tuple[pd.DataFrame, list[int]]:
    """The vehicle-averaged Sd/Sh/qR series of the measurements a filter selects, and the
    ids of the measurements used (those with Sd and qR)."""
    ids = measurement_store.matching_ids(session, filter_, field)
    if not ids:
        raise Unprocessable(field, "no measurements match the filter")
    frame, _ = measurement_store.calibration_frame(session, ids)
    usable = (frame["sd_mm"].notna() & frame["qr_mm"].notna()).to_numpy()
    frame = frame[usable].reset_index(drop=True)
    if frame.empty:
        raise Unprocessable(field, "no matching measurement has Sd and qR")
    measured = measured_vehicle_means(frame)
    if not (measured["distance_km"] > 0).any():
        raise Unprocessable(field, "every matching measurement is at 0 km: the wear scale "
                            "needs wheels measured after some mileage")
    return measured, frame["measurement_id"].astype(int).tolist()


def options_of(simulation: dict[str, Any]) -> dict[str, Any]:
    return {k: simulation.get(k) for k in OPTION_FIELDS if simulation.get(k) is not None}


def track_rails_of(session: Session, body: PhysicsModelIn) -> dict[str, Any]:
    """The stored rails a request names, checked as for ``POST /v1/simulations``
    (``rail_store.requested_rails``: 404 naming the field, 422 for differing inclinations),
    as the job's database-free ``rail_store.rail_spec`` per field ({} when none is named)."""
    rail_store.requested_rails(session, body)
    rails = {f: rail_store.rail_spec(session, getattr(body, f), f)
             for f in rail_store.RAIL_FIELDS if getattr(body, f) is not None}
    if rails and body.simulation.rail_tonnage_mt:
        raise Unprocessable("simulation.rail_tonnage_mt", "the rail-step model wears the "
                            "preset's nominal rail: give no rail_tonnage_mt with "
                            f"{', '.join(rails)}")
    return rails


def rail_ids_of(track_rails: dict[str, Any] | None) -> dict[str, int]:
    """The rail ids a model was built against ({field: id}, e.g. ``high_rail_id``)."""
    return {f: int(spec["rail_id"]) for f, spec in (track_rails or {}).items()}


def bogies_on_rails(vehicle: str, track_rails: dict[str, Any] | None) -> Any:
    """The vehicle preset's name, or, with stored rails (:func:`track_rails_of`), its bogies
    (``vehicle_bogies`` pairs) laid on them by ``rail_store.with_rails`` (rails, high / low
    rail of every curve, their stated inclination): what ``simulate_vehicle_wear`` runs."""
    if not track_rails:
        return vehicle
    from wearcast.physics.vehicle_wear_simulation import vehicle_bogies

    rails = [None if track_rails.get(f) is None
             else rail_store.measured_rail_from_spec(track_rails[f])
             for f in rail_store.RAIL_FIELDS]
    return [(rail_store.with_rails(b, *rails), n) for b, n in vehicle_bogies(vehicle)]


def prepare(session: Session, body: PhysicsModelIn) -> dict[str, Any]:
    """Validate a request completely; the job's spec (request, resolved route, measured)."""
    from wearcast.physics.vehicle_wear_simulation import VehicleWearOptions, vehicle_bogies
    from wearcast.physics.wear_loop import as_loop_classes

    route = _route_row(session, body)
    track_rails = track_rails_of(session, body)
    classes = resolve_classes(session, SimpleNamespace(route_id=route.id))
    sim = body.simulation.model_dump()
    if sim.get("curve_classes") is not None:
        if not route.segments:
            raise Unprocessable("simulation.curve_classes", f"route {route.name!r} is stored "
                                "as curve classes, not segments: it cannot be re-binned")
        classes = route_store.rebinned_classes(route.segments, sim["curve_classes"],
                                               "simulation.curve_classes")
    try:
        as_loop_classes(classes)
    except ValueError as exc:
        raise Unprocessable("route_id", f"route {route.name!r}: {exc}") from exc
    try:
        VehicleWearOptions(**options_of(sim))
        vehicle_bogies(bogies_on_rails(body.vehicle, track_rails), sim.get("friction"))
    except ValueError as exc:
        raise Unprocessable("simulation", str(exc)) from exc
    measured, ids = measured_series(session, dict(body.calibration.filter),
                                    "calibration.filter")
    furthest = float(measured["distance_km"].max())
    if body.simulation.mileage_km is None and 2.0 * furthest > body.simulation.max_mileage_km:
        raise Unprocessable("simulation.max_mileage_km", f"the calibration reaches "
                            f"{furthest:,.0f} km; the run needs at least twice that")
    spec = body.model_dump(mode="json")
    spec.update(kind=KIND, route_db_id=route.id, route_name=route.name,
                resolved_classes=classes, measurement_ids=ids,
                measured=measured.to_dict(orient="records"), track_rails=track_rails)
    return spec


# --- running ----------------------------------------------------------------------------------

def worn_rails(vehicle: str, classes: list[dict[str, Any]], law: str,
               simulation: dict[str, Any], tonnages_mt: Any) -> dict[float, Any]:
    """The vehicle's rail worn by its own passages on the route's classes to each tonnage
    [Mt] (``physics.rail_tonnage``: one chain of rail steps for all of them), with the
    model's friction and wear application: {tonnage: rail}."""
    from wearcast.physics.rail_tonnage import rails_worn_to_tonnages
    from wearcast.physics.vehicles import vehicle_preset
    from wearcast.physics.wear_loop import as_loop_classes

    veh = vehicle_preset(vehicle)
    if simulation.get("friction") is not None:
        veh = veh.with_(friction=float(simulation["friction"]))
    return rails_worn_to_tonnages(veh, as_loop_classes(classes), list(tonnages_mt), law=law,
                                  application=simulation.get("application") or "global").rails


def run_loop(vehicle: str, classes: list[dict[str, Any]], law: str, simulation: dict[str, Any],
             mileage_km: float, params: dict[str, Any] | None = None,
             progress: Any = None, continue_from: Any = None,
             contact_cache: dict | None = None, rails: dict[float, Any] | None = None,
             track_rails: dict[str, Any] | None = None) -> Any:
    """One whole-vehicle run with a model's options, ``params`` (VehicleWearOptions fields,
    ``law`` or ``rail_tonnage_mt``) replacing them; ``continue_from`` an earlier run to go on
    from (not with ``step_convergence``, which runs anew); ``contact_cache`` shared by the runs
    of one diagnosis (``simulate_vehicle_wear``: first contact updates solved once).

    ``rail_tonnage_mt`` (of ``params`` or the model's ``simulation``) > 0: the run is on the
    rail worn to it (:func:`worn_rails` on ``classes``), looked up in / added to ``rails``
    (the worn rails of one diagnosis, so each is computed once).

    ``track_rails``: the model's stored rails (:func:`track_rails_of`), under every run."""
    from wearcast.physics.vehicle_wear_simulation import (
        VehicleWearOptions,
        simulate_vehicle_wear,
        simulate_vehicle_wear_converged,
    )
    from wearcast.physics.wear_loop import as_loop_classes

    options = options_of(simulation)
    params = dict(params or {})
    law = params.pop("law", law)
    tonnage = float(params.pop("rail_tonnage_mt", simulation.get("rail_tonnage_mt")) or 0.0)
    options.update(params)
    if tonnage > 0:
        rails = {} if rails is None else rails
        if tonnage not in rails:
            rails.update(worn_rails(vehicle, classes, law, simulation, [tonnage]))
        options["rail"] = rails[tonnage]
    kwargs = {"law": law, "mileage_km": float(mileage_km),
              "options": VehicleWearOptions(**options),
              "max_steps": int(simulation.get("max_steps", 200)), "progress": progress,
              "contact_cache": contact_cache}
    route = as_loop_classes(classes)
    step = float(simulation.get("depth_per_step_mm", 0.8))
    bogies = bogies_on_rails(vehicle, track_rails)
    if simulation.get("step_convergence"):
        return simulate_vehicle_wear_converged(bogies, route, first_step_mm=step, **kwargs)
    return simulate_vehicle_wear(bogies, route, depth_per_step_mm=step,
                                 continue_from=continue_from, **kwargs)


def _needed_mileage(series: VehicleSeries, measured: pd.DataFrame, mileage_km: float) -> float:
    """A run long enough for the measured losses: the measured loss rate over the run's
    (FT and qR, the larger) times the furthest mileage, with 50 % to spare (at least 2x)."""
    ratios = []
    for col, q in (("FT_mm", "sd_mm"), ("QR_mm", "qr_mm")):
        mean = series.mean(q)
        rows = measured.dropna(subset=[col])
        run_rate = (mean[0] - mean[-1]) / float(series.mileage_km[-1]) * 1000.0
        meas_rate = loss_rate_per_1000_km(rows["distance_km"].to_numpy(float),
                                          mean[0] - rows[col].to_numpy(float))
        if run_rate > 0 and math.isfinite(meas_rate):
            ratios.append(meas_rate / run_rate)
    furthest = float(measured["distance_km"].max())
    need = 1.5 * max(ratios) * furthest if ratios else 4.0 * mileage_km
    return max(need, 2.0 * mileage_km)


def build(spec: dict[str, Any], control: JobControl | None = None
          ) -> tuple[VehicleSeries, Any, dict[str, Any], list[str]]:
    """Run the loop (further when the scale needs it) and calibrate: the series, the
    calibration, the run's description and warnings."""
    measured = pd.DataFrame(spec["measured"])
    sim_spec = spec["simulation"]
    fixed = sim_spec.get("mileage_km")
    cap = float(sim_spec.get("max_mileage_km", 1_000_000.0))
    mileage = float(fixed) if fixed else 2.0 * float(measured["distance_km"].max())
    runs: list[dict[str, Any]] = []
    warnings: list[str] = []
    sim: Any = None
    rails: dict[float, Any] = {}  # a worn rail (simulation.rail_tonnage_mt) computed once
    for attempt in range(MAX_RUNS):
        def progress(km: float, attempt: int = attempt, total: float = mileage) -> None:
            if control is not None:
                control.progress(min(0.95, (attempt + km / total) / MAX_RUNS),
                                 f"run {attempt + 1}: {km:,.0f} of {total:,.0f} km")
        sim = run_loop(spec["vehicle"], spec["resolved_classes"], spec["law"], sim_spec,
                       mileage, progress=progress, continue_from=sim, rails=rails,
                       track_rails=spec.get("track_rails"))
        series = VehicleSeries.from_simulation(sim)
        calibration = calibrate_scale(series, measured)
        runs.append({"mileage_km": mileage, "steps": int(series.mileage_km.size - 1),
                     "elapsed_s": float(sim.elapsed_s), "continued": attempt > 0,
                     "wear_scale": calibration.fit.wear_scale,
                     "at_reach": calibration.fit.at_reach})
        if not calibration.fit.at_reach or fixed or mileage >= cap:
            break
        mileage = min(cap, _needed_mileage(series, measured, mileage))
    if calibration.fit.at_reach:
        warnings.append(f"the fitted scale {calibration.fit.wear_scale:.3g} is at the largest "
                        f"the run reaches ({calibration.fit.reach:.3g}): the measured wheels "
                        "wear faster than a run of "
                        f"{mileage:,.0f} km shows; raise simulation.mileage_km")
    info = {"mileage_km": float(series.mileage_km[-1]), "steps": runs[-1]["steps"],
            "depth_per_step_mm": float(sim.depth_per_step_mm),
            "contact_updates": int(sim.contact_updates),
            "contact_fallbacks": int(sim.contact_fallbacks),
            "elapsed_s": float(sum(r["elapsed_s"] for r in runs)),
            "step_convergence": None if sim.convergence is None else sim.convergence.to_dict(),
            "runs": runs}
    return series, calibration, info, warnings


def state_of(spec: dict[str, Any], series: VehicleSeries, calibration: Any,
             info: dict[str, Any], warnings: list[str],
             extension: dict[str, Any] | None = None) -> dict[str, Any]:
    return finite_json({
        "kind": "physics", "vehicle": spec["vehicle"], "law": spec["law"],
        "options": options_of(spec["simulation"]), "simulation_spec": spec["simulation"],
        "series": series.to_dict(), "calibration": calibration.to_dict(),
        "measured": spec["measured"], "simulation": info, "warnings": warnings,
        "extension": extension, "resolved_classes": spec["resolved_classes"],
        "measurement_ids": list(spec["measurement_ids"]),
        "route_db_id": spec["route_db_id"], "track_rails": spec.get("track_rails") or {}})


def store_model(session: Session, name: str, spec: dict[str, Any], state: dict[str, Any],
                ids: list[int], derived_from: int | None = None) -> db.Model:
    public: dict[str, Any] = {k: spec[k] for k in ("kind", "name", "vehicle", "route_id", "law",
                                   "calibration", "simulation") if k in spec}
    public.update(kind="physics", name=name, **rail_ids_of(state.get("track_rails")))
    if derived_from is not None:
        public["derived_from"] = derived_from
    row = db.Model(name=name, kind="physics", measure=None, running_mode=None,
                   wear_table_id=None, route_id=int(spec["route_db_id"]), spec=public,
                   state=state)
    session.add(row)
    session.flush()
    for start in range(0, len(ids), 5000):
        session.execute(insert(db.ModelCalibrationMeasurement),
                        [{"model_id": row.id, "measurement_id": m}
                         for m in ids[start:start + 5000]])
    return row


def run_build(factory: SessionFactory, job_id: int, spec: dict[str, Any],
              control: JobControl) -> dict[str, Any]:
    """The build job's work: run, calibrate, store; the job's result."""
    series, calibration, info, warnings = build(spec, control)
    control.check()
    with transaction(factory) as session:
        row = store_model(session, spec["name"], spec, state_of(
            spec, series, calibration, info, warnings), spec["measurement_ids"])
        session.flush()
        out = model_out(session, row)
    return {"model_id": out.id, "model": out.model_dump(mode="json")}


# --- reading ----------------------------------------------------------------------------------

def model_out(session: Session, row: db.Model) -> ModelOut:
    from sqlalchemy import func

    n = session.scalar(select(func.count()).select_from(db.ModelCalibrationMeasurement)
                       .where(db.ModelCalibrationMeasurement.model_id == row.id)) or 0
    state = row.state
    series = VehicleSeries.from_dict(state["series"])
    cal = state["calibration"]
    c = float(cal["wear_scale"])
    spread = cal["spread"]
    measured = pd.DataFrame(state["measured"])
    summary = PhysicsModelSummary(
        vehicle=state["vehicle"], law=state["law"], route_id=row.route_id,
        options=state["options"], wear_scale=c, wear_scale_p10=spread["scale_p10"],
        wear_scale_p90=spread["scale_p90"], spread=spread, rms_mm=cal["rms_mm"],
        at_reach=cal["at_reach"],
        calibrated_on={"filter": row.spec.get("calibration", {}).get("filter", {}),
                       "n_measurements": int(n),
                       "measurement_ids": state.get("measurement_ids", []),
                       "vehicles": sorted(measured["vehicle"].astype(str).unique().tolist()),
                       "n_points": cal["n_points"], "series": state["measured"]},
        series={"mileage_km": (series.mileage_km / c).tolist(),
                "run_mileage_km": series.mileage_km.tolist(),
                "ft_mm": series.mean("sd_mm").tolist(), "fh_mm": series.mean("sh_mm").tolist(),
                "qr_mm": series.mean("qr_mm").tolist(), "wheels": list(series.wheels)},
        errors=cal["errors"], simulation=state["simulation"], warnings=state["warnings"],
        rails={f: {k: r.get(k) for k in ("rail_id", "name", "kind", "inclination")}
               for f, r in (state.get("track_rails") or {}).items()})
    return ModelOut(
        id=row.id, name=row.name, measure=None, running_mode=None, wear_table_id=None,
        route_id=row.route_id, calibration=row.spec.get("calibration", {}),
        n_calibration_measurements=int(n),
        summary={"vehicle": state["vehicle"], "law": state["law"], "wear_scale": c,
                 "rms_mm": cal["rms_mm"], **rail_ids_of(state.get("track_rails"))},
        kind="physics", derived_from=row.spec.get("derived_from"),
        extension=state.get("extension"), physics=summary)


@dataclass(frozen=True)
class PhysicsModel:
    """A stored physics model, deserialised."""

    id: int
    route_id: int
    route_name: str
    state: dict[str, Any]
    series: VehicleSeries

    @property
    def scales(self) -> tuple[float, float, float]:
        spread = self.state["calibration"]["spread"]
        return (float(spread["scale_p10"]), float(self.state["calibration"]["wear_scale"]),
                float(spread["scale_p90"]))


_models: LruCache[PhysicsModel] = LruCache(32)


#: Whether a model is a physics model, per (database URL, model id): the hot paths of
#: predict and reprofiling read it without the database once known.
_kinds: LruCache[bool] = LruCache(4096)


def known_kind(database_url: str, model_id: int) -> bool | None:
    return _kinds.get((database_url, model_id))


def remember_kind(database_url: str, model_id: int, physics: bool) -> bool:
    _kinds.put((database_url, model_id), physics)
    return physics


def is_physics(session: Session, model_id: int) -> bool:
    """Whether a stored model is a physics model (404 when there is none)."""
    kind = session.scalar(select(db.Model.kind).where(db.Model.id == model_id))
    if kind is None:
        raise NotFound("model_id", f"no model with id {model_id}")
    return kind == "physics"


def load(session: Session, model_id: int) -> PhysicsModel:
    row = session.get(db.Model, model_id)
    if row is None:
        raise NotFound("model_id", f"no model with id {model_id}")
    if row.kind != "physics":
        raise Unprocessable("model_id", f"model {model_id} is a {row.kind} model")

    def make() -> PhysicsModel:
        route = session.get(db.Route, row.route_id)
        return PhysicsModel(row.id, row.route_id, route.name if route else str(row.route_id),
                            row.state, VehicleSeries.from_dict(row.state["series"]))

    return _models.get_or_create((str(session.get_bind().engine.url), model_id,
                                  row.created_at), make)


def _check_route(session: Session, model: PhysicsModel, body: PredictIn | ReprofilingIn
                 ) -> None:
    if body.route is not None:
        raise Unprocessable("route", "a physics model predicts on the route it was simulated "
                            f"on ({model.route_name!r}); give no route or that route_id")
    if body.route_id is not None:
        row = route_store.get_route(session, body.route_id, "route_id")
        if row.id != model.route_id:
            raise Unprocessable("route_id", f"a physics model predicts on the route it was "
                                f"simulated on ({model.route_name!r}, id {model.route_id}), "
                                f"not {row.name!r}: build a physics model for that route")


def _start(session: Session, body: PredictIn | ReprofilingIn) -> Any:
    """The wheel's position and measured start: as the hybrid model's
    (``wheel_start.wheel_start``), except that ``wheel_id`` starts from the wheel's latest
    measurement of either kind (a physics model reads only Sd/Sh/qR)."""
    from wearcast.service.wheel_start import WheelStart, wheel_start

    if body.wheel_id is None:
        return wheel_start(session, body)
    wheel = session.get(db.Wheel, body.wheel_id)
    if wheel is None:
        raise NotFound("wheel_id", f"no wheel {body.wheel_id!r}")
    latest = session.scalar(
        select(db.Measurement).where(db.Measurement.wheel_id == body.wheel_id,
                                     db.Measurement.sd_mm.is_not(None),
                                     db.Measurement.qr_mm.is_not(None))
        .order_by(db.Measurement.mileage_km.desc(), db.Measurement.id.desc()).limit(1))
    if latest is None:
        raise Unprocessable("wheel_id", f"wheel {body.wheel_id!r} has no measurement with Sd "
                            "and qR to start from")
    for name, given, stored in (("bogie_type", body.bogie_type, wheel.bogie_type),
                                ("axle", body.axle, wheel.axle), ("side", body.side, wheel.side)):
        if given is not None and given != stored:
            raise Unprocessable(name, f"wheel {wheel.wheel_id!r} has {name} {stored!r}")
    params = {q: float(getattr(latest, q)) for q in QUANTITIES
              if getattr(latest, q) is not None}
    return WheelStart(wheel.bogie_type, int(wheel.axle), wheel.side, float(latest.mileage_km),
                      latest.id, None, None, params)


def _quantiles(rows: np.ndarray, i: int) -> dict[str, float]:
    """P10/P50/P90 of a quantity from its values at the P10, P50, P90 scales (the value at
    the middle scale is P50; the other two bound it whichever way the quantity moves)."""
    lo, hi = float(rows[:, i].min()), float(rows[:, i].max())
    return {"p10": lo, "p50": float(rows[1, i]), "p90": hi}


def predict(session: Session, model_id: int, body: PredictIn) -> dict[str, Any]:
    """``POST /v1/models/{id}/predict`` of a physics model (``PhysicsPredictionOut``)."""
    model = load(session, model_id)
    _check_route(session, model, body)
    start = _start(session, body)
    km = np.asarray(body.mileage_km, float)
    params = start.parameters if body.measured_start else None
    try:
        pred = predict_position(model.series, list(model.scales), km,
                                bogie_type=start.bogie_type, axle=start.axle, side=start.side,
                                start_km=start.mileage_km if body.measured_start else 0.0,
                                start=params)
    except ValueError as exc:
        raise Unprocessable("bogie_type", str(exc).partition(": ")[2] or str(exc)) from exc
    points = []
    for i, m in enumerate(km.tolist()):
        quant = {q: _quantiles(pred[q], i) for q in QUANTITIES}
        points.append({"mileage_km": m, **{q: quant[q]["p50"] for q in QUANTITIES},
                       "quantiles": quant,
                       "vehicle_mean_mm": {q: float(pred[f"vehicle_{q}"][i])
                                           for q in QUANTITIES},
                       "extrapolated": bool(pred["extrapolated"][i])})
    spread = model.state["calibration"]["spread"]
    notes = list(start.notes)
    if body.covariates:
        notes.append("covariates are not used by a physics model")
    return {"model_id": model_id, "kind": "physics", "route": model.route_name,
            "bogie_type": start.bogie_type, "axle": start.axle, "side": start.side,
            "wear_scale": dict(zip(("p10", "p50", "p90"), model.scales, strict=True)),
            "spread_method": spread["method"], "points": points,
            "start_mileage_km": start.mileage_km if body.measured_start else None,
            "start_measurement_id": start.measurement_id,
            "start_parameters_mm": params, "start_notes": notes}


def _crossed(start: dict[str, float] | None, limits: WheelLimits) -> dict[str, float]:
    if not start:
        return {}
    out = {}
    if start.get("sd_mm") is not None and start["sd_mm"] < limits.sd_min_mm:
        out["sd"] = limits.sd_min_mm - start["sd_mm"]
    if start.get("sh_mm") is not None and start["sh_mm"] > limits.sh_max_mm:
        out["sh"] = start["sh_mm"] - limits.sh_max_mm
    if start.get("qr_mm") is not None and start["qr_mm"] < limits.qr_min_mm:
        out["qr"] = limits.qr_min_mm - start["qr_mm"]
    return out


def reprofiling(session: Session, model_id: int, body: ReprofilingIn) -> dict[str, Any]:
    """``POST /v1/models/{id}/reprofiling`` of a physics model (``ReprofilingOut`` fields plus
    ``kind`` and ``wear_scale``): the first EN 15313 / EBO limit crossing per scale; the P10
    mileage comes from the P90 (fastest) scale."""
    model = load(session, model_id)
    _check_route(session, model, body)
    start = _start(session, body)
    limits = WheelLimits(**(body.limits.model_dump(exclude_none=True) if body.limits else {}))
    measured_start = any(v is not None for v in (body.wheel_id, body.measurement_id,
                                                 body.profile))
    params = start.parameters if measured_start else None
    start_km = start.mileage_km if measured_start else 0.0
    crossings = []
    for c in model.scales:
        try:
            crossings.append(first_crossing(model.series, c, bogie_type=start.bogie_type,
                                            axle=start.axle, side=start.side, limits=limits,
                                            start_km=start_km, start=params))
        except ValueError as exc:
            raise Unprocessable("bogie_type", str(exc).partition(": ")[2] or str(exc)) from exc
    fast, mid, slow = crossings[2], crossings[1], crossings[0]

    def q(offset: float) -> dict[str, float | None]:
        vals = (fast.remaining_km, mid.remaining_km, slow.remaining_km)
        return dict(zip(("p10", "p50", "p90"), (offset + v if math.isfinite(v) else None
                                                 for v in vals), strict=True))

    crossed = _crossed(params, limits)
    reason = None
    if not math.isfinite(mid.remaining_km):
        reason = "no limit is crossed within 3,000,000 km"
    elif crossed:
        reason = "the measured start is already past a limit"
    return finite_json({
        "model_id": model_id, "kind": "physics", "route": model.route_name,
        "wheel_id": body.wheel_id, "bogie_type": start.bogie_type, "axle": start.axle,
        "side": start.side, "start_mileage_km": start_km,
        "start_measurement_id": start.measurement_id, "start_areas_mm2": {},
        "remaining_km": q(0.0), "mileage_km": q(start_km),
        "governing_limit": mid.governing_limit, "sd_mm": mid.values["sd_mm"],
        "sh_mm": mid.values["sh_mm"], "qr_mm": mid.values["qr_mm"],
        "extrapolated": mid.extrapolated, "reason": reason,
        "limits": {"sd_min_mm": limits.sd_min_mm, "sh_max_mm": limits.sh_max_mm,
                   "qr_min_mm": limits.qr_min_mm},
        "crossed_limits": crossed, "start_parameters_mm": params,
        "start_notes": list(start.notes),
        "wear_scale": dict(zip(("p10", "p50", "p90"), model.scales, strict=True))})
