"""Database engine, sessions and migrations.

SQLite (the default) runs in WAL mode with foreign keys enforced, both set on every new
connection; PostgreSQL is used when ``WEARCAST_DATABASE_URL`` names it. The schema is created
and changed only by the Alembic migrations in ``wearcast.migrations`` (configured here, in
code: there is no ``alembic.ini``).
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event, text
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session, sessionmaker

from wearcast.service import batch_visibility  # noqa: F401  (pending batches stay unseen)
from wearcast.service.settings import Settings

SessionFactory = sessionmaker[Session]


def _sqlite_pragmas(dbapi_connection: Any, _record: Any) -> None:
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.execute("PRAGMA busy_timeout=30000")
    cursor.close()


def make_engine(url: str) -> Engine:
    """An engine for ``url``; for SQLite the file's folder is created and pragmas are set."""
    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        if parsed.database and parsed.database != ":memory:":
            Path(parsed.database).parent.mkdir(parents=True, exist_ok=True)
        engine = create_engine(url, connect_args={"check_same_thread": False})
        event.listen(engine, "connect", _sqlite_pragmas)
        return engine
    return create_engine(url, pool_pre_ping=True)


def make_session_factory(engine: Engine) -> SessionFactory:
    """Sessions that keep loaded attributes after commit (routes read them afterwards)."""
    return sessionmaker(bind=engine, expire_on_commit=False)


@contextmanager
def transaction(factory: SessionFactory) -> Iterator[Session]:
    """One session, committed when the block ends normally and rolled back otherwise."""
    session = factory()
    try:
        yield session
        session.commit()
    except BaseException:
        session.rollback()
        raise
    finally:
        session.close()


def alembic_config(engine: Engine) -> Any:
    """Programmatic Alembic configuration bound to ``engine`` (no ``alembic.ini``)."""
    import sys

    from alembic.config import Config

    import wearcast.migrations

    # the current stdout, not the one alembic bound as its default when first imported (it
    # may be a closed stream, e.g. when that import ran under a CLI test runner)
    config = Config(stdout=sys.stdout)
    config.set_main_option("script_location", str(Path(wearcast.migrations.__file__).parent))
    config.set_main_option("sqlalchemy.url", engine.url.render_as_string(hide_password=False))
    config.attributes["engine"] = engine
    return config


def migrate(engine: Engine, revision: str = "head") -> None:
    """Bring the schema to ``revision`` (default the newest) with the Alembic migrations."""
    from alembic import command

    command.upgrade(alembic_config(engine), revision)


@contextmanager
def scratch_database(admin: Engine, prefix: str) -> Iterator[str]:
    """A new empty database ``{prefix}_{12 hex digits}`` on the server of ``admin`` (an
    AUTOCOMMIT engine), its URL yielded; dropped, and ``admin`` disposed, afterwards."""
    name = f"{prefix}_{uuid.uuid4().hex[:12]}"
    with admin.connect() as connection:
        connection.execute(text(f'CREATE DATABASE "{name}"'))
    try:
        yield admin.url.set(database=name).render_as_string(hide_password=False)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


class Database:
    """An engine and its session factory, built from settings."""

    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self.engine = make_engine(settings.resolved_database_url)
        self.session_factory = make_session_factory(self.engine)
        #: SQLite: an embedded file database (no server round trips)
        self.is_sqlite = self.engine.dialect.name == "sqlite"

    def migrate(self) -> None:
        migrate(self.engine)

    def dispose(self) -> None:
        self.engine.dispose()
