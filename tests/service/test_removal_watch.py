"""A model removed through one serving process is no longer answered by another (issue 14 §1:
admin deletes with ``serve --workers N``): each process polls the newest removal in the audit
trail (``service/removal_watch.py``) and forgets its cached models, routes and tables."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import warnings
from pathlib import Path

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
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes, twin_wear_table

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


def _serve(data_dir: Path) -> tuple[str, subprocess.Popen]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    env = {k: v for k, v in os.environ.items() if not k.startswith("WEARCAST_")}
    env.update(WEARCAST_DATA_DIR=str(data_dir), WEARCAST_API_KEY=KEY)
    process = subprocess.Popen(
        [sys.executable, "-m", "wearcast.service.cli", "serve", "--port", str(port)],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    return f"http://127.0.0.1:{port}/v1", process


def _wait_healthy(base: str, process: subprocess.Popen) -> None:
    deadline = time.monotonic() + 60
    while True:
        try:
            if httpx.get(f"{base}/health").status_code == 200:
                return
        except httpx.TransportError:
            pass
        assert process.poll() is None and time.monotonic() < deadline, "server did not start"
        time.sleep(0.2)


def test_a_model_deleted_through_one_server_is_gone_from_another_within_seconds(
        tmp_path: Path) -> None:
    app = create_app(Settings(data_dir=tmp_path, api_key=KEY))
    client = TestClient(app, headers={"Authorization": f"Bearer {KEY}"})
    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("P", twin_routes.metro_route(), running_mode="lead"),),
        mileages_km=(40_000, 90_000, 140_000), mileage_jitter_km=0.0, rate_scatter=0.0,
        area_scatter=0.0, points_per_profile=120, seed=3))
    client.post("/v1/measurements/import", files={"file": (
        "p.csv", fleet.profiles.to_csv(index=False).encode(), "text/csv")})
    client.post("/v1/routes", json=twin_routes.metro_route().to_json())
    table = client.post("/v1/wear-tables", files={"file": (
        "t.csv", twin_wear_table.synthetic_wear_table().to_csv(index=False).encode(),
        "text/csv")}).json()
    model = client.post("/v1/models", json={
        "name": "m", "measure": "tau_max", "running_mode": "lead",
        "wear_table_id": table["id"], "calibration": {"route_id": "metro", "filter": {}}})
    assert model.status_code == 201, model.text
    app.state.database.dispose()
    servers = [_serve(tmp_path), _serve(tmp_path)]  # two processes on one SQLite file
    headers = {"Authorization": f"Bearer {KEY}"}
    try:
        for base, process in servers:
            _wait_healthy(base, process)
        (first, _), (second, _) = servers
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
    finally:
        logs = []
        for _base, process in servers:
            process.terminate()
            logs.append(process.communicate(timeout=30)[1])
    assert all("Traceback" not in log for log in logs), logs


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
