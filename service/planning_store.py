"""Maintenance planning in storage: fleets, vehicle attributes, fleet state, lathe plans.

The planning itself is :mod:`wearcast.statistics.maintenance`; this module reads the
measurements, the fleet's limits and the vehicles' mileage per day from storage, supplies the
calibrated model's forecast for wheels without a history since turning (the hybrid model's
first crossing of each limit alone, from the wheel's latest measured wear areas; seed 001
eq. 4), stores plans and writes them as CSV. Statistics errors ``"field: reason"`` become 422s.
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import math
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np
import pandas as pd
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import model_loading
from wearcast.service import models_db as db
from wearcast.service.errors import NotFound, Unprocessable, from_value_error
from wearcast.service.float32_blobs import from_f32
from wearcast.service.planning_schemas import FleetIn, PlanIn, VehicleIn
from wearcast.statistics import reprofiling as stat_reprofiling
from wearcast.statistics.maintenance.fleet_state import FleetState, Remaining, fleet_state
from wearcast.statistics.maintenance.lathe_plan import lathe_plan
from wearcast.statistics.maintenance.limits import FLANGE_LIMITS, FleetLimits
from wearcast.statistics.maintenance.plan_inputs import (
    diameter_groups,
    fleet_rates,
    plan_wheels,
    wheel_rates,
)
from wearcast.statistics.maintenance.turning import (
    TargetProfile,
    s1002_targets,
    turning_options,
    wheel_life,
)
from wearcast.statistics.profile_parameters import tape_circle_height_mm

M, W, V = db.Measurement, db.Wheel, db.Vehicle
#: Limits so far away that only the one under study can be crossed [mm].
_RELAXED = {"sd_min_mm": 1e-3, "sh_max_mm": 1e6, "qr_min_mm": 1e-3}


# --------------------------------------------------------------------------- fleets, vehicles


def _fleet_out(session: Session, row: db.Fleet) -> dict[str, Any]:
    vehicles = list(session.scalars(select(V.vehicle_id).where(V.fleet_id == row.fleet_id)
                                    .order_by(V.vehicle_id)))
    limits = FleetLimits.from_overrides(row.limits)
    return {"fleet_id": row.fleet_id, "limit_overrides": dict(row.limits or {}),
            "limits": limits.to_dict(), "vehicles": vehicles}


def put_fleet(session: Session, fleet_id: str, body: FleetIn) -> dict[str, Any]:
    """Create or replace a fleet's limit overrides and add the listed vehicles to it."""
    try:
        FleetLimits.from_overrides(body.limits)
    except ValueError as exc:
        raise from_value_error(exc) from exc
    row = session.get(db.Fleet, fleet_id)
    if row is None:
        row = db.Fleet(fleet_id=fleet_id, limits=dict(body.limits))
        session.add(row)
    else:
        row.limits = dict(body.limits)
    for vehicle_id in body.vehicles:
        vehicle = session.get(V, vehicle_id)
        if vehicle is None:
            session.rollback()
            raise Unprocessable("vehicles", f"no vehicle {vehicle_id!r} (import its "
                                "measurements first)")
        vehicle.fleet_id = fleet_id
    session.commit()
    return _fleet_out(session, row)


def get_fleet(session: Session, fleet_id: str) -> dict[str, Any]:
    row = session.get(db.Fleet, fleet_id)
    if row is None:
        raise NotFound("fleet_id", f"no fleet {fleet_id!r}")
    return _fleet_out(session, row)


def put_vehicle(session: Session, vehicle_id: str, body: VehicleIn) -> dict[str, Any]:
    vehicle = session.get(V, vehicle_id)
    if vehicle is None:
        raise NotFound("vehicle_id", f"no vehicle {vehicle_id!r}")
    if body.fleet_id is not None and session.get(db.Fleet, body.fleet_id) is None:
        raise Unprocessable("fleet_id", f"no fleet {body.fleet_id!r}")
    vehicle.km_per_day = body.km_per_day
    if body.fleet_id is not None:
        vehicle.fleet_id = body.fleet_id
    session.commit()
    return {"vehicle_id": vehicle.vehicle_id, "km_per_day": vehicle.km_per_day,
            "fleet_id": vehicle.fleet_id}


