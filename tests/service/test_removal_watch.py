"""A model removed through one serving process is no longer answered by another (issue 14 §1:
admin deletes with ``serve --workers N``): each process polls the newest removal in the audit
trail (``service/removal_watch.py``) and forgets its cached models, routes and tables."""

from __future__ import annotations

import time
import warnings
from pathlib import Path
from typing import Any

import httpx
import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service.app import create_app
from wearcast.service.db import Database
from wearcast.service.middleware import write_audit
from wearcast.service.removal_watch import CHECK_S, RemovalWatch
from wearcast.service.settings import Settings

KEY = "removal-watch-test-key-0123456789"
PREDICT = {"route_id": "metro", "mileage_km": [50_000], "bogie_type": "trailer", "axle": 1,
           "side": "left"}


def test_the_watch_clears_the_caches_once_per_new_removal_and_not_on_other_writes(
        backend_url: str, tmp_path: Path) -> None:
    database = Database(Settings(data_dir=tmp_path, database_url=backend_url))
    database.migrate()
    cleared: list[int] = []
    watch = RemovalWatch(database.session_factory, lambda: cleared.append(1))
    factory = database.session_factory
    try:
        assert watch.check() is False  # the first look only notes where the trail stands
        write_audit(factory, None, "create", "routes", "1", "POST", "/v1/routes", 201, None)
        assert watch.check() is False and cleared == []
        write_audit(factory, None, "delete", "models", "1", "DELETE", "/v1/admin/models/1",
                    200, {"row": {}})
        assert watch.check() is True and cleared == [1]
        assert watch.check() is False and cleared == [1]  # the same removal, seen already
        write_audit(factory, None, "supersede", "routes", "1", "POST",
                    "/v1/admin/routes/1/supersede", 200, {"row": {}})
        assert watch.check() is True and cleared == [1, 1]
    finally:
        database.dispose()


def test_a_model_deleted_through_one_server_is_gone_from_another_within_seconds(
        tmp_path: Path, calibrated_model: Any, serve: Any) -> None:
    app = create_app(Settings(data_dir=tmp_path, api_key=KEY))
    calibrated_model(TestClient(app, headers={"Authorization": f"Bearer {KEY}"}))
    app.state.database.dispose()
    # two processes on one SQLite file
    first, second = (serve(tmp_path, WEARCAST_API_KEY=KEY).base for _ in range(2))
    headers = {"Authorization": f"Bearer {KEY}"}
    for base in (first, second):  # both processes now hold the model in memory
        for _ in range(3):
            r = httpx.post(f"{base}/models/1/predict", json=PREDICT, headers=headers)
            assert r.status_code == 200, r.text
    assert httpx.delete(f"{first}/admin/models/1", headers=headers).status_code == 200
    assert httpx.post(f"{first}/models/1/predict", json=PREDICT,
                      headers=headers).status_code == 404
    deadline = time.monotonic() + 10 * CHECK_S + 5
    while True:  # the other process forgets it within about CHECK_S
        status = httpx.post(f"{second}/models/1/predict", json=PREDICT,
                            headers=headers).status_code
        if status == 404 or time.monotonic() > deadline:
            break
        time.sleep(0.1)
    assert status == 404


@pytest.mark.parametrize("period_s", [0.05])
def test_the_watch_thread_starts_and_stops(tmp_path: Path, period_s: float) -> None:
    database = Database(Settings(data_dir=tmp_path))
    database.migrate()
    cleared: list[int] = []
    watch = RemovalWatch(database.session_factory, lambda: cleared.append(1), period_s)
    watch.start()
    try:
        write_audit(database.session_factory, None, "delete", "routes", "1", "DELETE",
                    "/v1/admin/routes/1", 200, {"row": {}})
        deadline = time.monotonic() + 10
        while not cleared and time.monotonic() < deadline:
            time.sleep(0.02)
        assert cleared == [1]
    finally:
        watch.stop()
        database.dispose()
