"""Service test fixtures: the databases tests run on, a SQLite file and a throw-away database
on the local PostgreSQL (``WEARCAST_TEST_POSTGRES_URL``, default
``postgresql+psycopg://postgres@127.0.0.1:5432/test``; skipped, saying so, when unreachable).

A test that takes ``backend_url`` runs once on each.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from wearcast.service.app import create_app
from wearcast.service.db import scratch_database
from wearcast.service.jobs import JobRunner
from wearcast.service.settings import Settings

DEFAULT_POSTGRES_URL = "postgresql+psycopg://postgres@127.0.0.1:5432/test"


def sqlite_settings(tmp_path: Path) -> Settings:
    """A service on ``tmp_path`` with its SQLite database in the file ``w.db`` there."""
    return Settings(data_dir=tmp_path, database_url=f"sqlite:///{tmp_path / 'w.db'}")


def sqlite_client(tmp_path: Path) -> TestClient:
    """An in-process client of the app on ``sqlite_settings(tmp_path)``."""
    return TestClient(create_app(sqlite_settings(tmp_path)))


def wait_for_job(client: httpx.Client, url: str, timeout_s: float = 60.0,
                 until: tuple[str, ...] = ("done", "failed", "cancelled")) -> dict[str, Any]:
    """GET ``url`` (a job, simulation or fit) every 50 ms until its ``status`` is in
    ``until``: the last answer, with ``_seen_progress`` the ``progress`` of every answer
    (None where it has none); an AssertionError after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    seen = []
    while time.monotonic() < deadline:
        r = client.get(url)
        assert r.status_code == 200, r.text
        body: dict[str, Any] = r.json()
        seen.append(body.get("progress"))
        if body["status"] in until:
            body["_seen_progress"] = seen
            return body
        time.sleep(0.05)
    raise AssertionError(f"{url} did not end in {timeout_s} s")


def import_miniprof(client: Any, reference_dir: Path, name: str, manifest: str) -> Any:
    """``POST /v1/measurements/import`` of the reference MiniProf file ``name`` with the
    manifest CSV text ``manifest``: the response."""
    return client.post("/v1/measurements/import", files={
        "file": (name, (reference_dir / "miniprof" / name).read_bytes()),
        "manifest": ("manifest.csv", manifest.encode())})


_started_runners: list[JobRunner] = []
_runner_start = JobRunner.start


def _recording_start(runner: JobRunner) -> None:
    _started_runners.append(runner)
    _runner_start(runner)


def stop_runners_on(database_name: str, join_timeout_s: float = 5.0) -> None:
    """Shut down every job runner started on the database ``database_name`` (a client used
    without ``with`` never runs the app's shutdown, and ``submit`` starts the runner), waiting
    up to ``join_timeout_s`` in all for their threads: no job sweep outlives the PostgreSQL
    database it sweeps (a sweep on a dropped database logged "job sweep failed: ... does not
    exist" at the end of a run). Runners on other databases (a module's shared client) keep
    running."""
    deadline = time.monotonic() + join_timeout_s
    for runner in [r for r in _started_runners
                   if r.database.engine.url.database == database_name]:
        _started_runners.remove(runner)
        runner.shutdown()
        for thread in runner._threads:
            thread.join(timeout=max(0.0, deadline - time.monotonic()))


