"""``POST /v1/coefficient-fits``: seed 000's wear-coefficient calibration as a background job."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from tests.service.conftest import sqlite_client, wait_for_job
from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics.coefficient_fit_twin import make_twin

CLASSES = [{"radius_m": None, "speed_kmh": 70, "share": 0.6},
           {"radius_m": 1500, "speed_kmh": 70, "direction": "left", "share": 0.4}]
TRUE_K1 = 3e-4


@pytest.fixture(scope="module")
def twin():
    # Tangent + 1500 m: only KTH zone 1 occurs; 200 km in 100 km steps (twin of seed 000's
    # fit-at-one-mileage, predict-at-another; short so that the test is fast).
    classes = [CurveClass(c["radius_m"], 0.0, c["speed_kmh"], c.get("direction", "left"),
                          c["share"]) for c in CLASSES]
    return make_twin("metro_b", classes, (TRUE_K1, 35e-4, 5e-4, 350e-4), 200.0, 400.0, 100.0)




def _body(twin, **change):
    body = {"name": "twin", "vehicle": "metro_b", "classes": CLASSES,
            "wear": {"y_mm": twin.y_mm[::5].tolist(), "wear_mm": twin.wear_fit_mm[::5].tolist()},
            "mileage_km": 200.0, "step_km": 100.0, "methods": ["exact", "PSO"], "zones": [1],
            "predict": {"mileage_km": 400.0,
                        "wear": {"y_mm": twin.y_mm.tolist(),
                                 "wear_mm": twin.wear_predict_mm.tolist()}}}
    body.update(change)
    return body


def _wait(client: TestClient, job_id: int, timeout_s: float = 60.0) -> dict:
    return wait_for_job(client, f"/v1/coefficient-fits/{job_id}", timeout_s)


def test_fit_recovers_the_twin_coefficient_and_reports_the_table(tmp_path, twin):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/coefficient-fits", json=_body(twin))
    assert r.status_code == 202, r.text
    assert r.json()["status"] == "queued"
    body = _wait(client, r.json()["id"])
    assert body["status"] == "done", body
    assert body["_seen_progress"] == sorted(body["_seen_progress"])  # progress never goes back
    res = body["result"]
    # noise-free twin: the exact method returns the true k1 (zone 1 is the only zone met)
    assert res["coefficients"]["exact"][0] == pytest.approx(TRUE_K1, rel=1e-3)
    assert res["coefficients"]["PSO"][0] == pytest.approx(TRUE_K1, rel=2e-2)
    assert res["identifiable_zones"] == [1] and res["best_method"] in ("exact", "PSO")
    rows = {row["method"]: row for row in res["table"]}
    assert set(rows) == {"traditional_mean_k", "exact", "PSO"}
    assert rows["exact"]["rmse_mm"] < 1e-3 * max(res["measured_wear_mm"])
    assert rows["exact"]["rmse_mm"] <= rows["traditional_mean_k"]["rmse_mm"]
    # and it predicts the wear at 400 km it never saw
    assert rows["exact"]["rmse_predict_mm"] < 1e-3 * twin.wear_predict_mm.max()
    # fit jobs are not simulations and vice versa
    assert client.get(f"/v1/simulations/{body['id']}").status_code == 404
    assert client.get("/v1/simulations").json() == []
    assert [f["id"] for f in client.get("/v1/coefficient-fits").json()] == [body["id"]]


@pytest.mark.parametrize(("change", "status", "field"), [
    ({"vehicle": "tgv"}, 422, "vehicle"),
    ({"methods": ["magic"]}, 422, "methods[0]"),
    ({"zones": [5]}, 422, "zones[0]"),
    ({"bounds": [[2e-4, 1e-4]]}, 422, "bounds"),
    ({"measurement_id": 7}, 422, "wear"),  # both wear and measurement_id: each named
    ({"wear": None, "measurement_id": 7}, 404, "measurement_id"),
    ({"step_km": 0.5}, 422, "step_km"),
    ({"classes": None, "route_id": "nowhere"}, 404, "route_id"),
])
def test_bad_fit_requests_are_refused_before_queuing(tmp_path, twin, change, status, field):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/coefficient-fits", json=_body(twin, **change))
    assert r.status_code == status, r.text
    assert r.json()["errors"][0]["field"] == field
    assert client.get("/v1/coefficient-fits").json() == []


def _cli_wear_csv(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, twin) -> Path:
    """The CLI's database and data folder in ``tmp_path``; the twin's fitted wear curve
    written there as a ``y_mm,wear_mm`` CSV (its path)."""
    monkeypatch.setenv("WEARCAST_DATABASE_URL", f"sqlite:///{tmp_path / 'cli.db'}")
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path))
    csv = tmp_path / "wear.csv"
    csv.write_text("y_mm,wear_mm\n" + "\n".join(
        f"{y},{w}" for y, w in zip(twin.y_mm, twin.wear_fit_mm, strict=True)))
    return csv


def test_cli_fit_coefficients(tmp_path, twin, monkeypatch):
    from wearcast.service.cli import app

    csv = _cli_wear_csv(tmp_path, monkeypatch, twin)
    result = CliRunner().invoke(app, [
        "fit-coefficients", "--vehicle", "metro_b", "--class", "tangent:0:70:0.6",
        "--class", "1500:0:70:0.4:left", "--wear-csv", str(csv), "--mileage-km", "200",
        "--step-km", "100", "--zone", "1", "--out", str(tmp_path / "fit.json")])
    assert result.exit_code == 0, result.output
    assert "exact" in result.output and "0.0003" in result.output
    bad = CliRunner().invoke(app, ["fit-coefficients", "--vehicle", "metro_b", "--class",
                                   "tangent:0:70:1", "--mileage-km", "200"])
    assert bad.exit_code == 2


# --- the tau_max law's coefficient c_tau -------------------------------------------------------

TRUE_C_TAU = 3e-6   # mm/(m MPa); no paper publishes c_tau: a twin made by the loop
TAU_0_MPA = 100.0


@pytest.fixture(scope="module")
def tau_twin():
    classes = [CurveClass(c["radius_m"], 0.0, c["speed_kmh"], c.get("direction", "left"),
                          c["share"]) for c in CLASSES]
    return make_twin("metro_b", classes, (TRUE_C_TAU,), 200.0, 400.0, 100.0, law="tau_max",
                     tau_threshold_mpa=TAU_0_MPA)


def _tau_body(twin, **change):
    body = {"name": "tau twin", "vehicle": "metro_b", "classes": CLASSES, "law": "tau_max",
            "tau_threshold_mpa": TAU_0_MPA, "tau_coefficient_bounds": [1e-7, 1e-5],
            "wear": {"y_mm": twin.y_mm[::5].tolist(), "wear_mm": twin.wear_fit_mm[::5].tolist()},
            "mileage_km": 200.0, "step_km": 100.0, "methods": ["exact"], "max_runs": 10,
            "rtol": 1e-7,
            "predict": {"mileage_km": 400.0,
                        "wear": {"y_mm": twin.y_mm.tolist(),
                                 "wear_mm": twin.wear_predict_mm.tolist()}}}
    body.update(change)
    return body


def test_tau_max_fit_recovers_c_tau_and_names_the_law(tmp_path, tau_twin):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/coefficient-fits", json=_tau_body(tau_twin))
    assert r.status_code == 202, r.text
    spec = r.json()["spec"]
    # Only the chosen law's fields are stored, defaults resolved.
    assert spec["law"] == "tau_max" and "zones" not in spec and "bounds" not in spec
    assert spec["tau_coefficient_start"] == 1e-6
    body = _wait(client, r.json()["id"])
    assert body["status"] == "done", body
    res = body["result"]
    assert res["law"] == "tau_max" and res["tau_threshold_mpa"] == TAU_0_MPA
    # Noise-free twin, 10 loop runs with rtol 1e-7 (the outer iteration gains ~20x per run):
    # the exact method returns the true c_tau to 1e-6.
    assert res["fitted_coefficients"]["c_tau_mm_per_m_mpa"] == pytest.approx(TRUE_C_TAU,
                                                                              rel=1e-6)
    assert res["identifiable_coefficients"] == ["c_tau_mm_per_m_mpa"]
    assert "fitted_zones" not in res
    rows = {row["method"]: row for row in res["table"]}
    assert rows["exact"]["c_tau_mm_per_m_mpa"] == res["coefficients"]["exact"][0]
    # the start (the 1e-6 placeholder) is the "traditional" row; the fit predicts 400 km
    assert rows["traditional_mean_k"]["c_tau_mm_per_m_mpa"] == 1e-6
    assert rows["exact"]["rmse_predict_mm"] < 1e-4 * tau_twin.wear_predict_mm.max()


def test_archard_fit_result_names_its_law(tmp_path, twin):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/coefficient-fits", json=_body(twin, methods=["exact"], predict=None))
    assert r.status_code == 202, r.text
    assert "tau_threshold_mpa" not in r.json()["spec"]
    res = _wait(client, r.json()["id"])["result"]
    assert res["law"] == "archard_kth" and res["fitted_zones"] == [1]
    assert res["fitted_coefficients"]["k1"] == pytest.approx(TRUE_K1, rel=1e-3)


@pytest.mark.parametrize(("change", "field", "reason"), [
    ({"law": "wizard"}, "law", "unknown wear law"),
    ({"law": "usfd"}, "law", "no coefficient to fit"),
    ({"zones": [1]}, "zones", "archard_kth"),
    ({"bounds": [[1e-7, 1e-5]]}, "bounds", "tau_coefficient_bounds"),
    ({"start": [5e-4, 35e-4, 5e-4, 350e-4]}, "start", "archard_kth"),
    ({"application": "local"}, "application", "archard_kth only"),
    ({"tau_coefficient_bounds": [-1e-6, 1e-5]}, "tau_coefficient_bounds", "0 < lower < upper"),
    ({"tau_coefficient_bounds": [1e-5, 1e-7]}, "tau_coefficient_bounds", "0 < lower < upper"),
    ({"tau_threshold_mpa": -5.0}, "tau_threshold_mpa", "greater than or equal to 0"),
    ({"tau_coefficient_start": 0.0}, "tau_coefficient_start", "greater than 0"),
    ({"law": "archard_kth"}, "tau_threshold_mpa", "tau_max only"),
    ({"law": "archard_kth", "tau_threshold_mpa": None}, "tau_coefficient_bounds",
     "tau_max only"),
])
def test_bad_tau_max_requests_are_refused(tmp_path, tau_twin, change, field, reason):
    client = sqlite_client(tmp_path)
    r = client.post("/v1/coefficient-fits", json=_tau_body(tau_twin, **change))
    assert r.status_code == 422, r.text
    detail = r.json()["errors"][0]
    assert detail["field"] == field and reason in detail["reason"], detail
    assert client.get("/v1/coefficient-fits").json() == []


def test_cli_fit_tau_max(tmp_path, tau_twin, monkeypatch):
    from wearcast.service.cli import app

    csv = _cli_wear_csv(tmp_path, monkeypatch, tau_twin)
    common = ["fit-coefficients", "--vehicle", "metro_b", "--class", "tangent:0:70:0.6",
              "--class", "1500:0:70:0.4:left", "--wear-csv", str(csv), "--mileage-km", "200",
              "--step-km", "100", "--law", "tau_max"]
    result = CliRunner().invoke(app, common + [
        "--tau-threshold-mpa", "100", "--tau-coefficient-bounds", "1e-7", "1e-5",
        "--out", str(tmp_path / "fit.json")])
    assert result.exit_code == 0, result.output
    assert "tau_max" in result.output and "c_tau_mm_per_m_mpa" in result.output
    import json
    fit = json.loads((tmp_path / "fit.json").read_text())["result"]["fitted_coefficients"]
    # default max_runs 5 and rtol 1e-3 stop the outer iteration at ~1e-4 relative here
    assert fit["c_tau_mm_per_m_mpa"] == pytest.approx(TRUE_C_TAU, rel=1e-3)
    bad = CliRunner().invoke(app, common + ["--zone", "1"])
    assert bad.exit_code == 2 and "zones" in bad.output
