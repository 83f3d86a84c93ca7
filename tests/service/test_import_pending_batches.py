"""Imports in bounded write transactions (issue 14 §5): the measurements go in chunk by chunk
under a pending batch that no read sees, the batch is flipped to complete at the end, a
killed import leaves nothing visible and the next start removes it, another write completes
while a large import is half-way, and a repeated import creates nothing new — on SQLite and
on PostgreSQL."""

from __future__ import annotations

import datetime as dt
import io
import logging
import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from sqlalchemy import func, select

from wearcast.service import (
    admin_store,
    importing,
    measurement_store,
    pending_batches,
    route_store,
)
from wearcast.service import models_db as db
from wearcast.service.app import create_app
from wearcast.service.batch_visibility import INCLUDE_PENDING
from wearcast.service.db import Database
from wearcast.service.errors import ApiError, NotFound
from wearcast.service.housekeeping import sweep_abandoned_imports
from wearcast.service.import_staging import MAX_LOCK_PAUSE_S, WriteLockShare
from wearcast.service.measurement_schemas import MeasurementIn
from wearcast.service.route_schemas import RouteIn
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes

CHUNK = 8
ALL = {INCLUDE_PENDING: True}


@pytest.fixture(scope="module")
def upload() -> tuple[bytes, int]:
    """A long CSV of the fleet twin (2 vehicles, 8 mileages: 128 profiles) and its count."""
    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("P", twin_routes.metro_route(), vehicles=2, running_mode="lead"),),
        mileages_km=tuple(range(10_000, 90_000, 10_000)), mileage_jitter_km=0.0,
        rate_scatter=0.0, area_scatter=0.0, points_per_profile=80, seed=5))
    profiles = fleet.profiles
    return (profiles.to_csv(index=False).encode(),
            profiles.groupby(["wheel_id", "mileage_km"]).ngroups)


@pytest.fixture
def database(backend_url: str, tmp_path: Path) -> Any:
    settings = Settings(data_dir=tmp_path, database_url=backend_url)
    database = Database(settings)
    database.migrate()
    yield database
    database.dispose()


def _import(database: Database, data: bytes, name: str = "fleet.csv", **kw: Any
            ) -> importing.ImportResult:
    settings = database.settings
    with database.session_factory() as session:
        return importing.import_upload(session, settings.raw_dir, io.BytesIO(data), name,
                                       chunk_size=CHUNK, settings=settings, **kw)


def _counts(database: Database) -> dict[str, int]:
    """Rows as every read sees them, and as stored (pending batches included)."""
    with database.session_factory() as s:
        return {
            "visible": s.scalar(select(func.count()).select_from(db.Measurement)) or 0,
            "stored": s.scalar(select(func.count()).select_from(db.Measurement)
                               .execution_options(**ALL)) or 0,
            "pending_batches": s.scalar(select(func.count()).select_from(db.ImportBatch)
                                        .where(db.ImportBatch.status == "pending")) or 0,
            "batches": s.scalar(select(func.count()).select_from(db.ImportBatch)) or 0,
            "wheels": s.scalar(select(func.count()).select_from(db.Wheel)) or 0,
            "vehicles": s.scalar(select(func.count()).select_from(db.Vehicle)) or 0,
        }


class Pause:
    """A progress callback that stops the import after ``after`` chunks until released, and
    runs ``probe`` there (in the test's thread)."""

    def __init__(self, after: int) -> None:
        self.after, self.calls = after, 0
        self.reached, self.go_on = threading.Event(), threading.Event()

    def __call__(self, _n: int) -> None:
        self.calls += 1
        if self.calls == self.after:
            self.reached.set()
            assert self.go_on.wait(120), "the test never released the import"


def _in_background(database: Database, data: bytes, pause: Pause, **kw: Any
                   ) -> tuple[threading.Thread, dict[str, Any]]:
    out: dict[str, Any] = {}

    def run() -> None:
        try:
            out["result"] = _import(database, data, progress=pause, **kw)
        except BaseException as exc:  # reported by the test
            out["error"] = exc
            pause.reached.set()

    thread = threading.Thread(target=run)
    thread.start()
    assert pause.reached.wait(120), "the import never reached the pause"
    assert "error" not in out, out.get("error")
    return thread, out


