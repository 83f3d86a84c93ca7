"""``expected_progression`` in a hybrid diagnose: the finder's null grows as a simulation of
the route expects (``statistics.discrepancy_progression``) instead of linearly."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_diagnose_api import _load  # noqa: E402

from tests.service.conftest import sqlite_client, wait_for_job

MILEAGES = [1_000.0, 10_000.0, 50_000.0, 100_000.0, 200_000.0]


def _progression(exponent: float) -> dict:
    areas = [{"bogie_type": b, "wheelset": w, "region": r,
              "areas_mm2": [2.0 * (s / 1000.0) ** exponent for s in MILEAGES]}
             for b in ("motor", "trailer") for w in ("leading", "trailing")
             for r in ("flange", "tread")]
    return {"mileage_km": MILEAGES, "areas": areas}


def test_a_linear_expected_progression_is_the_linear_null(tmp_path):
    # areas proportional to the mileage give g = 1 everywhere: the same diagnosis
    client = sqlite_client(tmp_path)
    model_id = _load(client, "traction")
    plain = client.post(f"/v1/models/{model_id}/diagnose", json={"seed": 1}).json()
    r = client.post(f"/v1/models/{model_id}/diagnose",
                    json={"seed": 1, "expected_progression": _progression(1.0)})
    assert r.status_code == 200, r.text
    given = r.json()
    assert given["verdict"] == plain["verdict"] == "traction"
    assert given["findings"][0]["gain"]["relative"] == pytest.approx(
        plain["findings"][0]["gain"]["relative"], rel=1e-6)


def test_bad_progressions_name_the_field(tmp_path):
    client = sqlite_client(tmp_path)
    model_id = _load(client, "none")
    short = _progression(1.0)
    short["areas"][0]["areas_mm2"] = [1.0, 2.0]
    r = client.post(f"/v1/models/{model_id}/diagnose", json={"expected_progression": short})
    assert r.status_code == 422 and "expected_progression" in r.text, r.text
    backwards = _progression(1.0)
    backwards["mileage_km"] = list(reversed(MILEAGES))
    r = client.post(f"/v1/models/{model_id}/diagnose", json={"expected_progression": backwards})
    assert r.status_code == 422 and "expected_progression.mileage_km" in r.text, r.text


SIM = {"vehicle": "metro_b", "law": "archard_kth", "application": "global",
       "classes": [{"radius_m": None, "speed_kmh": 70, "share": 0.6},
                   {"radius_m": 500, "cant_mm": 60, "speed_kmh": 60, "direction": "left",
                    "share": 0.4}],
       "steps": {"mode": "adaptive", "count": 3}}


def _simulate(client, bogie_type: str, axle: int) -> int:
    r = client.post("/v1/simulations", json={**SIM, "bogie_type": bogie_type, "axle": axle})
    assert r.status_code in (201, 202), r.text
    sim_id = r.json()["id"]
    sim = wait_for_job(client, f"/v1/simulations/{sim_id}", 300.0)
    assert sim["status"] == "done", sim
    return sim_id


def _areas_by_hand(result: dict, mileage_km: np.ndarray) -> dict[str, np.ndarray]:
    """Independent of the service: the vertical wear's integral on each side of y = -30."""
    y = np.asarray(result["y_mm"])
    z = np.asarray(result["profiles_mm"])
    s = np.asarray(result["mileage_km"])
    out = {}
    for region, sel in (("flange", y < -30.0), ("tread", y >= -30.0)):
        per_step = [np.trapezoid((z[0] - zi)[sel], y[sel]) for zi in z]
        out[region] = np.interp(mileage_km, s, per_step)
    return out


def test_the_progression_derived_from_stored_simulations(tmp_path):
    """``expected_progression_simulations`` gives the same diagnosis as the progression
    computed by hand from the same simulations' profiles and sent as ``expected_progression``."""
    client = sqlite_client(tmp_path)
    model_id = _load(client, "none")
    sims = {(b, a): _simulate(client, b, a) for b in ("motor", "trailer") for a in (1, 2)}
    r = client.post(f"/v1/models/{model_id}/diagnose",
                    json={"seed": 1, "expected_progression_simulations": list(sims.values())})
    assert r.status_code == 200, r.text
    derived = r.json()
    assert derived["expected_progression"]["source"].startswith("wear-loop simulations")
    results = {k: client.get(f"/v1/simulations/{i}").json()["result"] for k, i in sims.items()}
    top = min(r["mileage_km"][-1] for r in results.values())  # the shortest run's end
    grid = np.linspace(0.0, top, 21)[1:]
    areas = []
    for (bogie, axle), result in results.items():
        for region, a in _areas_by_hand(result, grid).items():
            areas.append({"bogie_type": bogie, "wheelset": ("leading", "trailing")[axle - 1],
                          "region": region, "areas_mm2": a.tolist()})
    by_hand = client.post(f"/v1/models/{model_id}/diagnose", json={
        "seed": 1, "expected_progression": {"mileage_km": grid.tolist(), "areas": areas}})
    assert by_hand.status_code == 200, by_hand.text
    by_hand = by_hand.json()
    assert derived["verdict"] == by_hand["verdict"]
    for key, g in derived["expected_progression"]["factors"].items():
        assert g == pytest.approx(by_hand["expected_progression"]["factors"][key], rel=1e-9)
    # the simulated wear is not linear in mileage: the factors are not all 1
    assert any(abs(v - 1.0) > 0.01 for g in derived["expected_progression"]["factors"].values()
               for v in g)
    # bad ids and both fields at once name the field
    r = client.post(f"/v1/models/{model_id}/diagnose",
                    json={"expected_progression_simulations": [99_999]})
    assert r.status_code == 404 and "expected_progression_simulations" in r.text, r.text
    r = client.post(f"/v1/models/{model_id}/diagnose", json={
        "expected_progression_simulations": [sims[("motor", 1)]],
        "expected_progression": {"mileage_km": grid.tolist(), "areas": areas}})
    assert r.status_code == 422 and "not both" in r.text, r.text
    # one simulation covers only the motor bogie's leading axle: the trailer rows cannot be
    # given a progression
    r = client.post(f"/v1/models/{model_id}/diagnose",
                    json={"expected_progression_simulations": [sims[("motor", 1)]]})
    assert r.status_code == 422 and "expected_progression" in r.text, r.text
