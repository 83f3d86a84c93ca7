"""Jobs on a distributed queue: Dramatiq with a Redis broker (``WEARCAST_JOB_QUEUE=dramatiq``,
``WEARCAST_BROKER_URL``, default ``redis://127.0.0.1:6379/0``).

The API process sends only the job's id (:func:`enqueue`); a worker process started with
``wearcast worker`` (which runs ``dramatiq wearcast.service.job_queue``) claims the job's row
and runs it with :func:`wearcast.service.job_store.run_job`, writing a heartbeat every
:data:`HEARTBEAT_S` seconds while it runs. The row is the truth: a message delivered twice
runs the job once (the claim is a conditional UPDATE), and a job whose worker died is queued
again by the API's recovery sweep (:class:`wearcast.service.jobs.JobRunner`).
"""

from __future__ import annotations

import logging
import os
import threading
from functools import cache
from typing import Any

import dramatiq
from dramatiq.brokers.redis import RedisBroker

log = logging.getLogger(__name__)
HEARTBEAT_S = 10.0
QUEUE_NAME = "wearcast-jobs"
#: A job's own time limit is enforced by the job (job_timeout_s); the broker's is a backstop.
BROKER_TIME_LIMIT_MS = 24 * 3600 * 1000


@cache
def _broker(url: str) -> RedisBroker:
    broker = RedisBroker(url=url)
    dramatiq.set_broker(broker)
    return broker


def _worker_database() -> Any:
    from wearcast.service.db import Database
    from wearcast.service.settings import Settings

    return Database(Settings())


@cache
def _database() -> Any:
    return _worker_database()


def run(job_id: int) -> None:
    """The worker's side: claim and run one job, with a heartbeat while it runs."""
    from wearcast.service import job_store

    factory = _database().session_factory
    if not job_store.claim(factory, job_id):
        log.info("job %s already taken or ended", job_id)
        return
    stop = threading.Event()

    def beat() -> None:
        while not stop.wait(HEARTBEAT_S):
            try:
                job_store.set_job(factory, job_id, heartbeat_at=job_store.now_utc())
            except Exception:
                log.exception("heartbeat of job %s failed", job_id)

    thread = threading.Thread(target=beat, daemon=True, name=f"wearcast-beat-{job_id}")
    thread.start()
    try:
        job_store.run_job(factory, job_id, claimed=True)
    finally:
        stop.set()


_BROKER_URL = os.environ.get("WEARCAST_BROKER_URL", "").strip() or "redis://127.0.0.1:6379/0"


@cache
def _actor(url: str) -> Any:
    """The job actor on the broker at ``url`` (workers declare it on WEARCAST_BROKER_URL)."""
    broker = _broker(url) if url == _BROKER_URL else RedisBroker(url=url)
    return dramatiq.actor(actor_name="wearcast_run_job", queue_name=QUEUE_NAME, max_retries=0,
                          time_limit=BROKER_TIME_LIMIT_MS, broker=broker)(run)


run_job_actor = _actor(_BROKER_URL)


def enqueue(broker_url: str, job_id: int) -> bool:
    """Send a job's id to the workers; False (logged) when the broker cannot be reached: the
    job stays queued in the database and is sent again by the next recovery."""
    try:
        _actor(broker_url).send(int(job_id))
    except Exception as exc:
        log.warning("broker unreachable, job %s stays queued: %s", job_id, exc)
        return False
    return True


def broker_reachable(url: str, timeout_s: float = 1.0) -> bool:
    import redis

    try:
        return bool(redis.Redis.from_url(url, socket_connect_timeout=timeout_s).ping())
    except Exception:
        return False