def fleet_limits(session: Session, fleet_id: str | None) -> FleetLimits:
    if fleet_id is None:
        return FleetLimits()
    row = session.get(db.Fleet, fleet_id)
    if row is None:
        raise NotFound("fleet_id", f"no fleet {fleet_id!r}")
    return FleetLimits.from_overrides(row.limits)


# --------------------------------------------------------------------------- fleet state

_COLUMNS = ["measurement_id", "wheel_id", "vehicle_id", "bogie_type", "axle", "side",
            "mileage_km", "measured_on", "kind", "sd_mm", "sh_mm", "qr_mm", "diameter_mm",
            "flange_area_mm2", "tread_area_mm2"]


def measurements_frame(session: Session, fleet_id: str | None,
                       vehicle_id: str | None = None) -> pd.DataFrame:
    """Every measurement of the fleet's vehicles (all vehicles without a fleet id), or of
    one of its vehicles."""
    query = (select(M.id, M.wheel_id, W.vehicle_id, W.bogie_type, W.axle, W.side,
                    M.mileage_km, M.measured_on, M.kind, M.sd_mm, M.sh_mm, M.qr_mm,
                    M.diameter_mm, M.flange_area_mm2, M.tread_area_mm2)
             .join(W, W.wheel_id == M.wheel_id).join(V, V.vehicle_id == W.vehicle_id))
    if fleet_id is not None:
        query = query.where(V.fleet_id == fleet_id)
    if vehicle_id is not None:
        query = query.where(W.vehicle_id == vehicle_id)
    rows = session.execute(query.order_by(M.wheel_id, M.mileage_km)).all()
    frame = pd.DataFrame([tuple(r) for r in rows], columns=_COLUMNS)
    for col in ("sd_mm", "sh_mm", "qr_mm", "diameter_mm", "flange_area_mm2",
                "tread_area_mm2"):
        frame[col] = pd.to_numeric(frame[col], errors="coerce").astype(float)
    return frame


def _model_forecast(session: Session, model_id: int, route_id: int | str | None,
                    frame: pd.DataFrame, limits: FleetLimits):
    """Remaining km per flange limit from a calibrated model, started at the wheel's
    latest measured wear areas (the wheel's latest profile measurement)."""
    if route_id is None:
        raise Unprocessable("route_id", "a model forecast needs the route it runs on")
    inputs, route = model_loading.load_inputs(session, model_id, route_id)
    profiles = frame[(frame["kind"] == "profile") & frame["flange_area_mm2"].notna()]
    latest = profiles.sort_values("mileage_km").groupby("wheel_id").tail(1) \
        .set_index("wheel_id")

    def forecast(state) -> dict[str, Remaining]:
        if state.wheel_id not in latest.index:
            return {}
        row = latest.loc[state.wheel_id]
        areas = {"flange": max(0.0, float(row["flange_area_mm2"])),
                 "tread": max(0.0, float(row["tread_area_mm2"]))}
        gone = state.mileage_km - float(row["mileage_km"])
        # the model's Sd/Sh/qR followed from the measured ones, as reprofiling from a
        # measured wheel does (statistics.reprofiling, "Starting from what was measured")
        measured = {k: float(row[k]) for k in ("sd_mm", "sh_mm", "qr_mm")
                    if k in row and row[k] is not None and math.isfinite(float(row[k]))}
        position = {"bogie_type": state.bogie_type, "axle": state.axle, "side": state.side}
        out = {}
        try:
            model = model_loading.wheel_model(inputs.model, route.route, inputs.table,
                                              covariates=dict(route.attributes), **position)
            measures = model_loading.weighted_measures(inputs, route.route, **position)
            for name in FLANGE_LIMITS:
                key = {"sd": "sd_min_mm", "sh": "sh_max_mm", "qr": "qr_min_mm"}[name]
                wanted = {**_RELAXED, key: limits.limit_of(name)}
                r = stat_reprofiling.reprofiling_mileage(
                    model, route.route, inputs.table, limits=wanted, start_areas=areas,
                    weighted_measures=measures, start_parameters=measured or None, **position)
                q = [max(v - gone, 0.0) if math.isfinite(v) else math.inf
                     for v in (r.mileage_p10_km, r.mileage_p50_km, r.mileage_p90_km)]
                out[name] = Remaining(q[0], q[1], q[2], "model",
                                      reason=f"model {model_id} from measurement at "
                                      f"{float(row['mileage_km']):g} km")
        except ValueError as exc:
            raise from_value_error(exc) from exc
        return out

    return forecast


