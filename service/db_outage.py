"""A background loop's failures to reach the database, logged without flooding the log.

The embedded job worker (:mod:`wearcast.service.jobs`) and the removal watch
(:mod:`wearcast.service.removal_watch`) poll the database; when it is away for a moment they
keep polling. :class:`OutageLog` counts the consecutive failures of one loop and warns at the
first one and then once every ``every`` failures (about once a minute at the loop's period),
naming what could not be done and how many times; a success starts the count afresh.
"""

from __future__ import annotations

import logging


class OutageLog:
    """Consecutive failures of one polling loop (see the module docstring).

    Parameters
    ----------
    log : the logger to warn on
    what : what failed, e.g. ``"job worker could not read the queue"``
    every : warn again at every ``every``-th consecutive failure (>= 1)
    """

    def __init__(self, log: logging.Logger, what: str, every: int) -> None:
        if every < 1:
            raise ValueError("every: must be >= 1")
        self.log = log
        self.what = what
        self.every = every
        self.failures = 0

    def failed(self, exc: BaseException) -> None:
        """Count one failure; warn at the first and every ``every``-th."""
        self.failures += 1
        if self.failures == 1 or self.failures % self.every == 0:
            self.log.warning("%s (%d times): %s", self.what, self.failures, exc)

    def succeeded(self) -> None:
        """The database answered: the next failure is a first one again."""
        self.failures = 0
