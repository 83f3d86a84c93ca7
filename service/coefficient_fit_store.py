"""Wear-coefficient calibration (seed 000) as background jobs: validate, queue, run, read back.

A coefficient fit takes the measured wear of one wheel at one mileage (a wear curve given as
points, or a stored measurement whose profile is cleaned, aligned and reduced to its wear curve
against S1002), the vehicle and route of that wheel, and fits the coefficients of a wear law
with each requested method of :mod:`wearcast.statistics.coefficient_fit` (exact bounded least
squares, GA, PSO, TS, SA, DE): the Archard/KTH zone coefficients (``law = "archard_kth"``, the
default) or the tau_max law's c_tau with a given threshold tau_0 (``law = "tau_max"``). The
answer is seed 000's Table 2 for those methods (RMSE, maximum depth and its relative error, time,
loop runs), the law, the coefficients, which of them the data identifies, and the fitted wear
curve of the best method.

Storage reuses the ``simulations`` table (no migration): the job's spec carries
``kind = "coefficient_fit"``; :func:`wearcast.service.job_store.run_job` hands such rows to
:func:`run_coefficient_fit` (so recovery, cancel, time limit and the workers are shared) and
:mod:`wearcast.service.simulation_store` keeps them out of ``/v1/simulations``.
"""

from __future__ import annotations

import logging
from typing import Any, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.physics.vocabulary import Axle, BogieType, Side
from wearcast.physics.wear_distribution import Application
from wearcast.service import models_db as db
from wearcast.service.db import SessionFactory
from wearcast.service.errors import NotFound, Unprocessable, from_value_error
from wearcast.service.job_schemas import JobStatusOut
from wearcast.service.schema_base import FieldsError, Strict, exactly_one
from wearcast.service.simulation_schemas import SimulationClassIn, SmoothingIn
from wearcast.statistics.coefficient_fit import FIT_LAWS, FitMethod

log = logging.getLogger(__name__)

KIND = "coefficient_fit"
Zone = Literal[1, 2, 3, 4]
#: Default search box per zone (seed 000 §V for zones 1-3; zone 4 around the map mean 350e-4).
DEFAULT_BOUNDS = {1: (1e-4, 10e-4), 2: (30e-4, 40e-4), 3: (1e-4, 10e-4), 4: (300e-4, 400e-4)}
#: Fields that belong to one law only (a request for another law that sets them is refused).
ARCHARD_FIELDS = ("zones", "bounds", "start")
TAU_MAX_FIELDS = ("tau_threshold_mpa", "tau_coefficient_bounds", "tau_coefficient_start")


def _default_methods() -> list[FitMethod]:
    return ["exact"]


def _default_zones() -> list[Zone]:
    return [1, 2, 3]


class MeasuredWearIn(Strict):
    """A measured vertical wear curve w(y) [mm] on the wheel frame (docs/conventions.md)."""

    y_mm: list[float] = Field(min_length=5, max_length=5000)
    wear_mm: list[float] = Field(min_length=5, max_length=5000)

    @model_validator(mode="after")
    def _same_length(self) -> MeasuredWearIn:
        if len(self.y_mm) != len(self.wear_mm):
            raise FieldsError(["y_mm", "wear_mm"], "y_mm and wear_mm must have the same length")
        if any(b <= a for a, b in zip(self.y_mm, self.y_mm[1:], strict=False)):
            raise FieldsError(["y_mm"], "y_mm must be strictly increasing")
        if max(self.wear_mm) <= 0:
            raise FieldsError(["wear_mm"], "wear_mm holds no wear (its maximum must be > 0)")
        return self


class PredictIn(Strict):
    """Predict with the fitted coefficients at another mileage (and score it if measured)."""

    mileage_km: float = Field(gt=0, le=1e7)
    wear: MeasuredWearIn | None = None


