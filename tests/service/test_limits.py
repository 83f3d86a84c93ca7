"""Limits with clear answers (issue 14 §2, §3, §5): sizes, lines, columns, zip members, points,
ids, integers, NUL bytes, rate limits and ``Idempotency-Key`` reuse, on SQLite and
PostgreSQL. Every refusal is a 4xx naming the field or the limit, and writes nothing."""

from __future__ import annotations

import io
import time
import warnings
import zipfile
from pathlib import Path

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service import idempotency
from wearcast.service.app import create_app
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes

HEADER = b"wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm\n"


def _client(url: str, tmp_path: Path, **kw: object) -> TestClient:
    return TestClient(create_app(Settings(data_dir=tmp_path, database_url=url, **kw)))


def _import(client: TestClient, name: str, data: bytes, **kw: object):  # type: ignore[no-untyped-def]
    return client.post("/v1/measurements/import", files={"file": (name, data, "text/csv")},
                       **kw)  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def fleet_csv() -> bytes:
    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("L", twin_routes.metro_route(), running_mode="lead"),),
        mileages_km=(40_000, 90_000), mileage_jitter_km=0.0, rate_scatter=0.0,
        area_scatter=0.0, points_per_profile=120, seed=11))
    return fleet.profiles.to_csv(index=False).encode()


def _total(client: TestClient) -> int:
    return int(client.get("/v1/measurements").json()["total"])


def test_bad_uploads_are_refused_naming_the_limit(backend_url: str, tmp_path: Path) -> None:
    client = _client(backend_url, tmp_path, max_zip_members=50)
    cases: list[tuple[str, bytes, int, str]] = []
    wide = ",".join(f"c{i}" for i in range(1_000_000)).encode() + b"\n1\n"
    cases.append(("wide.csv", wide, 422, "max_columns"))
    cell = HEADER + b"W," + b"x" * 3_000_000 + b",motor,1,left,10,1,2\n"
    cases.append(("cell.csv", cell, 422, "max_line_bytes"))
    blank = io.BytesIO()
    with zipfile.ZipFile(blank, "w", zipfile.ZIP_DEFLATED) as archive:
        for i in range(1000):
            archive.writestr(f"m{i:04d}.csv", b"")
    cases.append(("blank.zip", blank.getvalue(), 422, "50"))  # the member limit
    crc = io.BytesIO()
    with zipfile.ZipFile(crc, "w", zipfile.ZIP_STORED) as archive:
        archive.writestr("a.csv", HEADER + b"W,V,motor,1,left,10,1,2\n" * 50)
    damaged = bytearray(crc.getvalue())
    damaged[damaged.find(b"W,V,motor") + 30] ^= 0xFF
    cases.append(("crc.zip", bytes(damaged), 422, "CRC"))
    long_id = HEADER + b"".join(b"W" * 300 + b",V,motor,1,left,10,%d,0\n" % i
                                for i in range(20))
    cases.append(("long.csv", long_id, 422, "max_id_length"))
    nul = HEADER + b"".join(b"W\x00,V,motor,1,left,10,%d,0\n" % i for i in range(20))
    cases.append(("nul.csv", nul, 422, "NUL"))
    for name, data, status, word in cases:
        started = time.perf_counter()
        r = _import(client, name, data)
        assert r.status_code == status and word in r.text, (name, r.status_code, r.text)
        assert r.headers["content-type"] == "application/problem+json"
        assert time.perf_counter() - started < 60, name  # refused early, not after a crawl
    assert _total(client) == 0


