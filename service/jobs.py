"""Where jobs run: in-process worker threads (the embedded default) or separate Dramatiq
worker processes on a Redis broker (``WEARCAST_JOB_QUEUE=dramatiq``).

The database row is the job's truth (:mod:`wearcast.service.job_store`): a queued job is
claimed by exactly one worker, which keeps a heartbeat while it runs. :class:`JobRunner`
(one per app):

* ``embedded``: ``job_workers`` threads (default 2, so one long job does not hold back the
  next) take queued jobs in id order; submitting wakes one;
* ``dramatiq``: submitting sends the job's id to the broker; ``wearcast worker`` processes
  (:mod:`wearcast.service.job_queue`) claim and run it.

Recovery: at start, and then every :data:`SWEEP_S` seconds, running jobs whose heartbeat is
older than :data:`STALE_S` (their worker died: kill -9, a crash, a restart) are queued again to
run from the start, or failed after two interruptions
(:func:`wearcast.service.job_store.recover_stale`); queued jobs are (re)dispatched. The same
sweep discards import batches abandoned by a dead process
(:func:`wearcast.service.housekeeping.sweep_abandoned_imports`).
"""

from __future__ import annotations

import datetime as dt
import logging
import threading

from sqlalchemy.orm import Session

from wearcast.service import job_store
from wearcast.service.db import Database
from wearcast.service.db_outage import OutageLog
from wearcast.service.errors import ApiError
from wearcast.service.housekeeping import sweep_abandoned_imports
from wearcast.service.settings import Settings

log = logging.getLogger(__name__)
#: A running job whose heartbeat is older than this [s] has lost its worker.
STALE_S = 60.0
#: How often [s] a runner writes the heartbeat of its jobs and looks for lost ones.
SWEEP_S = 10.0


class JobRunner:
    """Runs the app's jobs (see the module docstring)."""

    def __init__(self, database: Database, settings: Settings) -> None:
        self.database = database
        self.factory = database.session_factory
        self.settings = settings
        self.mode = settings.job_queue
        self._wake = threading.Condition()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._running: set[int] = set()
        self._lock = threading.Lock()
        self._started = False

    # -- lifecycle ----------------------------------------------------------------------
    def start(self) -> None:
        """Start the workers (embedded) and the heartbeat/recovery sweep; idempotent."""
        with self._lock:
            if self._started:
                return
            self._started = True
            self._stop.clear()
            if self.mode == "embedded":
                for i in range(self.settings.job_workers):
                    thread = threading.Thread(target=self._work, name=f"wearcast-job-{i}",
                                              daemon=True)
                    thread.start()
                    self._threads.append(thread)
            sweeper = threading.Thread(target=self._sweep, name="wearcast-job-sweep",
                                       daemon=True)
            sweeper.start()
            self._threads.append(sweeper)

    def recover(self, all_running: bool = False, dispatch_all: bool = True) -> list[int]:
        """Queue again (or fail) jobs whose worker is gone; ``all_running`` when this process
        is the only one that runs jobs (a single embedded server at start). Returns the ids
        queued again; dispatches them (or every queued job, ``dispatch_all``)."""
        now = job_store.now_utc()
        stale_before = now if all_running else now - dt.timedelta(seconds=STALE_S)
        requeued = job_store.recover_stale(self.factory, stale_before)
        if self.mode == "dramatiq":
            for job_id in job_store.queued_ids(self.factory) if dispatch_all else requeued:
                self._send(job_id)
        else:
            self._notify()
        return requeued

    def shutdown(self) -> None:
        """Stop taking jobs; a job running in a thread ends at its next step as interrupted
        (it is queued again by the next start)."""
        self._stop.set()
        self._notify()

    # -- submitting ---------------------------------------------------------------------
    def check_quota(self, session: Session) -> None:
        """429 naming ``job_quota_per_key`` when the request's key holds its quota."""
        from wearcast.service.auth import current_principal

        principal = current_principal.get()
        if principal is None:
            return
        active = job_store.active_jobs(session, principal.key_id)
        quota = self.settings.job_quota_per_key
        if active >= quota:
            error = ApiError(429, "job", f"this key has {active} queued or running jobs "
                             f"(limit job_quota_per_key = {quota}); wait for one to end or "
                             "cancel one", limit="job_quota_per_key")
            error.headers = {"Retry-After": "30"}
            raise error

    def submit(self, job_id: int) -> None:
        if self.mode == "dramatiq":
            self._send(job_id)
            return
        self.start()
        self._notify()

    def _send(self, job_id: int) -> None:
        from wearcast.service.job_queue import enqueue

        enqueue(self.settings.broker_url, job_id)

    def _notify(self) -> None:
        with self._wake:
            self._wake.notify_all()

    # -- embedded workers ---------------------------------------------------------------
    def _next(self) -> int | None:
        for job_id in job_store.queued_ids(self.factory):
            if job_store.claim(self.factory, job_id):
                return job_id
        return None

    def _work(self) -> None:
        # polled every 2 s while idle: a warning about once a minute while the database is away
        outage = OutageLog(log, "job worker could not read the queue", every=30)
        while not self._stop.is_set():
            try:
                job_id = self._next()
                outage.succeeded()
            except Exception as exc:  # the database is away for a moment: try again later
                outage.failed(exc)
                job_id = None
            if job_id is None:
                with self._wake:
                    self._wake.wait(timeout=2.0)
                continue
            with self._lock:
                self._running.add(job_id)
            try:
                job_store.run_job(self.factory, job_id, claimed=True)
            except Exception:
                log.exception("job %s crashed its worker", job_id)
            finally:
                with self._lock:
                    self._running.discard(job_id)

    def _sweep(self) -> None:
        while not self._stop.wait(SWEEP_S):
            try:
                with self._lock:
                    running = list(self._running)
                for job_id in running:
                    job_store.set_job(self.factory, job_id, heartbeat_at=job_store.now_utc())
                self.recover(dispatch_all=False)
                sweep_abandoned_imports(self.factory)
            except Exception as exc:
                log.warning("job sweep failed: %s", exc)