class CoefficientFitIn(Strict):
    """``POST /v1/coefficient-fits``: fit a wear law's coefficients to one measured wear.

    ``archard_kth`` (default): the KTH zone coefficients in ``zones`` within ``bounds`` from
    ``start``. ``tau_max``: c_tau [mm/(m MPa)] within ``tau_coefficient_bounds`` from
    ``tau_coefficient_start``, threshold ``tau_threshold_mpa`` fixed.
    """

    name: str | None = Field(default=None, max_length=200)
    vehicle: str = Field(min_length=1, max_length=50, description="vehicle preset")
    bogie_type: BogieType = "trailer"
    route_id: int | str | None = None
    classes: list[SimulationClassIn] | None = Field(default=None, min_length=1, max_length=200)
    wear: MeasuredWearIn | None = None
    measurement_id: int | None = None
    mileage_km: float | None = Field(default=None, gt=0, le=1e7, description=(
        "mileage of the measured wear [km]; default the measurement's"))
    law: str = Field(default="archard_kth", description=(
        "wear law whose coefficients are fitted: archard_kth (KTH zones) or tau_max (c_tau)"))
    methods: list[FitMethod] = Field(default_factory=_default_methods, min_length=1,
                                      max_length=6)
    zones: list[Zone] = Field(default_factory=_default_zones, min_length=1, max_length=4,
                              description="fitted KTH zones")
    bounds: list[tuple[float, float]] | None = Field(default=None, description=(
        "(lower, upper) per fitted zone; default seed 000's ranges"))
    start: tuple[float, float, float, float] | None = Field(default=None, description=(
        "k1..k4 start and value of the zones not fitted; default seed 000's map means"))
    tau_threshold_mpa: float | None = Field(default=None, ge=0, le=1e4, description=(
        "tau_max only: threshold tau_0 [MPa], fixed (default 0)"))
    tau_coefficient_bounds: tuple[float, float] | None = Field(default=None, description=(
        "tau_max only: (lower, upper) of c_tau [mm/(m MPa)], 0 < lower < upper; "
        "default (1e-8, 1e-4)"))
    tau_coefficient_start: float | None = Field(default=None, gt=0, le=1.0, description=(
        "tau_max only: start of c_tau [mm/(m MPa)]; default the placeholder 1e-6"))
    step_km: float = Field(default=5000.0, gt=0, le=1e6)
    application: Application = "global"
    axle: Axle = 1
    side: Side = "right"
    smoothing: SmoothingIn | None = None
    contact_update_depth_mm: float = Field(default=0.0, ge=0, le=5)
    max_runs: int = Field(default=5, ge=2, le=20)
    rtol: float = Field(default=1e-3, gt=0, lt=1)
    seed: int = 0
    predict: PredictIn | None = None

    @field_validator("law")
    @classmethod
    def _fittable_law(cls, law: str) -> str:
        from wearcast.physics.wear_laws import LAW_NAMES

        if law not in LAW_NAMES:
            raise ValueError(f"unknown wear law {law!r}; known: {', '.join(LAW_NAMES)}")
        if law not in FIT_LAWS:
            raise ValueError(f"{law} has no coefficient to fit; fitted laws: "
                             f"{', '.join(FIT_LAWS)}")
        return law

    @field_validator("tau_coefficient_bounds")
    @classmethod
    def _positive_box(cls, box: tuple[float, float] | None) -> tuple[float, float] | None:
        if box is not None and not 0 < box[0] < box[1]:
            raise ValueError("c_tau bounds must satisfy 0 < lower < upper [mm/(m MPa)]")
        return box

    @model_validator(mode="after")
    def _consistent(self) -> CoefficientFitIn:
        exactly_one(self, "route_id", "classes")
        exactly_one(self, "wear", "measurement_id")
        if self.wear is not None and self.mileage_km is None:
            raise FieldsError(["mileage_km"], "mileage_km is required with wear")
        if len(set(self.methods)) != len(self.methods):
            raise FieldsError(["methods"], "methods must not repeat")
        if len(set(self.zones)) != len(self.zones):
            raise FieldsError(["zones"], "zones must not repeat")
        if (self.law == "archard_kth" and self.bounds is not None
                and len(self.bounds) != len(self.zones)):
            raise FieldsError(["bounds"], "bounds must give one (lower, upper) per zone")
        return self