@contextmanager
def _paused_import(database: Database, data: bytes, after: int) -> Iterator[dict[str, Any]]:
    """An import of ``data`` in a background thread, held after ``after`` chunks while the
    ``with`` body runs, then released and joined: its ``out`` ({"result": ...} or
    {"error": ...})."""
    pause = Pause(after=after)
    thread, out = _in_background(database, data, pause)
    try:
        yield out
    finally:
        pause.go_on.set()
        thread.join()


def test_a_pending_batch_is_invisible_to_every_read(database: Database,
                                                    upload: tuple[bytes, int]) -> None:
    data, n = upload
    with _paused_import(database, data, 3) as out:
        counts = _counts(database)
        # three chunks are stored, under a pending batch, and no read sees them
        assert counts["stored"] >= 2 * CHUNK and counts["pending_batches"] == 1
        assert counts["visible"] == 0
        with database.session_factory() as s:
            pending_id = s.scalar(select(db.Measurement.id).execution_options(**ALL))
            assert pending_id is not None
            assert measurement_store.page(s, {}, 100, 0) == (0, [])
            assert measurement_store.matching_ids(s, {"vehicle_id": "P-001"}) == []
            with pytest.raises(NotFound):
                measurement_store.get(s, pending_id)
            assert s.get(db.Measurement, pending_id) is None
            joined = s.scalar(select(func.count()).select_from(db.Wheel)
                              .join(db.Measurement, db.Measurement.wheel_id == db.Wheel.wheel_id))
            assert joined == 0
            # nor the wheels and vehicles the pending import registered (all of them new)
            assert counts["wheels"] == counts["vehicles"] == 0
            assert s.scalar(select(func.count()).select_from(db.Wheel)
                            .execution_options(**ALL)) >= 1
            stored_wheel = s.scalar(select(db.Wheel.wheel_id).execution_options(**ALL))
            assert s.get(db.Wheel, stored_wheel) is None
    assert "error" not in out, out.get("error")
    assert out["result"].created == n
    counts = _counts(database)
    assert counts["visible"] == counts["stored"] == n and counts["pending_batches"] == 0
    assert counts["wheels"] >= 1 and counts["vehicles"] >= 1  # shown with their batch


def test_wheels_a_pending_import_registered_are_shown_once_another_import_measures_them(
        database: Database, upload: tuple[bytes, int]) -> None:
    data, _n = upload
    frame = pd.read_csv(io.BytesIO(data))
    frame["mileage_km"] += 5.0  # the same wheels measured again, 5 km on: other content
    with _paused_import(database, data, 2) as out:
        assert _counts(database)["wheels"] == 0  # registered by the pending import only
        other = _import(database, frame.to_csv(index=False).encode(), name="again.csv")
        assert other.created > 0
        with database.session_factory() as s:
            registered = s.scalar(select(func.count()).select_from(db.Wheel)
                                  .execution_options(**ALL))
            shown = set(s.scalars(select(db.Wheel.wheel_id)))
            measured = set(s.scalars(select(db.Measurement.wheel_id).distinct()))
        # every wheel the complete import measured is shown, with its vehicle
        assert measured and measured <= shown and len(shown) <= registered
        assert _counts(database)["vehicles"] >= 1
    assert "error" not in out, out.get("error")
    assert _counts(database)["wheels"] == registered


def test_a_small_write_completes_while_a_large_import_is_half_way(
        database: Database, upload: tuple[bytes, int]) -> None:
    data, n = upload
    with _paused_import(database, data, 2) as out:
        # the import has written chunks and has not finished: the write lock is free
        with database.session_factory() as s:
            route = route_store.create_route(s, RouteIn(name="written-meanwhile", classes=[
                {"radius_m": None, "speed_kmh": 80, "share": 1.0}]))
            posted = measurement_store.create(s, MeasurementIn(
                wheel_id="X1", vehicle_id="XV", bogie_type="motor", axle=1, side="left",
                mileage_km=1000.0, sd_mm=30.0, sh_mm=28.0, qr_mm=10.0))
        counts = _counts(database)
        assert counts["pending_batches"] == 1 and counts["stored"] > counts["visible"] == 1
        assert "result" not in out
    assert "error" not in out, out.get("error")
    assert out["result"].created == n
    with database.session_factory() as s:
        assert route_store.find_route(s, route.id) is not None
        assert measurement_store.get(s, posted.id).wheel_id == "X1"
    assert _counts(database)["visible"] == n + 1