@pytest.fixture(autouse=True, scope="session")
def _runners_are_recorded() -> Iterator[None]:
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(JobRunner, "start", _recording_start)
        yield


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
        try:
            yield database_url
        finally:
            stop_runners_on(make_url(database_url).database or "")  # before the drop


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def backend_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """An empty database: SQLite in ``tmp_path``, or a fresh PostgreSQL database."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'wearcast.sqlite3'}"
        return
    yield from fresh_postgres_database()


@dataclass
class RealServer:
    """``wearcast serve`` in a child process, as an operator starts it (no WEARCAST_* variable
    but the data folder): the served API's base URL; ``stop()`` terminates it and returns its
    log (stderr)."""

    base: str
    process: subprocess.Popen
    stderr: str | None = None

    def stop(self) -> str:
        if self.stderr is None:
            self.process.terminate()
            _out, self.stderr = self.process.communicate(timeout=30)
        return self.stderr


def start_server(data_dir: Path, **env_vars: str) -> RealServer:
    """``wearcast serve`` on a free port with ``data_dir`` as its data folder (and the given
    ``WEARCAST_*`` variables, no others), once ``/v1/health`` answers."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    env = {k: v for k, v in os.environ.items() if not k.startswith("WEARCAST_")}
    env.update(env_vars, WEARCAST_DATA_DIR=str(data_dir))
    process = subprocess.Popen(
        [sys.executable, "-m", "wearcast.service.cli", "serve", "--port", str(port)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    server = RealServer(f"http://127.0.0.1:{port}/v1", process)
    deadline = time.monotonic() + 60
    while True:
        try:
            if httpx.get(f"{server.base}/health").status_code == 200:
                return server
        except httpx.TransportError:
            pass
        if process.poll() is not None or time.monotonic() > deadline:
            server.stop()
            raise AssertionError("server did not start")
        time.sleep(0.2)


@pytest.fixture
def real_server(tmp_path: Path) -> Iterator[RealServer]:
    """The real HTTP server on a free port with ``tmp_path`` as its data folder, once
    ``/v1/health`` answers."""
    server = start_server(tmp_path)
    try:
        yield server
    finally:
        server.stop()


def calibrate_on_metro(client: Any, profiles: Any, name: str,
                       calibration_filter: dict[str, Any]) -> dict[str, Any]:
    """Through ``client``: import ``profiles`` (a fleet-twin profiles frame), store the metro
    route and the synthetic curve-radius table, and calibrate the tau_max lead-mode model
    ``name`` on the metro route's measurements that ``calibration_filter`` selects; the
    route's, the table's and the model's answers."""
    from wearcast.statistics.generators import twin_routes, twin_wear_table

    imported = client.post("/v1/measurements/import", files={"file": (
        "fleet.csv", profiles.to_csv(index=False).encode(), "text/csv")})
    assert imported.status_code == 200, imported.text
    route = client.post("/v1/routes", json=twin_routes.metro_route().to_json())
    assert route.status_code == 201, route.text
    table = client.post("/v1/wear-tables", files={"file": (
        "t.csv", twin_wear_table.synthetic_wear_table().to_csv(index=False).encode(),
        "text/csv")}).json()
    model = client.post("/v1/models", json={
        "name": name, "measure": "tau_max", "running_mode": "lead",
        "wear_table_id": table["id"],
        "calibration": {"route_id": "metro", "filter": calibration_filter}})
    assert model.status_code == 201, model.text
    return {"route": route.json(), "table": table, "model": model.json()}


def _calibrated_model(client: Any) -> dict[str, Any]:
    """A small fleet-twin unit and a tau_max model calibrated on it (``calibrate_on_metro``)."""
    from wearcast.statistics.generators import fleet_twin as ft
    from wearcast.statistics.generators import twin_routes

    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("P", twin_routes.metro_route(), running_mode="lead"),),
        mileages_km=(40_000, 90_000, 140_000), mileage_jitter_km=0.0, rate_scatter=0.0,
        area_scatter=0.0, points_per_profile=120, seed=3))
    return calibrate_on_metro(client, fleet.profiles, "m", {})


@pytest.fixture
def calibrated_model() -> Callable[[Any], dict[str, Any]]:
    """``calibrated_model(client)``: a small unit imported, the metro route, a synthetic table
    and a tau_max model calibrated on them through ``client``."""
    return _calibrated_model


@pytest.fixture
def serve() -> Iterator[Callable[..., RealServer]]:
    """``serve(data_dir, **WEARCAST_vars)`` starts a real server; all are stopped after the
    test."""
    started: list[RealServer] = []

    def start(data_dir: Path, **env_vars: str) -> RealServer:
        started.append(start_server(data_dir, **env_vars))
        return started[-1]

    yield start
    for server in started:
        server.stop()