class CoefficientFitOut(JobStatusOut):
    spec: dict[str, Any]
    result: dict[str, Any] | None = None


def _check_law_fields(body: CoefficientFitIn) -> None:
    """Refuse fields of another law than the requested one (422 naming the field)."""
    if body.law == "tau_max":
        for name in ARCHARD_FIELDS:
            if name in body.model_fields_set:
                raise Unprocessable(name, f"{name} belongs to law archard_kth (KTH zones); "
                                    "tau_max fits its one coefficient c_tau (use "
                                    "tau_coefficient_bounds, tau_coefficient_start)")
        if body.application != "global":
            raise Unprocessable("application", "the local application is defined for "
                                "archard_kth only (seed 002); use global with tau_max")
        return
    for name in TAU_MAX_FIELDS:
        if getattr(body, name) is not None:
            raise Unprocessable(name, f"{name} applies to law tau_max only, not {body.law}")


def _law_spec(body: CoefficientFitIn, spec: dict[str, Any]) -> None:
    """Keep in the stored spec only the chosen law's fields, with their defaults resolved."""
    from wearcast.statistics.coefficient_fit import TAU_MAX_BOUNDS, TAU_MAX_START

    drop = ARCHARD_FIELDS if body.law == "tau_max" else TAU_MAX_FIELDS
    for name in drop:
        spec.pop(name, None)
    if body.law == "tau_max":
        spec["tau_threshold_mpa"] = float(body.tau_threshold_mpa or 0.0)
        spec["tau_coefficient_bounds"] = list(body.tau_coefficient_bounds or TAU_MAX_BOUNDS[0])
        spec["tau_coefficient_start"] = float(body.tau_coefficient_start or TAU_MAX_START[0])


def _measured_wear(session: Session, body: CoefficientFitIn) -> tuple[list, list, float]:
    if body.wear is not None:
        assert body.mileage_km is not None
        return body.wear.y_mm, body.wear.wear_mm, float(body.mileage_km)
    from wearcast.service import measurement_store
    from wearcast.statistics.processing import process_profile

    assert body.measurement_id is not None
    m = measurement_store.get(session, body.measurement_id)
    if not m.y_mm:
        raise Unprocessable("measurement_id", f"measurement {m.id} has no profile points")
    if m.reference_fits is False:
        raise Unprocessable("measurement_id", f"measurement {m.id}'s shape does not fit its "
                            f"reference {m.reference_profile} (flagged at import); the wear "
                            "loop starts from S1002")
    datum = (m.placement or {}).get("alignment") == "datum"  # keep a MiniProf wheel's datum
    try:
        if m.y_mm is None or m.z_mm is None:
            raise ValueError("measurement_id: the measurement holds no profile points")
        processed = process_profile(m.y_mm, m.z_mm, alignment="datum" if datum else "free")
    except ValueError as exc:
        raise Unprocessable("measurement_id", f"measurement {m.id}: {exc}") from exc
    ok = np.isfinite(processed.wear_mm)
    y = processed.grid_y_mm[ok]
    w = processed.wear_mm[ok]
    if y.size < 5 or not np.max(w) > 0:
        raise Unprocessable("measurement_id", f"measurement {m.id} shows no wear to fit")
    mileage = float(body.mileage_km if body.mileage_km is not None else m.mileage_km)
    if not mileage > 0:
        raise Unprocessable("mileage_km", "the measurement's mileage must be > 0")
    return y.tolist(), w.tolist(), mileage


