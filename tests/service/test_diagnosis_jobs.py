"""A hybrid model's diagnosis as a background job (``Prefer: respond-async`` / ``wait=N``):
the job's result is the diagnosis the request answers directly (issue 14: diagnoses run as
jobs with recovery, cancel, timeout and quota)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_diagnose_api import _load  # noqa: E402

from tests.service.conftest import sqlite_client, wait_for_job


def test_a_diagnosis_job_answers_what_the_request_answers(tmp_path):
    client = sqlite_client(tmp_path)
    model_id = _load(client, "traction")
    direct = client.post(f"/v1/models/{model_id}/diagnose", json={"seed": 3}).json()
    r = client.post(f"/v1/models/{model_id}/diagnose", json={"seed": 3},
                    headers={"Prefer": "respond-async"})
    assert r.status_code == 202, r.text
    job = r.json()
    assert job["kind"] == "diagnosis" and r.headers["Location"] == f"/v1/jobs/{job['id']}"
    state = wait_for_job(client, f"/v1/jobs/{job['id']}", 120.0)
    assert state["status"] == "done", state
    assert state["result"]["verdict"] == direct["verdict"] == "traction"
    assert state["result"]["findings"][0]["gain"] == direct["findings"][0]["gain"]
    # waiting for it answers the diagnosis itself, with the job's id
    waited = client.post(f"/v1/models/{model_id}/diagnose", json={"seed": 3},
                         headers={"Prefer": "wait=120"})
    assert waited.status_code == 200, waited.text
    assert waited.json()["verdict"] == "traction" and waited.json()["job_id"] > job["id"]


def test_a_diagnosis_job_of_a_missing_model_is_a_404_and_queues_nothing(tmp_path):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/models/999/diagnose", json={}, headers={"Prefer": "respond-async"})
    assert r.status_code == 404 and "model_id" in r.text
    assert client.get("/v1/jobs").json() == []
