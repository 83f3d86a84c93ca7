"""Wear-loop simulations as background jobs: validate and queue, run with progress, read back.

The simulation is :func:`wearcast.physics.wear_loop.simulate_wear` (contact per curve class,
wear law, global or local application, adaptive or fixed steps; seeds 000, 002, 003, 004).
A request is validated completely before it is queued (preset, route, law, steps), so a bad
input is a 422 and never a failed job. The job row holds the status (``queued`` ->
``running`` -> ``done`` | ``failed``), the progress (0-1, written after every wheel step),
the error of a failed job and the result (``WearSimulation.to_dict()``).
"""

from __future__ import annotations

import datetime as dt
import logging
import math
import threading
import traceback
from concurrent.futures import Executor, ThreadPoolExecutor
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service import route_store
from wearcast.service.db import SessionFactory, transaction
from wearcast.service.errors import NotFound, Unprocessable, from_value_error
from wearcast.service.schemas import SimulationIn, SimulationOut

log = logging.getLogger(__name__)
#: Reason written on jobs that were running when the service stopped.
RESTART_REASON = "the service restarted while this simulation was running; submit it again"


def now_utc() -> dt.datetime:
    return dt.datetime.now(dt.UTC)


def resolve_classes(session: Session, body: SimulationIn) -> list[dict[str, Any]]:
    """The curve classes of the request: a stored route's classes or the given ones."""
    if body.route_id is not None:
        row = route_store.get_route(session, body.route_id, "route_id")
        return [{k: c.get(k) for k in ("radius_m", "cant_mm", "speed_kmh", "direction",
                                       "share")} | {"direction": c.get("direction") or "left"}
                for c in row.classes]
    return [c.model_dump() for c in body.classes or []]


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
    return {"vehicle": vehicle_preset(spec["vehicle"], spec.get("bogie_type", "trailer")),
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
    try:
        simulation_arguments(spec)
    except ValueError as exc:
        raise from_value_error(exc) from exc
    return queue_job(session, body.name, spec)


def queue_job(session: Session, name: str | None, spec: dict[str, Any]) -> db.Simulation:
    """Store a validated job (simulation or coefficient fit, told apart by its spec) as queued."""
    row = db.Simulation(name=name, spec=spec, status="queued", progress=0.0, message="queued")
    session.add(row)
    session.commit()
    return row


def set_job(factory: SessionFactory, sim_id: int, **values: Any) -> None:
    with transaction(factory) as session:
        session.execute(update(db.Simulation).where(db.Simulation.id == sim_id).values(**values))


def run_simulation(factory: SessionFactory, sim_id: int,
                   on_progress: Any = None) -> None:
    """Run a queued job to the end: status, progress and result (or error) in its row.

    Never raises for a failing simulation: the error is stored and the status is ``failed``.
    ``on_progress(done_steps, n_steps, mileage_km)`` is called after every wheel step too
    (the CLI's progress bar).
    """
    from wearcast.physics.wear_loop import simulate_wear

    with factory() as session:
        spec = session.scalar(select(db.Simulation.spec).where(db.Simulation.id == sim_id))
    if spec is None:
        return
    if spec.get("kind") == "coefficient_fit":  # seed 000 calibration jobs share the table
        from wearcast.service.coefficient_fit_store import run_coefficient_fit

        run_coefficient_fit(factory, sim_id, spec, on_progress)
        return
    set_job(factory, sim_id, status="running", started_at=now_utc(), progress=0.0,
         message="solving contacts")

    def progress(done: int, total: int, mileage_km: float) -> None:
        fraction = min(1.0, done / max(total, 1))
        set_job(factory, sim_id, progress=fraction,
             message=f"step {done}/{total}, {mileage_km:,.0f} km")
        if on_progress is not None:
            on_progress(done, total, mileage_km)

    try:
        result = simulate_wear(**simulation_arguments(spec), progress=progress)
        payload = finite_json(result.to_dict())
    except Exception as exc:  # the job reports any failure; it never kills the worker
        log.warning("simulation %s failed: %s", sim_id, traceback.format_exc())
        set_job(factory, sim_id, status="failed", finished_at=now_utc(),
             error=f"{type(exc).__name__}: {exc}", message="failed")
        return
    set_job(factory, sim_id, status="done", progress=1.0, finished_at=now_utc(), result=payload,
         message="done")


def finite_json(value: Any) -> Any:
    """JSON-safe copy: non-finite floats become None."""
    if isinstance(value, dict):
        return {str(k): finite_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite_json(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, str):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def get_simulation(session: Session, sim_id: int, with_result: bool = True) -> SimulationOut:
    row = session.get(db.Simulation, sim_id)
    if row is None or (row.spec or {}).get("kind") == "coefficient_fit":
        raise NotFound("simulation_id", f"no simulation with id {sim_id}")
    result = row.result if with_result and row.status == "done" else None
    return SimulationOut(id=row.id, name=row.name, status=row.status,  # type: ignore[arg-type]
                         progress=float(row.progress), message=row.message, error=row.error,
                         spec=row.spec, created_at=row.created_at, started_at=row.started_at,
                         finished_at=row.finished_at, result=result)


def list_simulations(session: Session, limit: int = 100) -> list[SimulationOut]:
    rows = session.execute(select(db.Simulation.id, db.Simulation.spec)
                           .order_by(db.Simulation.id.desc())).all()
    ids = [i for i, spec in rows if (spec or {}).get("kind") != "coefficient_fit"][:limit]
    return [get_simulation(session, i, with_result=False) for i in ids]


class SimulationRunner:
    """A small in-process executor for simulation jobs (one worker thread by default: the
    physics is CPU-bound and the machine is shared).

    On start it marks the jobs left ``running`` by a previous process ``failed`` (with
    :data:`RESTART_REASON`) and queues again the ones left ``queued``.
    """

    def __init__(self, factory: SessionFactory, workers: int = 1,
                 executor: Executor | None = None) -> None:
        self.factory = factory
        self._executor = executor or ThreadPoolExecutor(max_workers=workers,
                                                        thread_name_prefix="wearcast-sim")
        self._lock = threading.Lock()

    def recover(self) -> list[int]:
        """Fail interrupted jobs, requeue waiting ones; returns the requeued ids."""
        with transaction(self.factory) as session:
            session.execute(update(db.Simulation).where(db.Simulation.status == "running")
                            .values(status="failed", error=RESTART_REASON,
                                    message="failed", finished_at=now_utc()))
            queued = list(session.scalars(select(db.Simulation.id)
                                          .where(db.Simulation.status == "queued")
                                          .order_by(db.Simulation.id)))
        for sim_id in queued:
            self.submit(sim_id)
        return queued

    def submit(self, sim_id: int) -> None:
        with self._lock:
            self._executor.submit(run_simulation, self.factory, sim_id)

    def shutdown(self) -> None:
        self._executor.shutdown(wait=False, cancel_futures=True)


def submit(session: Session, runner: SimulationRunner, body: SimulationIn) -> SimulationOut:
    """Validate, store as queued and hand to the runner; the answer is the queued job."""
    row = create_simulation(session, body)
    runner.submit(row.id)
    return SimulationOut(id=row.id, name=row.name, status="queued", progress=0.0,
                         message="queued", spec=row.spec, created_at=row.created_at)


def unprocessable_law(body: SimulationIn) -> None:
    """Combinations the wear loop refuses, refused before queuing (none since every law has
    a local application on the FASTSIM grid)."""
    return None
