"""API keys, scopes, the audit trail, admin deletes/supersedes, CORS and cross-site writes
(issue 14 §1), on SQLite and PostgreSQL. These tests opt out of the test suite's default key
(``del client.headers["authorization"]``) to see what a client without one gets.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any

import httpx
import pytest
from sqlalchemy import select

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service.app import create_app
from wearcast.service.models_access import ApiKey
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes

ROUTE = {"name": "line", "classes": [
    {"radius_m": None, "speed_kmh": 80, "share": 0.7},
    {"radius_m": 400, "direction": "left", "cant_mm": 100, "speed_kmh": 70, "share": 0.3}]}


def _app(url: str, tmp_path: Path, **kw: object) -> object:
    return create_app(Settings(data_dir=tmp_path, database_url=url, **kw))


def _anonymous(app: object) -> TestClient:
    client = TestClient(app)  # type: ignore[arg-type]
    del client.headers["authorization"]
    return client


def _with_key(app: object, key: str) -> TestClient:
    return TestClient(app, headers={"Authorization": f"Bearer {key}"})  # type: ignore


def _fill(path: str) -> str:
    return re.sub(r"\{[^}]+\}", "1", path)


def test_no_route_but_health_answers_without_a_key(backend_url: str, tmp_path: Path) -> None:
    app = _app(backend_url, tmp_path)
    client = _anonymous(app)
    checked = 0
    for path, operations in app.openapi()["paths"].items():  # type: ignore[attr-defined]
        if path == "/v1/health":
            continue
        for method in operations:
            r = client.request(method.upper(), _fill(path), json={})
            assert r.status_code == 401, (method, path, r.status_code, r.text)
            assert "Authorization" in r.text and r.headers["www-authenticate"].startswith("Bearer")
            assert r.headers["content-type"] == "application/problem+json"
            checked += 1
    assert checked >= 25
    wrong = TestClient(app, headers={"Authorization": "Bearer wc_not-a-key"})
    assert wrong.post("/v1/routes", json=ROUTE).status_code == 401
    assert wrong.get("/v1/routes").status_code == 401
    assert client.get("/v1/health").status_code == 200  # open
    assert TestClient(app).get("/v1/routes").json() == []  # nothing was written


def test_scopes_revocation_and_keys_stored_hashed(backend_url: str, tmp_path: Path) -> None:
    app = _app(backend_url, tmp_path)
    admin = TestClient(app)
    keys = {}
    for scope in ("read", "write"):
        r = admin.post("/v1/admin/api-keys", json={"name": f"{scope}er", "scopes": [scope]})
        assert r.status_code == 201, r.text
        keys[scope] = r.json()["key"]
        assert r.json()["scopes"] == [scope]
    reader, writer = _with_key(app, keys["read"]), _with_key(app, keys["write"])
    assert reader.get("/v1/routes").status_code == 200
    refused = reader.post("/v1/routes", json=ROUTE)
    assert refused.status_code == 403 and "write" in refused.text
    assert writer.post("/v1/routes", json=ROUTE).status_code == 201
    assert writer.get("/v1/routes").status_code == 200  # write implies read
    assert writer.get("/v1/admin/api-keys").status_code == 403
    assert writer.delete("/v1/admin/routes/1").status_code == 403
    # only hashes are stored: no secret appears in the table or in the listing
    with app.state.database.session_factory() as session:  # type: ignore[attr-defined]
        stored = [(k.key_sha256, k.prefix) for k in session.scalars(select(ApiKey))]
    assert all(keys["write"] != digest and len(digest) == 64 for digest, _ in stored)
    listing = admin.get("/v1/admin/api-keys").text
    assert keys["write"] not in listing and keys["read"] not in listing
    writer_id = next(k["id"] for k in admin.get("/v1/admin/api-keys").json()
                     if k["name"] == "writeer")
    assert admin.delete(f"/v1/admin/api-keys/{writer_id}").status_code == 200
    assert writer.get("/v1/routes").status_code == 401  # revoked: at once in this process
    admin_id = next(k["id"] for k in admin.get("/v1/admin/api-keys").json()
                    if "admin" in k["scopes"])
    assert admin.delete(f"/v1/admin/api-keys/{admin_id}").status_code == 409  # the last one
    bad = admin.post("/v1/admin/api-keys", json={"name": "x", "scopes": ["root"]})
    assert bad.status_code == 422 and "scopes" in bad.text


def test_the_audit_trail_names_who_wrote_what_and_admin_deletes_keep_history(
        backend_url: str, tmp_path: Path) -> None:
    app = _app(backend_url, tmp_path)
    admin = TestClient(app)
    writer_key = admin.post("/v1/admin/api-keys",
                            json={"name": "depot-a", "scopes": ["write"]}).json()["key"]
    writer = _with_key(app, writer_key)
    route = writer.post("/v1/routes", json=ROUTE).json()
    second = writer.post("/v1/routes", json={**ROUTE, "name": "line-b"}).json()
    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("Q", twin_routes.metro_route(), running_mode="lead"),),
        mileages_km=(40_000, 90_000), mileage_jitter_km=0.0, rate_scatter=0.0,
        area_scatter=0.0, points_per_profile=120, seed=5))
    batch = writer.post("/v1/measurements/import", files={"file": (
        "q.csv", fleet.profiles.to_csv(index=False).encode(), "text/csv")}).json()
    audit = admin.get("/v1/admin/audit").json()
    mine = [(a["key_name"], a["action"], a["entity"], a["entity_id"]) for a in audit]
    assert ("depot-a", "create", "routes", str(route["id"])) in mine
    assert ("depot-a", "create", "measurements", str(batch["batch_id"])) in mine
    # supersede the first route by the second; delete the batch; the history stays
    r = admin.post(f"/v1/admin/routes/{route['id']}/supersede",
                   json={"by": second["id"], "reason": "renamed"})
    assert r.status_code == 200, r.text
    assert admin.get(f"/v1/routes/{route['id']}").status_code == 404
    r = admin.delete(f"/v1/admin/batches/{batch['batch_id']}", params={"reason": "test"})
    assert r.status_code == 200, r.text
    assert admin.get("/v1/measurements").json()["total"] == 0
    records = admin.get("/v1/admin/audit", params={"entity": "routes"}).json()
    superseded = next(a for a in records if a["action"] == "supersede")
    assert superseded["snapshot"]["row"]["name"] == "line"
    assert superseded["snapshot"]["superseded_by"] == second["id"]
    deleted = admin.get("/v1/admin/audit", params={"entity": "batches"}).json()[0]
    assert deleted["action"] == "delete" and len(deleted["snapshot"]["row"]["measurement_ids"]) == \
        batch["created"]
    assert deleted["snapshot"]["row"]["raw_files"][0]["sha256"]
    # the same upload can be imported again after the delete
    again = writer.post("/v1/measurements/import", files={"file": (
        "q.csv", fleet.profiles.to_csv(index=False).encode(), "text/csv")}).json()
    assert again["duplicate"] is False and again["created"] == batch["created"]
    assert admin.delete("/v1/admin/routes/999").status_code == 404
    assert admin.delete("/v1/admin/things/1").status_code == 422


def test_a_table_or_route_a_model_uses_cannot_be_deleted(tmp_path: Path,
                                                          calibrated_model: Any) -> None:
    app = _app(f"sqlite:///{tmp_path / 'w.db'}", tmp_path)
    client = TestClient(app)
    made = calibrated_model(client)
    route, table = made["route"], made["table"]
    for kind, entity_id in (("routes", route["id"]), ("wear-tables", table["id"]),
                            ("measurements", 1), ("batches", 1)):
        r = client.delete(f"/v1/admin/{kind}/{entity_id}")
        assert r.status_code == 409 and "model(s) 1" in r.text, r.text
    predict = {"route_id": "metro", "mileage_km": [50_000], "bogie_type": "trailer",
               "axle": 1, "side": "left"}
    assert client.post("/v1/models/1/predict", json=predict).status_code == 200
    assert client.delete("/v1/admin/models/1").status_code == 200
    # the model is gone for the hot path too (its cache is cleared)
    assert client.post("/v1/models/1/predict", json=predict).status_code == 404
    assert client.delete(f"/v1/admin/wear-tables/{table['id']}").status_code == 200


def test_cors_is_closed_and_cross_site_writes_are_refused(tmp_path: Path) -> None:
    app = _app(f"sqlite:///{tmp_path / 'w.db'}", tmp_path)
    client = TestClient(app)
    pre = client.options("/v1/routes", headers={
        "Origin": "https://evil.example", "Access-Control-Request-Method": "POST"})
    assert "access-control-allow-origin" not in pre.headers
    r = client.post("/v1/routes", json=ROUTE, headers={"Origin": "https://evil.example"})
    assert r.status_code == 403 and "Origin" in r.text
    form = client.post("/v1/measurements/import", headers={"Sec-Fetch-Site": "cross-site"},
                       files={"file": ("a.csv", b"x", "text/csv")})
    assert form.status_code == 403
    assert client.get("/v1/routes", headers={"Origin": "https://evil.example"}).status_code \
        == 200  # reading is not a cross-site write (and CORS keeps the answer from the page)
    allowed = TestClient(_app(f"sqlite:///{tmp_path / 'w2.db'}", tmp_path / "b",
                              cors_origins=["https://ops.example"]))
    pre = allowed.options("/v1/routes", headers={
        "Origin": "https://ops.example", "Access-Control-Request-Method": "POST",
        "Access-Control-Request-Headers": "authorization,content-type"})
    assert pre.headers["access-control-allow-origin"] == "https://ops.example"
    r = allowed.post("/v1/routes", json=ROUTE, headers={"Origin": "https://ops.example"})
    assert r.status_code == 201


def test_health_is_open_and_hides_the_database_error(tmp_path: Path) -> None:
    url = "postgresql+psycopg://someone:hunter2@127.0.0.1:9/secret_db_name?connect_timeout=1"
    app = create_app(Settings(data_dir=tmp_path, database_url=url), migrate=False)
    r = _anonymous(app).get("/v1/health")
    assert r.status_code == 503 and r.headers["content-type"] == "application/problem+json"
    for secret in ("hunter2", "secret_db_name", "127.0.0.1", "psycopg", ":9"):
        assert secret not in r.text


def test_the_first_start_creates_an_admin_key_and_prints_it_once(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.delenv("WEARCAST_API_KEY")
    app = create_app(Settings(data_dir=tmp_path))
    printed = capsys.readouterr().err
    key = re.search(r"(wc_[A-Za-z0-9_-]{40,})", printed).group(1)  # type: ignore[union-attr]
    create_app(Settings(data_dir=tmp_path))
    assert "wc_" not in capsys.readouterr().err  # only once
    assert _with_key(app, key).post("/v1/routes", json=ROUTE).status_code == 201
    assert _anonymous(app).post("/v1/routes", json=ROUTE).status_code == 401


def test_an_empty_api_key_variable_counts_as_unset(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """``WEARCAST_API_KEY=`` (set but empty, as a compose file or ``make run`` may pass it)
    starts the service like an unset variable: the first start creates and prints a key.
    The other optional settings set empty keep their defaults too."""
    monkeypatch.setenv("WEARCAST_API_KEY", "")
    for name in ("DATABASE_URL", "CORS_ORIGINS", "MAX_BODY_BYTES", "JOB_QUEUE",
                 "RATE_LIMIT_BURST", "BROKER_URL"):
        monkeypatch.setenv(f"WEARCAST_{name}", "")
    settings = Settings(data_dir=tmp_path)
    assert settings.api_key is None and settings.database_url is None
    defaults = Settings.model_fields
    assert settings.cors_origins == []
    assert settings.max_body_bytes == defaults["max_body_bytes"].default
    assert settings.rate_limit_burst == defaults["rate_limit_burst"].default
    assert settings.job_queue == "embedded" and settings.broker_url.startswith("redis://")
    assert Settings(data_dir=tmp_path, api_key="  ").api_key is None  # blank given directly
    app = create_app(settings)
    key = re.search(r"(wc_[A-Za-z0-9_-]{40,})", capsys.readouterr().err)
    assert key is not None
    assert _with_key(app, key.group(1)).post("/v1/routes", json=ROUTE).status_code == 201
    assert _anonymous(app).post("/v1/routes", json=ROUTE).status_code == 401


def test_the_real_server_accepts_no_write_without_a_key(real_server: Any) -> None:
    """``wearcast serve`` as an operator starts it (no WEARCAST_API_KEY, defaults)."""
    base = real_server.base
    for method, path, kw in (("POST", "/routes", {"json": ROUTE}),
                             ("POST", "/measurements/import",
                              {"files": {"file": ("a.csv", b"a,b\n1,2\n")}}),
                             ("POST", "/wear-tables", {"files": {"file": ("t.csv", b"x")}}),
                             ("POST", "/models", {"json": {}}),
                             ("POST", "/simulations", {"json": {}}),
                             ("DELETE", "/admin/routes/1", {}),
                             ("POST", "/admin/api-keys", {"json": {}})):
        r = httpx.request(method, base + path, **kw)  # type: ignore[arg-type]
        assert r.status_code == 401, (path, r.status_code, r.text)
    assert httpx.get(f"{base}/routes").status_code == 401
    log = real_server.stop()
    key = re.search(r"(wc_[A-Za-z0-9_-]{40,})", log)
    assert key is not None, log  # printed once on the first start
