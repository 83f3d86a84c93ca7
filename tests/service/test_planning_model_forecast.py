"""Fleet state of a wheel with a single measurement since turning: the calibrated model's
forecast (the bundled example fleet), checked against the model's own reprofiling answer
for each limit alone."""

from __future__ import annotations

import warnings

import pytest

from wearcast.service import demo
from wearcast.service.app import create_app
from wearcast.service.settings import Settings

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

RELAXED = {"sd_min_mm": 1e-3, "sh_max_mm": 1e6, "qr_min_mm": 1e-3}


def test_model_forecast_for_a_wheel_without_history(tmp_path):
    with TestClient(create_app(Settings(data_dir=tmp_path))) as client:
        ids = demo.load_example_fleet(client)
        r = client.post("/v1/models", json={
            "name": "aosta motor", "measure": "tau_max", "running_mode": "mixed",
            "wear_table_id": ids.wear_table_id,
            "calibration": {"route_id": "aosta", "filter": {"bogie_type": "motor"}}})
        assert r.status_code == 201, r.text
        model_id = r.json()["id"]
        # a new wheel measured once: the profile of an example wheel, under another id
        source = client.get("/v1/measurements", params={
            "wheel_id": "A1-M1L", "include_points": "true"}).json()["items"][2]
        body = {k: source[k] for k in ("vehicle_id", "bogie_type", "axle", "side",
                                       "mileage_km", "y_mm", "z_mm")}
        body.update(wheel_id="NEW-1", vehicle_id="NEWV", diameter_mm=890.0,
                    measured_on="2026-05-20")
        r = client.post("/v1/measurements", json=body)
        assert r.status_code == 201, r.text
        state = client.get("/v1/fleet/state", params={"model_id": model_id,
                                                      "route_id": "aosta"}).json()
        wheel = next(w for w in state["wheels"] if w["wheel_id"] == "NEW-1")
        assert wheel["n_since_turning"] == 1
        for name, key in (("sd", "sd_min_mm"), ("qr", "qr_min_mm")):
            rem = wheel["remaining_km"][name]
            assert rem["source"] == "model"
            ref = client.post(f"/v1/models/{model_id}/reprofiling", json={
                "route_id": "aosta", "wheel_id": "NEW-1",
                "limits": {**RELAXED, key: state["limits"][key]}}).json()
            for q in ("p10", "p50", "p90"):
                expected = ref["remaining_km"][q]
                got = rem[q]
                if expected is None:
                    assert got == "inf"
                else:
                    assert got == pytest.approx(expected, rel=1e-9)
        # a plan with the model plans it (dated, with its vehicle's mileage per day)
        assert client.put("/v1/vehicles/NEWV", json={"km_per_day": 400}).status_code == 200
        r = client.post("/v1/plans", json={"model_id": model_id, "route_id": "aosta",
                                           "start": "2026-06-01", "capacity_per_week": 2})
        assert r.status_code == 201, r.text
        plan = r.json()
        assert "NEW-1" not in {u["wheel_id"] for u in plan["unplanned"]}
        [mine] = [w for w in plan["wheelsets"] if "NEW-1" in w["wheel_ids"]]
        assert mine["deadline"] is not None
        # without a model the same wheel's remaining km are unknown, and it cannot be planned
        plain = client.get("/v1/fleet/state").json()
        wheel = next(w for w in plain["wheels"] if w["wheel_id"] == "NEW-1")
        assert wheel["remaining_km"]["sd"]["source"] == "unknown"
        assert wheel["urgency"] == "unknown"
        plan = client.post("/v1/plans", json={"start": "2026-06-01"}).json()
        assert any(u["wheel_id"] == "NEW-1" and "fewer than 2" in u["reason"]
                   for u in plan["unplanned"])
        bad = client.get("/v1/fleet/state", params={"model_id": model_id})
        assert bad.status_code == 422 and "route_id" in bad.text
