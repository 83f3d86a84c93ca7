"""``POST /v1/wear-tables/jobs``: a curve-radius table built as a background job (issue 14:
table builds run as jobs with recovery, cancel, timeout and quota like every job)."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.service.conftest import sqlite_client, wait_for_job

BODY = {"name": "metro radii", "vehicle": "metro_b",
        "radii": [{"radius_m": 300, "cant_mm": 100}, {"radius_m": 1000, "cant_mm": 40}]}


def _wait(client: TestClient, job_id: int, timeout_s: float = 120.0) -> dict:
    return wait_for_job(client, f"/v1/jobs/{job_id}", timeout_s)


def test_a_table_build_job_stores_the_same_table_as_the_direct_build(tmp_path):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/wear-tables/jobs", json=BODY)
    assert r.status_code == 202, r.text
    queued = r.json()
    assert queued["kind"] == "wear_table" and queued["status"] in ("queued", "running", "done")
    job = _wait(client, queued["id"])
    assert job["status"] == "done", job
    table_id = job["result"]["wear_table_id"]
    stored = client.get(f"/v1/wear-tables/{table_id}").json()
    direct = client.post("/v1/wear-tables/compute", json={**BODY, "name": "direct"}).json()
    assert stored["n_rows"] == direct["n_rows"] == job["result"]["n_rows"]
    assert stored["sha256"] == direct["sha256"]  # the same rows, computed twice
    assert any(j["kind"] == "wear_table" for j in client.get("/v1/jobs").json())


def test_bad_table_jobs_are_refused_before_queuing(tmp_path):
    client = sqlite_client(tmp_path)
    for change, field in (({"vehicle": "tram_x"}, "vehicle"),
                          ({"radii": None, "route_id": "nowhere"}, "route_id"),
                          ({"measurement_id": 99}, "measurement_id"),
                          ({"rail_id": 7}, "rail_id")):
        r = client.post("/v1/wear-tables/jobs", json={**BODY, **change})
        assert 400 <= r.status_code < 500, (change, r.text)
        assert field in r.text, (change, r.text)
    assert client.get("/v1/jobs").json() == []  # nothing queued


def test_a_table_job_can_be_cancelled(tmp_path):
    client = sqlite_client(tmp_path)
    many = {**BODY, "radii": [{"radius_m": r, "cant_mm": 50} for r in range(200, 3000, 50)]}
    job = client.post("/v1/wear-tables/jobs", json=many).json()
    r = client.post(f"/v1/jobs/{job['id']}/cancel")
    assert r.status_code in (200, 409), r.text
    ended = _wait(client, job["id"])
    assert ended["status"] in ("cancelled", "done")  # done if it ended before the cancel