def problem_from_spec(spec: dict[str, Any]):
    """The :class:`~wearcast.statistics.coefficient_fit.CalibrationProblem` of a stored spec
    (ValueError phrased ``field: reason``)."""
    from wearcast.physics.vehicles import preset_names, vehicle_preset
    from wearcast.physics.wear_distribution import Smoothing
    from wearcast.physics.wear_loop import as_loop_classes
    from wearcast.statistics.coefficient_fit import SEED_000_MEAN_K, CalibrationProblem

    if spec["vehicle"] not in preset_names():
        raise ValueError(f"vehicle: unknown vehicle preset {spec['vehicle']!r}; known presets: "
                         f"{', '.join(preset_names())}")
    try:
        classes = as_loop_classes(spec["resolved_classes"])
    except ValueError as exc:
        raise ValueError(f"classes: {exc}") from exc
    law = spec.get("law", "archard_kth")
    if law == "tau_max":
        free: tuple[int, ...] = (0,)
        bounds = [spec["tau_coefficient_bounds"]]
        start: tuple[float, ...] = (float(spec["tau_coefficient_start"]),)
        bounds_field = "tau_coefficient_bounds"
    else:
        zones = [int(z) for z in spec["zones"]]
        free = tuple(z - 1 for z in zones)
        bounds = spec.get("bounds") or [DEFAULT_BOUNDS[z] for z in zones]
        start = tuple(spec.get("start") or SEED_000_MEAN_K)
        bounds_field = "bounds"
    smoothing = Smoothing()
    if spec.get("smoothing"):
        try:
            smoothing = Smoothing(**{k: v for k, v in spec["smoothing"].items()
                                     if v is not None})
        except ValueError as exc:
            raise ValueError(f"smoothing: {exc}") from exc
    measured = spec["resolved_wear"]
    try:
        return CalibrationProblem(
            vehicle=vehicle_preset(spec["vehicle"], spec.get("bogie_type", "trailer")),
            classes=classes, y_mm=np.asarray(measured["y_mm"], dtype=float),
            wear_mm=np.asarray(measured["wear_mm"], dtype=float),
            mileage_km=float(measured["mileage_km"]), step_km=float(spec["step_km"]),
            free=free, bounds=tuple((float(lo), float(hi)) for lo, hi in bounds), start=start,
            application=spec["application"], smoothing=smoothing, axle=int(spec["axle"]),
            side=spec["side"], contact_update_depth_mm=float(spec["contact_update_depth_mm"]),
            law=law, tau_threshold_mpa=float(spec.get("tau_threshold_mpa") or 0.0))
    except ValueError as exc:
        text = str(exc)
        field = bounds_field if "bound" in text else "body"
        raise ValueError(f"{field}: {text}") from exc


def create_fit(session: Session, body: CoefficientFitIn) -> db.Simulation:
    """Validate a request completely and store it as a queued job."""
    from wearcast.service.job_store import default_timeout, queue_job, resolve_classes

    _check_law_fields(body)
    y, w, mileage = _measured_wear(session, body)
    furthest_km = max(mileage, body.predict.mileage_km if body.predict is not None else 0.0)
    if body.step_km * 200 < furthest_km:
        raise Unprocessable("step_km", "more than 200 loop steps to reach the mileage; "
                            "use a larger step_km")
    spec = body.model_dump(mode="json")
    spec["kind"] = KIND
    _law_spec(body, spec)
    spec["resolved_classes"] = resolve_classes(session, body)  # type: ignore[arg-type]
    spec["resolved_wear"] = {"y_mm": y, "wear_mm": w, "mileage_km": mileage}
    try:
        problem_from_spec(spec)
    except ValueError as exc:
        raise from_value_error(exc) from exc
    return queue_job(session, body.name, spec, timeout_s=default_timeout())


def run_coefficient_fit(factory: SessionFactory, job_id: int, spec: dict[str, Any],
                        on_progress: Any = None, control: Any = None) -> None:
    """Run a claimed fit to the end; progress (per method) and result in its row; a cancel or
    a passed time limit ends it after the method running then."""
    from wearcast.service.job_store import JobControl, complete_job, set_job
    from wearcast.statistics.coefficient_fit_comparison import compare_methods

    control = control or JobControl(factory, job_id, None)
    methods = list(spec["methods"])
    set_job(factory, job_id, progress=0.0, message=f"fitting with {methods[0]}")

    def progress(done: int, total: int, method: str) -> None:
        nxt = f", next {methods[done]}" if done < total else ""
        control.progress(done / total, f"{done}/{total} methods done ({method}{nxt})")
        if on_progress is not None:
            on_progress(done, total, method)

    def compute() -> dict[str, Any]:
        problem = problem_from_spec(spec)
        predict = spec.get("predict") or {}
        pw = (predict.get("wear") or None)
        pw_on_y = None
        if pw is not None:
            pw_on_y = np.interp(problem.y_mm, pw["y_mm"], pw["wear_mm"])
        table, fits = compare_methods(
            problem, methods, predict_mileage_km=predict.get("mileage_km"),
            predict_wear_mm=pw_on_y, seed=int(spec.get("seed", 0)),
            max_runs=int(spec.get("max_runs", 5)), rtol=float(spec.get("rtol", 1e-3)))
        return result_payload(problem, table, fits)

    complete_job(factory, job_id, control, compute, kind="coefficient fit", logger=log)


