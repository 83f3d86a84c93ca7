"""OutageLog: a polling loop's database failures warned at the first and every N-th."""

from __future__ import annotations

import logging

import pytest

from wearcast.service.db_outage import OutageLog


def test_warns_at_the_first_and_every_nth_failure_and_starts_afresh(caplog) -> None:
    log = logging.getLogger("wearcast.test.outage")
    outage = OutageLog(log, "loop could not read the table", every=3)
    with caplog.at_level(logging.WARNING, logger=log.name):
        for _ in range(7):
            outage.failed(RuntimeError("database is away"))
        outage.succeeded()
        outage.failed(RuntimeError("away again"))
    assert [r.getMessage() for r in caplog.records] == [
        "loop could not read the table (1 times): database is away",
        "loop could not read the table (3 times): database is away",
        "loop could not read the table (6 times): database is away",
        "loop could not read the table (1 times): away again",
    ]


def test_every_must_be_positive() -> None:
    with pytest.raises(ValueError, match="every"):
        OutageLog(logging.getLogger("wearcast.test.outage"), "x", every=0)
