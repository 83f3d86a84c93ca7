"""The rows behind background jobs (simulations, coefficient fits): queue, claim, progress,
cancel, time limit, and the end of a job; shared by every kind of job.

A job is a ``simulations`` row (a coefficient fit's spec carries ``kind =
"coefficient_fit"``, the build and the diagnosis of a physics model ``physics_model`` and
``physics_diagnosis``; a simulation's spec has no ``kind``). Its status goes ``queued`` ->
``running`` -> ``done`` | ``failed`` | ``cancelled``. A worker *claims* a queued job with one
conditional UPDATE (so two workers, threads or processes, never run the same job), writes a
heartbeat with every progress step and, between steps, reads whether the job was cancelled
or passed its time limit (:class:`JobControl`). The kinds are run by :func:`run_job`, which
imports the module of each kind only when needed (no module of a kind imports another).
"""

from __future__ import annotations

import datetime as dt
import logging
import math
import traceback
from collections.abc import Callable
from typing import Any

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.db import SessionFactory, transaction
from wearcast.service.utc_time import as_utc, now_utc

log = logging.getLogger(__name__)
ACTIVE = ("queued", "running")
#: Reason written on jobs that were interrupted twice (a crash, a kill) and are not retried.
RESTART_REASON = ("the service stopped twice while this job was running; it is not retried: "
                  "submit it again")


class JobStopped(Exception):  # noqa: N818 (a signal, not an error of the job)
    """Raised inside a running job when it was cancelled or passed its time limit."""

    def __init__(self, status: str, reason: str) -> None:
        super().__init__(reason)
        self.status = status
        self.reason = reason


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


def resolve_classes(session: Session, body: Any) -> list[dict[str, Any]]:
    """The curve classes of a job request: a stored route's classes or the given ones."""
    from wearcast.service import route_store

    if body.route_id is not None:
        row = route_store.get_route(session, body.route_id, "route_id")
        return route_store.loop_classes(row.classes)
    return [c.model_dump() for c in body.classes or []]


def default_timeout() -> float | None:
    """The time limit of a job queued now (``job_timeout_s`` of the serving app)."""
    from wearcast.service.auth import current_settings

    settings = current_settings.get()
    return None if settings is None else settings.job_timeout_s


def queue_job(session: Session, name: str | None, spec: dict[str, Any],
              owner_key_id: int | None = None, timeout_s: float | None = None
              ) -> db.Simulation:
    """Store a validated job (simulation, coefficient fit or table build, told apart by its
    spec's ``kind``) as queued."""
    from wearcast.service.auth import current_principal

    principal = current_principal.get()
    if owner_key_id is None and principal is not None:
        owner_key_id = principal.key_id
    row = db.Simulation(name=name, spec=spec, status="queued", progress=0.0, message="queued",
                        owner_key_id=owner_key_id, timeout_s=timeout_s, attempts=0,
                        cancel_requested=False)
    session.add(row)
    session.commit()
    return row


def active_jobs(session: Session, owner_key_id: int) -> int:
    return int(session.scalar(select(func.count()).select_from(db.Simulation).where(
        db.Simulation.owner_key_id == owner_key_id, db.Simulation.status.in_(ACTIVE))) or 0)


def set_job(factory: SessionFactory, job_id: int, **values: Any) -> None:
    with transaction(factory) as session:
        session.execute(update(db.Simulation).where(db.Simulation.id == job_id).values(**values))


def claim(factory: SessionFactory, job_id: int) -> bool:
    """Mark a queued job running for this worker; False when another took it (or it ended)."""
    with transaction(factory) as session:
        done = session.execute(
            update(db.Simulation)
            .where(db.Simulation.id == job_id, db.Simulation.status == "queued")
            .values(status="running", started_at=now_utc(), heartbeat_at=now_utc(),
                    attempts=db.Simulation.attempts + 1, message="started"))
        return bool(done.rowcount)  # type: ignore[attr-defined]


def finish(factory: SessionFactory, job_id: int, status: str, **values: Any) -> None:
    """End a running job (only one still running: a cancelled one stays cancelled)."""
    with transaction(factory) as session:
        session.execute(update(db.Simulation)
                        .where(db.Simulation.id == job_id, db.Simulation.status == "running")
                        .values(status=status, finished_at=now_utc(), **values))


def complete_job(factory: SessionFactory, job_id: int, control: JobControl,
                 compute: Callable[[], Any], *, kind: str,
                 logger: logging.Logger | None = None) -> None:
    """Run a claimed job's computation and write how it ended; never raises for the job.

    ``compute()`` returns the job's result (made JSON-safe by :func:`finite_json`): the job is
    ``done`` with it. A cancel or a passed time limit (:class:`JobStopped`, checked first and at
    every progress step) ends it as the signal says; any other exception marks it ``failed``
    with the error, logged (on ``logger``) with its traceback as the ``kind`` named.
    """
    try:
        control.check()
        payload = finite_json(compute())
    except JobStopped as stop:
        finish(factory, job_id, stop.status, error=stop.reason, message=stop.reason)
        return
    except Exception as exc:  # the job reports any failure; it never kills the worker
        (logger or log).warning("%s %s failed: %s", kind, job_id, traceback.format_exc())
        finish(factory, job_id, "failed", error=f"{type(exc).__name__}: {exc}",
               message="failed")
        return
    finish(factory, job_id, "done", progress=1.0, result=payload, message="done")


