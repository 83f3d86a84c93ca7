"""What a start cleans up after a previous process that was killed or crashed: import batches
left pending (their measurements, never visible, and the wheels and vehicles only they used;
:func:`wearcast.service.pending_batches.discard_batch`), temporary upload files, raw files no
committed batch refers to, idempotency claims left in flight, and (at shutdown) the import
worker processes.

:func:`clean_after_restart` is run only by the one process that starts the service
(``create_app(migrate=True)``, i.e. ``wearcast serve``), when no import of this service can be
running; :func:`sweep_abandoned_imports` by every serving process, periodically.
"""

from __future__ import annotations

import datetime as dt
import logging
import shutil
from pathlib import Path

from sqlalchemy import select

from wearcast.service import models_db as db
from wearcast.service.db import SessionFactory

log = logging.getLogger(__name__)


def clean_after_restart(factory: SessionFactory, data_dir: Path) -> dict[str, int]:
    """Remove leftovers of interrupted imports; returns what was removed, by kind."""
    from wearcast.service.idempotency import release_stale
    from wearcast.service.pending_batches import discard_batch, incomplete_batch_ids

    removed = {"pending_batches": 0, "pending_measurements": 0, "temporary": 0,
               "orphan_raw": 0, "idempotency_claims": 0}
    with factory() as session:  # first: their raw files become orphans, removed below
        for batch_id in incomplete_batch_ids(session):
            removed["pending_measurements"] += discard_batch(session, batch_id)
            removed["pending_batches"] += 1
    raw_dir = data_dir / "raw"
    tmp_dir = data_dir / "tmp"
    if tmp_dir.is_dir():
        for path in tmp_dir.iterdir():
            if path.is_dir():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
            removed["temporary"] += 1
    if raw_dir.is_dir():
        with factory() as session:
            referenced = set(session.scalars(select(db.RawFile.storage_path)))
        for path in raw_dir.glob("*/*"):
            relative = f"{path.parent.name}/{path.name}"
            if path.name.startswith(".upload-"):
                path.unlink(missing_ok=True)
                removed["temporary"] += 1
            elif path.is_file() and relative not in referenced:
                path.unlink(missing_ok=True)  # written by an import that never committed
                removed["orphan_raw"] += 1
    with factory() as session:
        removed["idempotency_claims"] = release_stale(session)
    if any(removed.values()):
        log.info("cleaned up after the last run: %s", removed)
    return removed


def sweep_abandoned_imports(factory: SessionFactory, now: dt.datetime | None = None
                            ) -> int:
    """Discard the import batches left pending by a process that died while the service
    kept running (silent for ``pending_batches.STALE_S``) and those left half-discarded, and
    release the Idempotency-Key claims of such requests (``idempotency.release_abandoned``);
    run periodically by every serving process (:class:`wearcast.service.jobs.JobRunner`).
    Returns how many were discarded."""
    from wearcast.service.idempotency import release_abandoned
    from wearcast.service.pending_batches import STALE_S, discard_batch, incomplete_batch_ids

    now = now or dt.datetime.now(dt.UTC)
    silent_since = now - dt.timedelta(seconds=STALE_S)
    with factory() as session:
        stale = incomplete_batch_ids(session, silent_since)
        for batch_id in stale:
            removed = discard_batch(session, batch_id)
            log.warning("discarded import batch %s, abandoned by its import (%d "
                        "measurements, never visible)", batch_id, removed)
        released = release_abandoned(session, silent_since)
        if released:
            log.warning("released %d Idempotency-Key claims abandoned by their requests",
                        released)
    return len(stale)


def stop_import_workers() -> None:
    """Terminate the import pool's worker processes (at shutdown, e.g. on SIGTERM)."""
    from wearcast.service import import_pool

    pool = import_pool._POOL
    if pool is None:
        return
    processes = list((getattr(pool, "_processes", None) or {}).values())
    import_pool.discard_pool()
    for process in processes:
        if process.is_alive():
            process.terminate()