def compute_state(session: Session, fleet_id: str | None, model_id: int | None = None,
                  route_id: int | str | None = None, vehicle_id: str | None = None
                  ) -> tuple[FleetState, pd.DataFrame]:
    """The fleet's state (or that of one of its vehicles) and the measurements behind it."""
    limits = fleet_limits(session, fleet_id)
    frame = measurements_frame(session, fleet_id, vehicle_id)
    query = select(V.vehicle_id, V.km_per_day)
    if fleet_id is not None:
        query = query.where(V.fleet_id == fleet_id)
    if vehicle_id is not None:
        query = query.where(V.vehicle_id == vehicle_id)
    km_per_day = {v: k for v, k in session.execute(query) if k is not None}
    forecast = None if model_id is None else _model_forecast(session, model_id, route_id,
                                                             frame, limits)
    if frame.empty:
        return FleetState([], [], limits), frame
    try:
        state = fleet_state(frame, limits, km_per_day, forecast)
    except ValueError as exc:
        raise from_value_error(exc) from exc
    return state, frame


def state_payload(session: Session, fleet_id: str | None, model_id: int | None = None,
                  route_id: int | str | None = None, today: dt.date | None = None
                  ) -> dict[str, Any]:
    state, _ = compute_state(session, fleet_id, model_id, route_id)
    out = state.to_dict(today or dt.date.today())
    out.update(fleet_id=fleet_id, today=(today or dt.date.today()).isoformat(),
               n_wheels=len(state.wheels))
    return out


STATE_CSV_COLUMNS = ["wheel_id", "vehicle_id", "bogie_type", "axle", "side", "mileage_km",
                     "measured_on", "sd_mm", "sh_mm", "qr_mm", "diameter_mm",
                     "remaining_p10_km", "remaining_p50_km", "remaining_p90_km",
                     "governing_limit", "date_p10", "urgency"]