class JobControl:
    """Progress, heartbeat, cancel and time limit of one running job.

    ``progress(fraction, message)`` writes both and raises :class:`JobStopped` when the job
    was cancelled (``cancelled``) or has run longer than its limit (``failed``).
    """

    def __init__(self, factory: SessionFactory, job_id: int, timeout_s: float | None) -> None:
        self.factory = factory
        self.job_id = job_id
        self.timeout_s = timeout_s
        self.started = now_utc()

    def check(self) -> None:
        with self.factory() as session:
            cancel = session.scalar(select(db.Simulation.cancel_requested)
                                    .where(db.Simulation.id == self.job_id))
        if cancel:
            raise JobStopped("cancelled", "cancelled on request")
        if self.timeout_s is not None:
            elapsed = (now_utc() - self.started).total_seconds()
            if elapsed > self.timeout_s:
                raise JobStopped("failed", f"timed out after {elapsed:,.0f} s (limit "
                                 f"job_timeout_s = {self.timeout_s:g})")

    def progress(self, fraction: float, message: str) -> None:
        set_job(self.factory, self.job_id, progress=min(1.0, max(0.0, fraction)),
                message=message[:500], heartbeat_at=now_utc())
        self.check()


def cancel(session: Session, job_id: int) -> db.Simulation | None:
    """Cancel a job: a queued one at once, a running one at its next step."""
    row = session.get(db.Simulation, job_id)
    if row is None:
        return None
    if row.status == "queued":
        session.execute(update(db.Simulation)
                        .where(db.Simulation.id == job_id, db.Simulation.status == "queued")
                        .values(status="cancelled", cancel_requested=True,
                                finished_at=now_utc(), message="cancelled on request"))
    elif row.status == "running":
        session.execute(update(db.Simulation).where(db.Simulation.id == job_id)
                        .values(cancel_requested=True, message="cancel requested"))
    session.commit()
    session.refresh(row)
    return row


def recover_stale(factory: SessionFactory, stale_before: dt.datetime,
                  max_attempts: int = 2) -> list[int]:
    """Jobs whose worker went silent (no heartbeat since ``stale_before``): queued again to
    run from the start, or failed with :data:`RESTART_REASON` after ``max_attempts``.
    Returns the ids queued again."""
    with transaction(factory) as session:
        rows = session.execute(select(db.Simulation.id, db.Simulation.attempts,
                                      db.Simulation.heartbeat_at, db.Simulation.started_at)
                               .where(db.Simulation.status == "running")).all()
        requeued = []
        for job_id, attempts, beat, started in rows:
            last = as_utc(beat) or as_utc(started)
            if last is not None and last > stale_before:
                continue
            if (attempts or 0) >= max_attempts:
                session.execute(update(db.Simulation).where(
                    db.Simulation.id == job_id, db.Simulation.status == "running").values(
                    status="failed", error=RESTART_REASON, message="failed",
                    finished_at=now_utc()))
            else:
                session.execute(update(db.Simulation).where(
                    db.Simulation.id == job_id, db.Simulation.status == "running").values(
                    status="queued", progress=0.0, started_at=None,
                    message="interrupted by a service stop; queued again"))
                requeued.append(job_id)
    return requeued


def queued_ids(factory: SessionFactory) -> list[int]:
    with factory() as session:
        return list(session.scalars(select(db.Simulation.id)
                                    .where(db.Simulation.status == "queued")
                                    .order_by(db.Simulation.id)))


def run_job(factory: SessionFactory, job_id: int, on_progress: Any = None,
            claimed: bool = False) -> None:
    """Claim a queued job and run it to its end (never raises for a failing job)."""
    if not claimed and not claim(factory, job_id):
        return
    with factory() as session:
        row = session.execute(select(db.Simulation.spec, db.Simulation.timeout_s)
                              .where(db.Simulation.id == job_id)).one_or_none()
    if row is None:
        return
    spec, timeout_s = row
    control = JobControl(factory, job_id, timeout_s)
    kind = (spec or {}).get("kind")
    if kind == "coefficient_fit":
        from wearcast.service.coefficient_fit_store import run_coefficient_fit

        run_coefficient_fit(factory, job_id, spec, on_progress, control=control)
    elif kind == "diagnosis":
        from wearcast.service.diagnosis_jobs import run_diagnosis_job

        run_diagnosis_job(factory, job_id, spec, on_progress, control=control)
    elif kind == "wear_table":
        from wearcast.service.wear_table_jobs import run_wear_table_job

        run_wear_table_job(factory, job_id, spec, on_progress, control=control)
    elif kind in ("physics_model", "physics_diagnosis"):
        from wearcast.service.physics_jobs import run_physics_job

        run_physics_job(factory, job_id, spec, control=control)
    else:
        from wearcast.service.simulation_store import run_claimed_simulation

        run_claimed_simulation(factory, job_id, spec, on_progress, control=control)
