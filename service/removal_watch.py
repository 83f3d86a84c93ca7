"""Cached copies of removed rows are forgotten by every serving process, not only by the one
that served the removal.

Models, routes and tables are kept in process memory (:mod:`wearcast.service.model_loading`
and the stores' caches) on the rule that a stored row never changes. An admin delete or
supersede (:mod:`wearcast.service.admin_store`) breaks that rule for one row; it writes an
audit record (action ``delete`` or ``supersede``) in the same transaction. Each serving process
polls the newest such record every :data:`CHECK_S` seconds in a thread of its own
(:class:`RemovalWatch`) and clears its caches when it changed, so a model removed through one
worker of ``serve --workers N`` is no longer answered by the others after about a second (SQLite
may even give the removed row's id to the next new row).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from sqlalchemy import func, select

from wearcast.service.db_outage import OutageLog
from wearcast.service.models_access import AuditRecord

log = logging.getLogger(__name__)

#: How often each serving process looks for a new removal [s].
CHECK_S = 1.0
REMOVALS = ("delete", "supersede")


def newest_removal(session: Any) -> int:
    """Id of the newest removal's audit record (0 when there is none)."""
    found = session.scalar(select(func.max(AuditRecord.id))
                           .where(AuditRecord.action.in_(REMOVALS)))
    session.rollback()
    return int(found or 0)


class RemovalWatch:
    """Clears this process's caches (``clear``) whenever a removal newer than the last one
    seen is stored, by any process. :meth:`check` does one look; :meth:`start` looks every
    ``period_s`` seconds in a daemon thread until :meth:`stop`."""

    def __init__(self, factory: Callable[[], Any], clear: Callable[[], None],
                 period_s: float = CHECK_S) -> None:
        self.factory = factory
        self.clear = clear
        self.period_s = period_s
        self.seen: int | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def check(self) -> bool:
        """Look once; True when the caches were cleared (a removal not seen before)."""
        with self.factory() as session:
            newest = newest_removal(session)
        changed = self.seen is not None and newest != self.seen
        self.seen = newest
        if changed:
            self.clear()
        return changed

    def _run(self) -> None:
        # a warning about once a minute (at CHECK_S = 1 s) while the database is away
        outage = OutageLog(log, "removal watch could not read the audit trail", every=60)
        while not self._stop.wait(self.period_s):
            try:
                self.check()
                outage.succeeded()
            except Exception as exc:  # the database is away for a moment: look again later
                outage.failed(exc)

    def start(self) -> None:
        if self._thread is not None:
            return
        try:
            self.check()
        except Exception as exc:
            log.warning("removal watch could not read the audit trail: %s", exc)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="wearcast-removal-watch",
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
