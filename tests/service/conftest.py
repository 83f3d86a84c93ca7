"""Service test fixtures: the databases tests run on, a SQLite file and a throw-away database
on the local PostgreSQL (``WEARCAST_TEST_POSTGRES_URL``, default
``postgresql+psycopg://postgres@127.0.0.1:5432/test``; skipped, saying so, when unreachable).

A test that takes ``backend_url`` runs once on each.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from wearcast.service.db import scratch_database

DEFAULT_POSTGRES_URL = "postgresql+psycopg://postgres@127.0.0.1:5432/test"


def postgres_admin_url() -> str:
    url = os.environ.get("WEARCAST_TEST_POSTGRES_URL", DEFAULT_POSTGRES_URL)
    if url.startswith("postgresql://"):
        url = "postgresql+psycopg://" + url.removeprefix("postgresql://")
    return url


def fresh_postgres_database() -> Iterator[str]:
    """A new empty database on the test server (dropped afterwards), or a skip."""
    url = make_url(postgres_admin_url())
    admin = create_engine(url, isolation_level="AUTOCOMMIT",
                          connect_args={"connect_timeout": 3})
    try:
        with admin.connect() as connection:
            connection.execute(text("SELECT 1"))
    except Exception as exc:  # no server, no driver, no permission
        admin.dispose()
        pytest.skip(f"PostgreSQL not reachable at {url.render_as_string()}: {exc}")
    with scratch_database(admin, "wearcast_test") as database_url:
        yield database_url


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def backend_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """An empty database: SQLite in ``tmp_path``, or a fresh PostgreSQL database."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'wearcast.sqlite3'}"
        return
    yield from fresh_postgres_database()