def test_writes_that_collide_with_a_running_import_are_refused_to_retry(
        database: Database, upload: tuple[bytes, int]) -> None:
    data, n = upload
    with _paused_import(database, data, 2) as out:
        with pytest.raises(ApiError) as same:  # the same content, while it is imported
            _import(database, data, "again.csv")
        assert same.value.status == 409 and same.value.headers.get("Retry-After")
        first = pd.read_csv(io.BytesIO(data), nrows=1).iloc[0]
        with pytest.raises(ApiError) as overlap:  # its first measurement, posted alone
            with database.session_factory() as s:
                measurement_store.create(s, MeasurementIn(
                    wheel_id=first.wheel_id, vehicle_id=first.vehicle_id,
                    bogie_type=first.bogie_type, axle=int(first.axle), side=first.side,
                    mileage_km=float(first.mileage_km), sd_mm=30.0, sh_mm=28.0, qr_mm=10.0))
        assert overlap.value.status == 409 and "being imported" in overlap.value.reason
        with database.session_factory() as s:  # an operator cannot delete it half-way
            batch_id = s.scalar(select(db.ImportBatch.id))
            with pytest.raises(ApiError) as removal:
                admin_store.remove(s, "batches", batch_id)
        assert removal.value.status == 409 and "being imported" in removal.value.reason
    assert out["result"].created == n


def test_an_import_given_up_as_abandoned_cannot_complete(
        database: Database, upload: tuple[bytes, int]) -> None:
    data, n = upload
    with _paused_import(database, data, 2) as out:
        with database.session_factory() as s:  # what the sweep does to a silent import
            batch_id = s.scalar(select(db.ImportBatch.id))
            assert pending_batches.discard_batch(s, batch_id) >= CHUNK
    assert isinstance(out.get("error"), ApiError) and out["error"].status == 409
    assert _counts(database) == {"visible": 0, "stored": 0, "pending_batches": 0,
                                 "batches": 0, "wheels": 0, "vehicles": 0}
    assert _import(database, data).created == n  # tried again, it is imported whole


def test_a_repeated_import_creates_nothing_new(database: Database,
                                               upload: tuple[bytes, int]) -> None:
    data, n = upload
    first = _import(database, data, idempotency_key="fleet-1")
    before = _counts(database)
    again = _import(database, data, "renamed.csv")
    keyed = _import(database, data, idempotency_key="fleet-1")
    assert first.created == n and not first.duplicate
    assert again.duplicate and keyed.duplicate
    assert again.batch_id == keyed.batch_id == first.batch_id
    assert again.created == keyed.created == 0
    assert _counts(database) == before


def test_a_failed_import_discards_everything_it_wrote(database: Database,
                                                      upload: tuple[bytes, int]) -> None:
    data, _ = upload
    lines = data.decode().splitlines()
    # the last line's z is not a number: found after all earlier chunks were inserted
    cells = lines[-1].split(",")
    header = lines[0].split(",")
    cells[header.index("z_mm")] = "not-a-number"
    broken = "\n".join(lines[:-1] + [",".join(cells)]).encode()
    with pytest.raises(ApiError) as caught:
        _import(database, broken)
    assert caught.value.status == 422 and caught.value.field == "z_mm"
    assert _counts(database) == {"visible": 0, "stored": 0, "pending_batches": 0,
                                 "batches": 0, "wheels": 0, "vehicles": 0}
    assert not [p for p in database.settings.raw_dir.rglob("*") if p.is_file()]