def _csv_text(columns: list[str], rows: Iterable[list[Any]]) -> str:
    """CSV text (``\\n`` line ends) of a header row and the rows."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(rows)
    return buffer.getvalue()


def state_csv(payload: dict[str, Any]) -> str:
    def rows() -> Iterator[list[Any]]:
        for w in payload["wheels"]:
            gov = w["first_limit"]["governing_p10"]
            date = w["dates"][gov]["p10"] if gov else None
            yield [w["wheel_id"], w["vehicle_id"], w["bogie_type"], w["axle"], w["side"],
                   w["mileage_km"], w["measured_on"], w["sd_mm"], w["sh_mm"], w["qr_mm"],
                   w["diameter_mm"], w["first_limit"]["p10"], w["first_limit"]["p50"],
                   w["first_limit"]["p90"], gov, date, w["urgency"]]

    return _csv_text(STATE_CSV_COLUMNS, rows())


# --------------------------------------------------------------------------- one wheel


def _targets(thicknesses: list[float] | None = None) -> list[TargetProfile]:
    try:
        return s1002_targets(thicknesses) if thicknesses else s1002_targets()
    except ValueError as exc:
        raise Unprocessable("target_flange_thicknesses_mm", str(exc).partition(": ")[2]) \
            from exc


def _latest_profile(session: Session, wheel_id: str) -> db.Measurement | None:
    return session.scalar(select(M).where(M.wheel_id == wheel_id, M.kind == "profile",
                                          M.y_mm.is_not(None))
                          .order_by(M.mileage_km.desc()).limit(1))


def wheel_detail(session: Session, wheel_id: str, fleet_id: str | None = None,
                 model_id: int | None = None, route_id: int | str | None = None,
                 today: dt.date | None = None) -> dict[str, Any]:
    """History, state, forecast lines, latest profile over its reference, turning options."""
    row = session.get(W, wheel_id)
    if row is None:
        raise NotFound("wheel_id", f"no wheel {wheel_id!r}")
    # the wheel's vehicle is enough for its state (dates need only its vehicle's mileage)
    state, frame = compute_state(session, fleet_id, model_id, route_id, row.vehicle_id)
    wheel = next((w for w in state.wheels if w.wheel_id == wheel_id), None)
    if wheel is None:
        raise NotFound("wheel_id", f"wheel {wheel_id!r} is not in fleet {fleet_id!r}")
    mine = frame[frame["wheel_id"] == wheel_id].sort_values("mileage_km")
    history: list[dict[str, Any]] = []
    for r in mine.to_dict("records"):
        day = r["measured_on"]
        history.append({
            "measurement_id": int(r["measurement_id"]), "mileage_km": float(r["mileage_km"]),
            "measured_on": None if day is None or pd.isna(day) else day.isoformat(),
            **{c: None if pd.isna(r[c]) else float(r[c])
               for c in ("sd_mm", "sh_mm", "qr_mm", "diameter_mm")}})
    limits = state.limits
    forecast = {}
    for name in ("sd", "sh", "qr", "diameter"):
        rem = wheel.remaining[name]
        value = getattr(wheel, f"{name}_mm")
        if rem.source != "history" or value is None or rem.rate_mm_per_1000km is None:
            continue
        finite = [k for k in (rem.p10, rem.p50, rem.p90) if k is not None and math.isfinite(k)]
        span = 1.5 * max(finite) if finite else 100_000.0
        lines = {}
        for q in ("p10", "p50", "p90"):  # straight to the limit at the quantile's crossing
            km = getattr(rem, q)
            end = [wheel.mileage_km + km, limits.limit_of(name)] \
                if km is not None and math.isfinite(km) else [wheel.mileage_km + span, value]
            lines[q] = [[wheel.mileage_km, value], end]
        forecast[name] = {"limit_mm": limits.limit_of(name), "lines": lines}
    out: dict[str, Any] = {"wheel": wheel.to_dict(today or dt.date.today()),
                           "history": history, "forecast": forecast,
                           "limits": limits.to_dict(), "profile": None, "turning": None}
    latest = _latest_profile(session, wheel_id)
    if latest is not None:
        y, z = from_f32(latest.y_mm), from_f32(latest.z_mm)
        assert y is not None and z is not None
        order = np.argsort(y)
        y, z = y[order], z[order]
        z0 = tape_circle_height_mm(y, z)
        targets = _targets()
        grid = np.round(np.arange(max(y[0], -70.0), min(y[-1], 60.0), 0.5), 3)
        out["profile"] = {
            "measurement_id": latest.id, "mileage_km": latest.mileage_km,
            "reference_profile": latest.reference_profile,
            "y_mm": np.round(y, 4).tolist(), "z_mm": np.round(z - z0, 4).tolist(),
            "reference": {"y_mm": grid.tolist(),
                          **{t.name: np.round(t.heights(grid), 4).tolist()
                             for t in targets}}}
        own = all(wheel.remaining[n].source == "history"
                  and (wheel.remaining[n].rate_mm_per_1000km or 0.0) > 0
                  for n in (*FLANGE_LIMITS, "diameter"))
        # the fleet's median rates stand in for those the wheel's history cannot give
        fleet = state if own else compute_state(session, fleet_id)[0]
        rates = wheel_rates(wheel, fleet_rates(fleet))
        try:
            options = turning_options(y, z, targets, limits, rates, rates["diameter"])
        except ValueError as exc:
            out["turning"] = {"error": str(exc)}
        else:
            out["turning"] = _turning_payload(wheel, options, limits, rates)
    return out


def _turning_payload(wheel, options, limits: FleetLimits, rates: dict[str, float]
                     ) -> dict[str, Any]:
    from wearcast.statistics.maintenance.turning import economic_choice

    best, least = economic_choice(options)
    life = None
    if best is not None and wheel.diameter_mm is not None:
        p10, _ = wheel.first("p10")
        life = wheel_life(wheel.diameter_mm, limits.scrap_diameter_mm,
                          best.cut.diameter_loss_mm, best.km_to_next_limit,
                          rates["diameter"], p10 if p10 is not None else 0.0).to_dict()
    return {"options": [o.to_dict() for o in options],
            "economic": best.cut.target if best else None,
            "least_loss": least.cut.target if least else None,
            "rates_mm_per_1000km": {k: v * 1000.0 for k, v in rates.items()},
            "life": life}


# --------------------------------------------------------------------------- plans


def _latest_profiles(session: Session, wheel_ids: list[str]
                     ) -> dict[str, tuple[np.ndarray, np.ndarray, float]]:
    out = {}
    for wheel_id in wheel_ids:
        row = _latest_profile(session, wheel_id)
        if row is not None:
            y, z = from_f32(row.y_mm), from_f32(row.z_mm)
            if y is not None and z is not None:
                out[wheel_id] = (y, z, float(row.mileage_km))
    return out


def create_plan(session: Session, body: PlanIn) -> dict[str, Any]:
    state, _ = compute_state(session, body.fleet_id, body.model_id, body.route_id)
    targets = _targets(body.target_flange_thicknesses_mm)
    profiles = _latest_profiles(session, [w.wheel_id for w in state.wheels])
    wheels, unplanned = plan_wheels(state, profiles, targets)
    start = body.start or dt.date.today()
    extra = {f"{k.split('/')[0]}/{k.split('/')[1]}/{k.split('/')[2]}":
             f"axle diameter difference {s.spread_mm:g} mm > {s.limit_mm:g} mm"
             for s in state.diameter_spreads if s.scope == "axle" for k in [s.key]}
    try:
        plan = lathe_plan(wheels, start=start, horizon_weeks=body.horizon_weeks,
                          capacity_per_week=body.capacity_per_week,
                          fixed_interval_km=body.fixed_interval_km,
                          scrap_diameter_mm=state.limits.scrap_diameter_mm,
                          new_diameter_mm=state.limits.new_diameter_mm, extra_due=extra,
                          groups=diameter_groups(state) if body.keep_diameter_differences
                          else ())
    except (ValueError, TypeError) as exc:
        raise from_value_error(ValueError(str(exc))) from exc
    result = plan.to_dict()
    result["unplanned"] = unplanned
    result["limits"] = state.limits.to_dict()
    row = db.Plan(fleet_id=body.fleet_id, spec=body.spec(), result=_jsonable(result))
    session.add(row)
    session.commit()
    return plan_out(row)


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, np.generic):
        return _jsonable(value.item())
    return value


def plan_out(row: db.Plan) -> dict[str, Any]:
    return {"id": row.id, "fleet_id": row.fleet_id, "spec": row.spec, **row.result}


def get_plan(session: Session, plan_id: int) -> dict[str, Any]:
    row = session.get(db.Plan, plan_id)
    if row is None:
        raise NotFound("plan_id", f"no plan with id {plan_id}")
    return plan_out(row)


def list_plans(session: Session) -> list[dict[str, Any]]:
    rows = session.execute(select(db.Plan.id, db.Plan.fleet_id, db.Plan.spec,
                                  db.Plan.created_at).order_by(db.Plan.id)).all()
    return [{"id": r[0], "fleet_id": r[1], "spec": r[2],
             "created_at": r[3].isoformat() if r[3] else None} for r in rows]


PLAN_CSV_COLUMNS = ["week", "turn_date", "wheelset", "wheel_id", "action", "target",
                    "diameter_loss_mm", "matching_loss_mm", "final_diameter_mm", "deadline",
                    "in_time", "at_risk", "reason"]


def plan_csv(plan: dict[str, Any]) -> str:
    """One row per wheel of every wheelset in the plan (turned or at risk)."""
    def rows() -> Iterator[list[Any]]:
        for ws in plan["wheelsets"]:
            if ws["week"] is None and not ws["at_risk"]:
                continue
            for wid in ws["wheel_ids"]:
                cut = ws["cuts"].get(wid, {})
                yield [ws["week"], ws["turn_date"], ws["wheelset"], wid, ws["action"],
                       cut.get("target"), cut.get("diameter_loss_mm"),
                       cut.get("matching_loss_mm"), ws["final_diameter_mm"], ws["deadline"],
                       ws["in_time"], ws["at_risk"], ws["reason"]]

    return _csv_text(PLAN_CSV_COLUMNS, rows())
