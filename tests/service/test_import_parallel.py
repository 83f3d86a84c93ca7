"""Large imports process profiles in a worker pool: same rows, same errors, one transaction."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import func, select

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.service import import_pool, importing
from wearcast.service import models_db as db
from wearcast.service.db import Database
from wearcast.service.settings import Settings

N_PROFILES = import_pool.PARALLEL_MIN_PROFILES + 44  # one chunk large enough for the pool
HEADER = "wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm\n"


def _csv(n_profiles: int, bad_at: int | None = None) -> tuple[bytes, int]:
    """Worn S1002 profiles of 200 points; profile ``bad_at`` covers the tread only.

    Returns the file and the 1-based line of the bad profile's first row.
    """
    y = np.linspace(-70.0, 60.0, 200)
    lines, bad_line = [HEADER], 0
    for i in range(n_profiles):
        wear = 0.002 * (i % 50) * np.exp(-((y - 5.0) / 15.0) ** 2)
        z = s1002_height_mm(y) - wear
        yy, zz = (y, z)
        if i == bad_at:
            keep = y > -20.0  # no flange: the profile cannot be aligned or measured
            yy, zz = y[keep], z[keep]
            bad_line = sum(line.count("\n") for line in lines) + 1
        prefix = f"W{i:04d},V{i // 8},motor,{1 + i % 2},{'left' if i % 4 < 2 else 'right'},"
        prefix += f"{1000.0 * (i + 1):.1f},"
        lines.extend(f"{prefix}{a:.4f},{b:.4f}\n" for a, b in zip(yy, zz, strict=True))
    return "".join(lines).encode(), bad_line


def _import(tmp_path: Path, name: str, data: bytes, workers: str,
            monkeypatch: pytest.MonkeyPatch) -> tuple[Database, importing.ImportResult]:
    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", workers)
    settings = Settings(data_dir=tmp_path / name, database_url=None)
    database = Database(settings)
    database.migrate()
    with database.session_factory() as session:
        result = importing.import_upload(session, settings.raw_dir, io.BytesIO(data), "big.csv")
    return database, result


def _rows(database: Database) -> list[tuple]:
    m = db.Measurement
    with database.session_factory() as session:
        return [tuple(r) for r in session.execute(
            select(m.wheel_id, m.mileage_km, m.flange_area_mm2, m.tread_area_mm2, m.sd_mm,
                   m.sh_mm, m.qr_mm, m.rms_residual_mm, m.wear_mm).order_by(m.wheel_id))]


def test_pool_and_in_process_imports_store_the_same_rows(tmp_path, monkeypatch):
    data, _ = _csv(N_PROFILES)
    serial_db, serial = _import(tmp_path, "serial", data, "0", monkeypatch)
    pooled_db, pooled = _import(tmp_path, "pooled", data, "2", monkeypatch)
    assert serial.created == pooled.created == N_PROFILES
    # Same arithmetic in another process: the rows must be identical, not merely close.
    assert _rows(serial_db) == _rows(pooled_db)
    serial_db.dispose()
    pooled_db.dispose()


def test_an_unusable_profile_in_a_pooled_chunk_names_its_line_and_writes_nothing(
        tmp_path, monkeypatch):
    data, bad_line = _csv(N_PROFILES, bad_at=N_PROFILES - 3)
    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", "2")
    settings = Settings(data_dir=tmp_path / "bad", database_url=None)
    database = Database(settings)
    database.migrate()
    with database.session_factory() as session, pytest.raises(importing.ApiError) as caught:
        importing.import_upload(session, settings.raw_dir, io.BytesIO(data), "big.csv")
    item = caught.value.item()
    assert (item["file"], item["line"], item["field"]) == ("big.csv", bad_line, "z_mm")
    assert f"W{N_PROFILES - 3:04d}" in item["reason"]
    with database.session_factory() as session:
        assert session.scalar(select(func.count()).select_from(db.Measurement)) == 0
        assert session.scalar(select(func.count()).select_from(db.ImportBatch)) == 0
    database.dispose()


def test_discarding_the_pool_can_wait_for_its_workers(tmp_path, monkeypatch):
    data, _ = _csv(N_PROFILES)
    database, result = _import(tmp_path, "pooled", data, "2", monkeypatch)
    assert result.created == N_PROFILES
    pool = import_pool._POOL
    assert pool is not None
    processes = list(pool._processes.values())
    assert processes
    import_pool.discard_pool(wait=True)
    assert import_pool._POOL is None
    assert not any(p.is_alive() for p in processes)
    database.dispose()