KILLED_IMPORT = """
import io, os, signal, sys
from pathlib import Path
from wearcast.service import importing
from wearcast.service.db import Database
from wearcast.service.settings import Settings

settings = Settings(data_dir=Path(sys.argv[1]), database_url=sys.argv[2])
database = Database(settings)
calls = []

def progress(_n):
    calls.append(1)
    if len(calls) == int(sys.argv[4]):
        os.kill(os.getpid(), signal.SIGKILL)

with database.session_factory() as session, open(sys.argv[3], "rb") as stream:
    importing.import_upload(session, settings.raw_dir, stream, "fleet.csv", chunk_size=8,
                            progress=progress, settings=settings, idempotency_key="fleet-key")
"""


@pytest.mark.parametrize("recovery", ["restart", "sweep"])
def test_a_killed_import_leaves_nothing_visible_and_is_removed_by_the_next_start_or_sweep(
        database: Database, upload: tuple[bytes, int], tmp_path: Path,
        caplog: pytest.LogCaptureFixture, recovery: str) -> None:
    data, n = upload
    csv = tmp_path / "fleet.csv"
    csv.write_bytes(data)
    killed = subprocess.run(
        [sys.executable, "-c", KILLED_IMPORT, str(database.settings.data_dir),
         database.settings.resolved_database_url, str(csv), "4"],
        capture_output=True, text=True, env=dict(os.environ, WEARCAST_IMPORT_WORKERS="0"),
        check=False)
    assert killed.returncode == -9, killed.stderr[-2000:]
    left = _counts(database)
    assert left["stored"] >= 3 * CHUNK and left["pending_batches"] == 1  # killed half-way
    assert left["visible"] == 0
    assert any(p.is_file() for p in database.settings.raw_dir.rglob("*"))
    if recovery == "restart":
        with caplog.at_level(logging.INFO, logger="wearcast.service.housekeeping"):
            create_app(database.settings, migrate=True)  # the start `wearcast serve` makes
        assert "'pending_batches': 1" in caplog.text
        assert f"'pending_measurements': {left['stored']}" in caplog.text
        assert not [p for p in database.settings.raw_dir.rglob("*") if p.is_file()]
    else:  # the service kept running (another worker of `serve --workers N`): its sweep
        factory = database.session_factory
        now = dt.datetime.now(dt.UTC)
        assert sweep_abandoned_imports(factory, now) == 0  # silent for seconds only
        with pytest.raises(ApiError) as in_flight:  # the dead request still holds its key
            _import(database, data, idempotency_key="fleet-key")
        assert in_flight.value.status == 409
        later = now + dt.timedelta(seconds=pending_batches.STALE_S + 1)
        assert sweep_abandoned_imports(factory, later) == 1
    assert _counts(database) == {"visible": 0, "stored": 0, "pending_batches": 0,
                                 "batches": 0, "wheels": 0, "vehicles": 0}
    # the same upload under the same key is imported whole (not answered as a duplicate of
    # the dead one, nor refused while the dead request's claim on the key is left)
    result = _import(database, data, idempotency_key="fleet-key")
    assert not result.duplicate and result.created == n


def test_an_import_leaves_the_sqlite_write_lock_free_about_as_long_as_it_held_it() -> None:
    now, slept = [100.0], []

    def sleep(seconds: float) -> None:
        slept.append(seconds)
        now[0] += seconds

    share = WriteLockShare(sqlite=True, clock=lambda: now[0], sleep=sleep)
    share.acquire()  # the first chunk does not wait
    now[0] += 0.040
    share.release()  # held 40 ms
    now[0] += 0.010
    share.acquire()  # free for 10 ms only: waits 30 ms more
    assert slept == pytest.approx([0.030])
    now[0] += 2.0
    share.release()  # held 2 s (a slow chunk on a loaded machine)
    share.acquire()  # waits at most MAX_LOCK_PAUSE_S
    assert slept[-1] == pytest.approx(MAX_LOCK_PAUSE_S)
    now[0] += 0.050
    share.release()
    now[0] += 1.0  # reading the next chunk took longer than the chunk held the lock
    share.acquire()
    assert len(slept) == 2
    other = WriteLockShare(sqlite=False, clock=lambda: now[0], sleep=sleep)
    other.acquire()
    other.release()
    other.acquire()  # PostgreSQL: row locks, no pause
    assert len(slept) == 2