def test_size_points_and_integer_limits(backend_url: str, tmp_path: Path,
                                        fleet_csv: bytes) -> None:
    client = _client(backend_url, tmp_path, max_body_bytes=4096, max_upload_bytes=200_000,
                     max_points_per_profile=100)
    big = {"name": "x" * 10_000, "classes": []}
    r = client.post("/v1/routes", json=big)
    assert r.status_code == 413 and "max_body_bytes" in r.text
    r = _import(client, "big.csv", fleet_csv + b"#" * 300_000)
    assert r.status_code == 413 and "max_upload_bytes" in r.text
    r = _import(client, "fleet.csv", fleet_csv)  # 120 points per profile
    assert r.status_code == 422 and "max_points_per_profile" in r.text
    huge = 2**70
    for method, path, kw in (("GET", f"/v1/models/{huge}", {}),
                             ("GET", f"/v1/measurements/{huge}", {}),
                             ("GET", "/v1/measurements", {"params": {"limit": str(huge)}}),
                             ("GET", "/v1/measurements", {"params": {"batch_id": str(huge)}}),
                             ("POST", "/v1/measurements", {"json": {
                                 "wheel_id": "W", "vehicle_id": "V", "bogie_type": "motor",
                                 "axle": huge, "side": "left", "mileage_km": 10,
                                 "sd_mm": 30, "sh_mm": 28, "qr_mm": 10}}),
                             ("POST", "/v1/models/1/predict", {"json": {
                                 "route_id": "metro", "mileage_km": [1e300],
                                 "bogie_type": "trailer", "axle": 1, "side": "left"}}),
                             ("GET", "/v1/routes/a%00b", {})):
        r = client.request(method, path, **kw)  # type: ignore[arg-type]
        assert 400 <= r.status_code < 500, (path, r.status_code, r.text)
    r = client.post("/v1/simulations", json={"vehicle": "metro_b", "classes": [
        {"radius_m": None, "speed_kmh": 70, "share": 1}], "steps": {"count": huge}})
    assert r.status_code == 422 and "steps.count" in r.text and "64-bit" in r.text
    assert _total(client) == 0


def test_rate_limit_answers_429_with_retry_after(tmp_path: Path) -> None:
    client = _client(f"sqlite:///{tmp_path / 'w.db'}", tmp_path, rate_limit_per_second=0.5,
                     rate_limit_burst=3)
    answers = [client.get("/v1/routes").status_code for _ in range(5)]
    assert answers[:3] == [200, 200, 200] and answers[3] == 429
    r = client.get("/v1/routes")
    assert r.status_code == 429 and int(r.headers["retry-after"]) >= 1
    assert "rate_limit_per_second" in r.text
    assert client.get("/v1/health").status_code == 200  # not limited


def test_idempotency_key_reuse_and_in_flight(backend_url: str, tmp_path: Path,
                                            fleet_csv: bytes) -> None:
    client = _client(backend_url, tmp_path)
    key = {"Idempotency-Key": "import-1"}
    first = _import(client, "a.csv", fleet_csv, headers=key)
    assert first.status_code == 200 and first.json()["duplicate"] is False
    again = _import(client, "a.csv", fleet_csv, headers=key)
    assert again.json()["duplicate"] is True and again.json()["batch_id"] == \
        first.json()["batch_id"]
    other = _import(client, "b.csv", fleet_csv.replace(b"\n", b"\r\n"), headers=key)
    assert other.status_code == 422 and "Idempotency-Key" in other.text
    # a request under a key whose first request is still running: 409, nothing written
    with client.app.state.database.session_factory() as session:  # type: ignore[attr-defined]
        import hashlib

        file_sha = hashlib.sha256(fleet_csv.replace(b"\n", b"\n\n")).hexdigest()
        assert idempotency.claim(session, "import-2",
                                 hashlib.sha256(file_sha.encode()).hexdigest()) is None
    busy = _import(client, "c.csv", fleet_csv.replace(b"\n", b"\n\n"),
                   headers={"Idempotency-Key": "import-2"})
    assert busy.status_code == 409 and "Idempotency-Key" in busy.text
    assert "retry-after" in busy.headers
    assert _total(client) == first.json()["created"]
    # a failed import releases its key: the corrected request may use it
    bad = _import(client, "d.csv", HEADER + b"W,V,motor,9,left,10,1,2\n",
                  headers={"Idempotency-Key": "import-3"})
    assert bad.status_code == 422
    assert _import(client, "d.csv", HEADER + b"W,V,motor,9,left,10,1,2\n",
                   headers={"Idempotency-Key": "import-3"}).status_code == 422
