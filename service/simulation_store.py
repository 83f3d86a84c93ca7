"""Wear-loop simulations as background jobs: validate and queue, run with progress, read back.

The simulation is :func:`wearcast.physics.wear_loop.simulate_wear` (contact per curve class,
wear law, global or local application, adaptive or fixed steps; seeds 000, 002, 003, 004).
A request is validated completely before it is queued (preset, route, law, steps), so a bad
input is a 422 and never a failed job. The job row holds the status (``queued`` ->
``running`` -> ``done`` | ``failed``), the progress (0-1, written after every wheel step),
the error of a failed job and the result (``WearSimulation.to_dict()``). Queueing, claiming,
cancel, time limit and recovery are :mod:`wearcast.service.job_store`'s and
:mod:`wearcast.service.jobs`'s.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.db import SessionFactory
from wearcast.service.errors import NotFound, from_value_error
from wearcast.service.job_store import (
    RESTART_REASON,
    JobControl,
    complete_job,
    default_timeout,
    finite_json,
    now_utc,
    queue_job,
    resolve_classes,
    run_job,
    set_job,
)
from wearcast.service.simulation_schemas import SimulationIn, SimulationOut

log = logging.getLogger(__name__)
__all__ = ["RESTART_REASON", "create_simulation", "finite_json", "get_simulation",
           "list_simulations", "now_utc", "queue_job", "resolve_classes", "run_simulation",
           "set_job", "submit"]


def simulation_arguments(spec: dict[str, Any]) -> dict[str, Any]:
    """Keyword arguments of ``simulate_wear`` from a stored spec (raises ValueError as the
    physics does, phrased ``field: reason``)."""
    from wearcast.physics.vehicles import preset_names, vehicle_preset
    from wearcast.physics.wear_distribution import Smoothing
    from wearcast.physics.wear_laws import WearLaw
    from wearcast.physics.wear_loop import WearSteps, as_loop_classes

    if spec["vehicle"] not in preset_names():
        raise ValueError(f"vehicle: unknown vehicle preset {spec['vehicle']!r}; known presets: "
                         f"{', '.join(preset_names())}")
    steps_in = spec.get("steps") or {}
    step_kwargs: dict[str, Any] = {"mode": steps_in.get("mode", "adaptive"),
                                   "n_steps": int(steps_in.get("count", 20))}
    for key in ("depth_per_step_mm", "step_km", "max_step_km", "contact_update_depth_mm"):
        if steps_in.get(key) is not None:
            step_kwargs[key] = float(steps_in[key])
    try:
        steps = WearSteps(**step_kwargs)
    except ValueError as exc:
        raise ValueError(f"steps: {exc}") from exc
    smoothing = None
    if spec.get("smoothing"):
        sm = {k: v for k, v in spec["smoothing"].items() if v is not None}
        try:
            smoothing = Smoothing(**sm)
        except ValueError as exc:
            raise ValueError(f"smoothing: {exc}") from exc
    try:
        classes = as_loop_classes(spec["resolved_classes"])
    except ValueError as exc:
        raise ValueError(f"classes: {exc}") from exc
    vehicle = vehicle_preset(spec["vehicle"], spec.get("bogie_type", "trailer"))
    from wearcast.service.rail_store import measured_rail_from_spec, with_rails

    vehicle = with_rails(vehicle, *(  # measured rails in place of the preset's nominal one
        measured_rail_from_spec(spec[key]) if spec.get(key) else None
        for key in ("resolved_rail", "resolved_high_rail", "resolved_low_rail")))
    initial = None
    if spec.get("resolved_wheel"):  # the wheel starts from a stored measurement
        resolved = spec["resolved_wheel"]
        initial = (np.asarray(resolved["y_mm"], float), np.asarray(resolved["z_mm"], float))
    return {"vehicle": vehicle, "initial_profile": initial,
            "route_classes": classes, "law": WearLaw(name=spec["law"]),
            "application": spec["application"], "steps": steps, "axle": int(spec["axle"]),
            "side": spec["side"], "smoothing": smoothing,
            "unbalanced_acceleration_m_s2": float(spec["unbalanced_acceleration_m_s2"]),
            "tangent_speed_kmh": float(spec["tangent_speed_kmh"]),
            "patch_width": spec.get("patch_width", "hertz")}


def create_simulation(session: Session, body: SimulationIn) -> db.Simulation:
    """Validate a request completely and store it as a queued job."""
    unprocessable_law(body)
    spec = body.model_dump(mode="json")
    spec["resolved_classes"] = resolve_classes(session, body)
    from wearcast.service.rail_store import RAIL_FIELDS, rail_spec, requested_rails

    requested_rails(session, body)  # 404 / 422 naming the field
    for field in RAIL_FIELDS:
        if getattr(body, field) is not None:
            key = "resolved_" + field.removesuffix("_id")
            spec[key] = rail_spec(session, getattr(body, field), field)
    from wearcast.service.measured_wheel_source import requested_wheel

    measured = requested_wheel(session, body)
    if measured is not None:
        wheel, info = measured
        y, z = wheel.on_grid()
        spec["resolved_wheel"] = {**info, "y_mm": y.tolist(), "z_mm": z.tolist()}
    try:
        simulation_arguments(spec)
    except ValueError as exc:
        raise from_value_error(exc) from exc
    return queue_job(session, body.name, spec, timeout_s=default_timeout())


def run_simulation(factory: SessionFactory, sim_id: int,
                   on_progress: Any = None) -> None:
    """Claim a queued job and run it to its end (the CLI's path; the service's runner calls
    :func:`wearcast.service.job_store.run_job`, which dispatches on the job's kind)."""
    run_job(factory, sim_id, on_progress)


def run_claimed_simulation(factory: SessionFactory, sim_id: int, spec: dict[str, Any],
                           on_progress: Any = None, control: JobControl | None = None) -> None:
    """Run a claimed simulation job: progress, result (or error) in its row.

    Never raises for a failing simulation: the error is stored and the status is ``failed``;
    a cancel or a passed time limit ends it at its next wheel step.
    ``on_progress(done_steps, n_steps, mileage_km)`` is called after every wheel step too
    (the CLI's progress bar).
    """
    from wearcast.physics.wear_loop import simulate_wear

    control = control or JobControl(factory, sim_id, None)
    set_job(factory, sim_id, progress=0.0, message="solving contacts")

    def progress(done: int, total: int, mileage_km: float) -> None:
        control.progress(done / max(total, 1), f"step {done}/{total}, {mileage_km:,.0f} km")
        if on_progress is not None:
            on_progress(done, total, mileage_km)

    complete_job(factory, sim_id, control,
                 lambda: simulate_wear(**simulation_arguments(spec), progress=progress).to_dict(),
                 kind="simulation", logger=log)


def get_simulation(session: Session, sim_id: int, with_result: bool = True) -> SimulationOut:
    row = session.get(db.Simulation, sim_id)
    if row is None or "kind" in (row.spec or {}):  # another kind of job
        raise NotFound("simulation_id", f"no simulation with id {sim_id}")
    result = row.result if with_result and row.status == "done" else None
    return SimulationOut(id=row.id, name=row.name, status=row.status,  # type: ignore[arg-type]
                         progress=float(row.progress), message=row.message, error=row.error,
                         spec=row.spec, created_at=row.created_at, started_at=row.started_at,
                         finished_at=row.finished_at, result=result)


def list_simulations(session: Session, limit: int = 100) -> list[SimulationOut]:
    rows = session.execute(select(db.Simulation.id, db.Simulation.spec)
                           .order_by(db.Simulation.id.desc())).all()
    ids = [i for i, spec in rows if "kind" not in (spec or {})][:limit]
    return [get_simulation(session, i, with_result=False) for i in ids]


def submit(session: Session, runner: Any, body: SimulationIn) -> SimulationOut:
    """Validate, store as queued and hand to the runner; the answer is the queued job
    (429 naming ``job_quota_per_key`` when the key already holds its quota of jobs)."""
    runner.check_quota(session)
    row = create_simulation(session, body)
    runner.submit(row.id)
    return SimulationOut(id=row.id, name=row.name, status="queued", progress=0.0,
                         message="queued", spec=row.spec, created_at=row.created_at)


def unprocessable_law(body: SimulationIn) -> None:
    """Combinations the wear loop refuses, refused before queuing (none since every law has
    a local application on the FASTSIM grid)."""
    return None