def result_payload(problem: Any, table: Any, fits: dict[str, Any]) -> dict[str, Any]:
    """JSON result: the law, comparison table rows, best method, per-method coefficient vectors,
    the best method's fitted coefficients by name (``k1``.. or ``c_tau_mm_per_m_mpa``), which of
    them the data identifies, and the best fit's wear curve on the measured y. Archard/KTH also
    names its fitted and identifiable zones; tau_max its threshold tau_0 [MPa]."""
    best = min(fits, key=lambda m: fits[m].rmse_mm)
    fit = fits[best]
    names = [problem.coefficient_names[i] for i in problem.free]
    y = np.asarray(problem.y_mm, dtype=float)
    out: dict[str, Any] = {
        "law": problem.law,
        "table": table.to_dict(orient="records"),
        "best_method": best,
        "coefficients": {m: f.coefficients.tolist() for m, f in fits.items()},
        "fitted_coefficients": {n: float(fit.coefficients[i])
                                for n, i in zip(names, problem.free, strict=True)},
        "identifiable_coefficients": [n for n, ok in zip(names, fit.identifiable, strict=True)
                                      if ok],
    }
    if problem.law == "archard_kth":
        zones = [i + 1 for i in problem.free]
        out["fitted_zones"] = zones
        out["identifiable_zones"] = [z for z, ok in zip(zones, fit.identifiable, strict=True)
                                     if ok]
    else:
        out["tau_threshold_mpa"] = problem.tau_threshold_mpa
    return out | {
        "mileage_km": problem.mileage_km,
        "y_mm": y.tolist(),
        "measured_wear_mm": np.asarray(problem.wear_mm, dtype=float).tolist(),
        "fitted_wear_mm": np.interp(y, fit.simulation.y_mm,
                                    fit.simulation.wear_mm[-1]).tolist(),
    }


def _row(session: Session, job_id: int) -> db.Simulation:
    row = session.get(db.Simulation, job_id)
    if row is None or (row.spec or {}).get("kind") != KIND:
        raise NotFound("coefficient_fit_id", f"no coefficient fit with id {job_id}")
    return row


def get_fit(session: Session, job_id: int, with_result: bool = True) -> CoefficientFitOut:
    row = _row(session, job_id)
    result = row.result if with_result and row.status == "done" else None
    return CoefficientFitOut(id=row.id, name=row.name, status=row.status,  # type: ignore
                             progress=float(row.progress), message=row.message,
                             error=row.error, spec=row.spec, result=result)


def list_fits(session: Session, limit: int = 100) -> list[CoefficientFitOut]:
    rows = session.execute(select(db.Simulation.id, db.Simulation.spec)
                           .order_by(db.Simulation.id.desc())).all()
    ids = [i for i, spec in rows if (spec or {}).get("kind") == KIND][:limit]
    return [get_fit(session, i, with_result=False) for i in ids]


def submit(session: Session, runner: Any, body: CoefficientFitIn) -> CoefficientFitOut:
    """Validate, store as queued and hand to the app's job runner (429 naming
    ``job_quota_per_key`` when the key already holds its quota of jobs)."""
    runner.check_quota(session)
    row = create_fit(session, body)
    runner.submit(row.id)
    return CoefficientFitOut(id=row.id, name=row.name, status="queued", progress=0.0,
                             message="queued", spec=row.spec)
