"""``expected_progression`` in a hybrid diagnose: the finder's null grows as a simulation of
the route expects (``statistics.discrepancy_progression``) instead of linearly."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_diagnose_api import _client, _load  # noqa: E402

MILEAGES = [1_000.0, 10_000.0, 50_000.0, 100_000.0, 200_000.0]


def _progression(exponent: float) -> dict:
    areas = [{"bogie_type": b, "wheelset": w, "region": r,
              "areas_mm2": [2.0 * (s / 1000.0) ** exponent for s in MILEAGES]}
             for b in ("motor", "trailer") for w in ("leading", "trailing")
             for r in ("flange", "tread")]
    return {"mileage_km": MILEAGES, "areas": areas}


def test_a_linear_expected_progression_is_the_linear_null(tmp_path):
    # areas proportional to the mileage give g = 1 everywhere: the same diagnosis
    client = _client(tmp_path)
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
    client = _client(tmp_path)
    model_id = _load(client, "none")
    short = _progression(1.0)
    short["areas"][0]["areas_mm2"] = [1.0, 2.0]
    r = client.post(f"/v1/models/{model_id}/diagnose", json={"expected_progression": short})
    assert r.status_code == 422 and "expected_progression" in r.text, r.text
    backwards = _progression(1.0)
    backwards["mileage_km"] = list(reversed(MILEAGES))
    r = client.post(f"/v1/models/{model_id}/diagnose", json={"expected_progression": backwards})
    assert r.status_code == 422 and "expected_progression.mileage_km" in r.text, r.text
