"""A physics model (``POST /v1/models`` with ``kind: "physics"``) on stored measured rails:
``rail_id`` / ``high_rail_id`` / ``low_rail_id`` with the rules of ``POST /v1/simulations``
(``rail_store.requested_rails``), stored with the model, under its run and its diagnosis.

The measurements are the loop data of ``test_physics_models_api`` (metro_b on two 250 m
curves and tangent track, two vehicles); the measured rail is the worn MiniProf low rail
``avg_low2.ban`` of the reference data, laid as the high rail of every curve.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from tests.service.test_physics_models_api import MODEL, _load
from wearcast.service import physics_model_store
from wearcast.service.app import create_app
from wearcast.service.settings import Settings


def _rail(client: TestClient, data: bytes, name: str, **form: str) -> int:
    r = client.post("/v1/rails/import", files={"file": (name, data)}, data=form)
    assert r.status_code == 200, r.text
    return int(r.json()["created"][0]["id"])


def _errors(r) -> list[str]:
    return [e["field"] for e in r.json()["errors"]]


def test_a_physics_model_on_a_measured_high_rail(backend_url: str, tmp_path: Path,
                                                 reference_dir: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    runs: list[dict | None] = []  # the stored rails of every loop run made

    def spy(*args, **kwargs):
        runs.append(kwargs.get("track_rails"))
        return loop(*args, **kwargs)

    loop = physics_model_store.run_loop
    monkeypatch.setattr(physics_model_store, "run_loop", spy)
    with TestClient(create_app(Settings(data_dir=tmp_path, database_url=backend_url))) as c:
        _on_a_measured_high_rail(c, reference_dir, runs)


def _on_a_measured_high_rail(client: TestClient, reference_dir: Path,
                             runs: list[dict | None]) -> None:
    data = (reference_dir / "miniprof" / "avg_low2.ban").read_bytes()
    worn = _rail(client, data, "avg_low2.ban")
    _load(client, vehicles=2)
    nominal = client.post("/v1/models", json={**MODEL, "name": "nominal"})
    assert nominal.status_code == 201, nominal.text
    high = client.post("/v1/models", json={**MODEL, "name": "worn high", "high_rail_id": worn})
    assert high.status_code == 201, high.text
    nominal_m, high_m = nominal.json(), high.json()
    # the rails it was built against are stored and returned; a model without rails has none
    assert high_m["physics"]["rails"] == {"high_rail_id": {
        "rail_id": worn, "name": high_m["physics"]["rails"]["high_rail_id"]["name"],
        "kind": "rail", "inclination": None}}
    assert "avg_low2" in high_m["physics"]["rails"]["high_rail_id"]["name"]
    assert high_m["summary"]["high_rail_id"] == worn
    assert nominal_m["physics"]["rails"] == {} and "high_rail_id" not in nominal_m["summary"]
    again = client.get(f"/v1/models/{high_m['id']}").json()
    assert again["physics"] == high_m["physics"] and again["summary"] == high_m["summary"]
    # the worn, wider head as the high rail changes the run (deterministic: the same run, to
    # the last digit, if the rail were not laid): the vehicle-mean flange thickness (Sd), flange
    # height (Sh) and qR lost by 1,500 run-km differ from the nominal 60E1's
    def losses(model: dict) -> dict[str, float]:
        s = model["physics"]["series"]
        return {q: abs(float(np.interp(1500.0, s["run_mileage_km"], s[q])) - s[q][0])
                for q in ("ft_mm", "fh_mm", "qr_mm")}

    on_nominal, on_worn = losses(nominal_m), losses(high_m)
    ratios = {q: on_worn[q] / on_nominal[q] for q in on_nominal}
    print("losses at 1500 run-km, worn high rail / nominal: " + ", ".join(
        f"{q} {on_worn[q]:.4f}/{on_nominal[q]:.4f} mm = {ratios[q]:.3f}" for q in ratios)
        + f"; wear scale {high_m['physics']['wear_scale']:.4f} / "
        f"{nominal_m['physics']['wear_scale']:.4f}")
    assert all(v > 0 for v in (*on_nominal.values(), *on_worn.values()))
    assert abs(ratios["ft_mm"] - 1.0) > 0.02
    # the stored run is the loop's on the stored rail, and not on the nominal rail
    with client.app.state.database.session_factory() as session:  # type: ignore[attr-defined]
        state = physics_model_store.load(session, high_m["id"]).state
    assert [int(r["rail_id"]) for r in state["track_rails"].values()] == [worn]
    args = (state["vehicle"], state["resolved_classes"], state["law"], state["simulation_spec"],
            state["simulation"]["mileage_km"])
    stored = np.asarray(state["series"]["sd_mm"])
    again_on_rail = physics_model_store.run_loop(*args, track_rails=state["track_rails"])
    assert np.asarray(again_on_rail.sd_mm) == pytest.approx(stored, abs=1e-9)
    on_nominal_rail = physics_model_store.run_loop(*args)
    assert np.max(np.abs(np.asarray(on_nominal_rail.sd_mm)[-1] - stored[-1])) > 1e-3
    # predict answers from the model's own run (on its rails)
    for model in (nominal_m, high_m):
        r = client.post(f"/v1/models/{model['id']}/predict", json={
            "bogie_type": "motor", "axle": 1, "side": "right", "mileage_km": [0, 1000]})
        assert r.status_code == 200, r.text
    # a diagnosis reruns the loop on the same rails; the rail-state cause is skipped
    runs.clear()
    r = client.post(f"/v1/models/{high_m['id']}/diagnose", json={"causes": ["patch_model"]})
    assert r.status_code == 200, r.text
    assert runs and all(t is not None and [int(v["rail_id"]) for v in t.values()] == [worn]
                        for t in runs)
    assert "stored measured rails" in r.json()["skipped"]["rail_state"]
    assert r.json()["null_fit"]["wear_scale"] == pytest.approx(
        high_m["physics"]["wear_scale"], rel=1e-6)
    runs.clear()
    r = client.post(f"/v1/models/{nominal_m['id']}/diagnose", json={"causes": ["patch_model"]})
    assert r.status_code == 200, r.text
    assert runs and all(not t for t in runs)
    assert "rail_state" not in r.json()["skipped"]


def test_physics_model_rails_are_checked_as_for_simulations(backend_url: str, tmp_path: Path,
                                                            reference_dir: Path) -> None:
    with TestClient(create_app(Settings(data_dir=tmp_path, database_url=backend_url))) as c:
        _checked_as_for_simulations(c, reference_dir)


def _checked_as_for_simulations(client: TestClient, reference_dir: Path) -> None:
    data = (reference_dir / "miniprof" / "avg_low2.ban").read_bytes()
    at_40 = _rail(client, data, "avg_low2.ban", inclination="1/40")
    copy = data.replace(b"Filename=low.typ2.trc", b"Filename=low.copy.trc", 1)
    assert copy != data  # another file: stored anew, at its own inclination
    at_20 = _rail(client, copy, "copy.ban", inclination="1/20")
    _load(client, vehicles=2)
    for field in ("rail_id", "high_rail_id", "low_rail_id"):
        r = client.post("/v1/models", json={**MODEL, field: 999})
        assert r.status_code == 404, r.text
        assert _errors(r) == [field]
    r = client.post("/v1/models", json={**MODEL, "high_rail_id": at_40, "low_rail_id": at_20})
    assert r.status_code == 422, r.text
    assert _errors(r) == ["low_rail_id"] and "inclination" in r.json()["detail"]
    r = client.post("/v1/models", json={**MODEL, "high_rail_id": at_40,
                                        "simulation": {**MODEL["simulation"],
                                                       "rail_tonnage_mt": 5.0}})
    assert r.status_code == 422 and _errors(r) == ["simulation.rail_tonnage_mt"]
    # the wheel fields of the table and simulation requests are not a physics model's
    r = client.post("/v1/models", json={**MODEL, "measurement_id": 1})
    assert r.status_code == 422 and _errors(r) == ["measurement_id"]
    assert client.get("/v1/models/1").status_code == 404  # none of them stored a model
