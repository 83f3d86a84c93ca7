"""Storage: settings, SQLite pragmas, Alembic migrations as the only schema source."""

from __future__ import annotations

from pathlib import Path

import pytest
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import inspect, text

from wearcast.service.db import Database, alembic_config, make_engine, migrate
from wearcast.service.models_db import Base
from wearcast.service.settings import Settings

REPO = Path(__file__).resolve().parents[2]


def test_default_database_is_a_sqlite_file_in_the_data_dir(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch
                                                           ) -> None:
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path / "d"))
    settings = Settings()
    assert settings.resolved_database_url == f"sqlite:///{tmp_path / 'd' / 'wearcast.sqlite3'}"
    monkeypatch.setenv("WEARCAST_DATABASE_URL", "postgresql+psycopg://u@h/db")
    assert Settings().resolved_database_url == "postgresql+psycopg://u@h/db"


def test_sqlite_runs_in_wal_mode_with_foreign_keys(tmp_path: Path) -> None:
    engine = make_engine(f"sqlite:///{tmp_path / 'x' / 'w.sqlite3'}")
    with engine.connect() as connection:
        assert connection.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert connection.execute(text("PRAGMA foreign_keys")).scalar() == 1


def test_migrations_create_the_schema_and_leave_no_pending_diff(tmp_path: Path) -> None:
    database = Database(Settings(data_dir=tmp_path))
    assert inspect(database.engine).get_table_names() == []
    database.migrate()
    tables = set(inspect(database.engine).get_table_names())
    assert set(Base.metadata.tables) <= tables and "alembic_version" in tables
    head = ScriptDirectory.from_config(alembic_config(database.engine)).get_current_head()
    with database.engine.connect() as connection:
        assert connection.execute(text("SELECT version_num FROM alembic_version")).scalar() \
            == head
        # what `alembic check` does: autogenerate against the migrated DB finds nothing
        diff = compare_metadata(MigrationContext.configure(
            connection, opts={"compare_type": True}), Base.metadata)
    assert diff == []
    command.check(alembic_config(database.engine))  # `alembic check`: raises if a diff
    database.migrate()  # idempotent


def test_downgrade_to_base_and_back(tmp_path: Path) -> None:
    engine = make_engine(f"sqlite:///{tmp_path / 'w.sqlite3'}")
    migrate(engine)
    command.downgrade(alembic_config(engine), "base")
    assert set(inspect(engine).get_table_names()) <= {"alembic_version"}
    migrate(engine)
    assert "measurements" in inspect(engine).get_table_names()


def test_alembic_is_configured_in_code_only() -> None:
    assert not (REPO / "alembic.ini").exists()
    assert (REPO / "migrations" / "env.py").is_file()
