"""Writes that do not block each other (issue 14 §5): an import holds no write lock while it
reads and processes its upload, and concurrent imports sharing new vehicles all succeed
(upserts), on SQLite and PostgreSQL."""

from __future__ import annotations

import io
import sqlite3
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest
from sqlalchemy import func, select

from wearcast.service import importing
from wearcast.service import models_db as db
from wearcast.service.db import Database
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes


@pytest.fixture(scope="module")
def profiles() -> pd.DataFrame:
    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("C", twin_routes.metro_route(), vehicles=2, running_mode="lead"),),
        mileages_km=tuple(range(10_000, 90_000, 10_000)), mileage_jitter_km=0.0,
        rate_scatter=0.0, area_scatter=0.0, points_per_profile=80, seed=4))
    return fleet.profiles


def test_an_import_holds_no_write_lock_while_it_processes(tmp_path: Path,
                                                         profiles: pd.DataFrame) -> None:
    settings = Settings(data_dir=tmp_path)
    database = Database(settings)
    database.migrate()
    path = Path(settings.resolved_database_url.removeprefix("sqlite:///"))
    free_while_staging = []

    def progress(_n: int) -> None:
        # another writer takes SQLite's write lock at once (no waiting: timeout 0)
        other = sqlite3.connect(path, timeout=0)
        try:
            other.execute("BEGIN IMMEDIATE")
            other.execute("INSERT INTO vehicles (vehicle_id) VALUES (?)",
                          (f"other-{len(free_while_staging)}",))
            other.commit()
            free_while_staging.append(True)
        except sqlite3.OperationalError:
            free_while_staging.append(False)
        finally:
            other.close()

    data = profiles.to_csv(index=False).encode()
    with database.session_factory() as session:
        result = importing.import_upload(session, settings.raw_dir, io.BytesIO(data), "c.csv",
                                         chunk_size=16, progress=progress, settings=settings)
    assert len(free_while_staging) > 3 and all(free_while_staging)
    assert result.created == profiles.groupby(["wheel_id", "mileage_km"]).ngroups
    database.dispose()


def test_concurrent_imports_sharing_new_vehicles_all_succeed(backend_url: str, tmp_path: Path,
                                                             profiles: pd.DataFrame) -> None:
    settings = Settings(data_dir=tmp_path, database_url=backend_url)
    database = Database(settings)
    database.migrate()
    # eight uploads, one per mileage: every one brings the same new vehicles and wheels
    uploads = [g.to_csv(index=False).encode() for _, g in profiles.groupby("mileage_km")]
    assert len(uploads) == 8

    def run(i: int) -> importing.ImportResult:
        with database.session_factory() as session:
            return importing.import_upload(session, settings.raw_dir, io.BytesIO(uploads[i]),
                                           f"m{i}.csv", settings=settings)

    with ThreadPoolExecutor(8) as pool:
        results = list(pool.map(run, range(8)))
    assert all(not r.duplicate for r in results)
    with database.session_factory() as session:
        stored = session.scalar(select(func.count()).select_from(db.Measurement))
        wheels = session.scalar(select(func.count()).select_from(db.Wheel))
    assert stored == sum(r.created for r in results) == profiles.groupby(
        ["wheel_id", "mileage_km"]).ngroups
    assert wheels == profiles.wheel_id.nunique()
    database.dispose()
