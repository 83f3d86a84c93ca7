"""The /v1 HTTP contract end to end on a temporary SQLite database (FastAPI TestClient).

Synthetic measurements come from the statistics core's fleet twin with a KNOWN calibration
factor c_s (seed 001 eq. 3) and no per-wheel rate scatter, so calibration through the service
must return that c_s, and prediction on the calibration route must reproduce the measured
wear areas.
"""

from __future__ import annotations

import io
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from sqlalchemy import func, select

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service import models_db as db
from wearcast.service.app import create_app
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes, twin_wear_table

C_S = {"tread": 1.5e-6, "flange": 6.0e-6}


@pytest.fixture(scope="module")
def fleet() -> ft.FleetTwin:
    config = ft.FleetConfig(
        units=(ft.UnitConfig("B", twin_routes.metro_route(), vehicles=1, running_mode="lead",
                             covariates={"depot": "north", "lubricated": 0}),),
        mileages_km=(30_000, 80_000, 130_000, 180_000), mileage_jitter_km=0.0,
        calibration_factor=C_S, rate_scatter=0.0, area_scatter=0.0, noise_mm=0.005,
        points_per_profile=300, seed=7)
    return ft.generate_fleet(config)


@pytest.fixture(scope="module")
def fleet_csv(fleet: ft.FleetTwin) -> bytes:
    return fleet.profiles.to_csv(index=False).encode()


@pytest.fixture(scope="module")
def table_csv() -> bytes:
    return twin_wear_table.synthetic_wear_table().to_csv(index=False).encode()


def _client(data_dir: Path) -> TestClient:
    return TestClient(create_app(Settings(data_dir=data_dir)))


@pytest.fixture
def client(tmp_path: Path) -> TestClient:
    return _client(tmp_path)


@pytest.fixture(scope="module")
def loaded(tmp_path_factory: pytest.TempPathFactory, fleet_csv: bytes, table_csv: bytes
           ) -> dict:
    """A database with the fleet imported, both routes, the table and a calibrated model."""
    client = _client(tmp_path_factory.mktemp("loaded"))
    imported = client.post("/v1/measurements/import",
                           files={"file": ("fleet.csv", fleet_csv, "text/csv")}).json()
    for route in (twin_routes.metro_route(), twin_routes.aosta_route()):
        assert client.post("/v1/routes", json=route.to_json()).status_code == 201
    table = client.post("/v1/wear-tables", files={"file": ("t.csv", table_csv, "text/csv")})
    model = client.post("/v1/models", json={
        "name": "metro-lead", "measure": "tau_max", "running_mode": "lead",
        "wear_table_id": table.json()["id"],
        "calibration": {"route_id": "metro", "filter": {"route_id": "metro"}}})
    assert model.status_code == 201, model.text
    return {"client": client, "import": imported, "table": table.json(), "model": model.json()}


def _field(response) -> str:
    return response.json()["errors"][0]["field"]


def _count(client: TestClient, table) -> int:
    factory = client.app.state.database.session_factory
    with factory() as session:
        return session.scalar(select(func.count()).select_from(table))


# --- health -----------------------------------------------------------------------------

def test_health_answers_with_the_database(client: TestClient) -> None:
    response = client.get("/v1/health")
    assert response.status_code == 200
    assert response.json() == {"status": "ok", "database": "sqlite"}


# --- the full walk ----------------------------------------------------------------------

def test_import_counts_every_measurement(loaded: dict, fleet: ft.FleetTwin) -> None:
    result = loaded["import"]
    assert result["duplicate"] is False
    assert result["records"] == result["created"] == len(fleet.truth) == 32
    assert result["duplicates"] == 0
    assert result["points"] == len(fleet.profiles)


def test_calibration_returns_the_known_calibration_factor(loaded: dict) -> None:
    # The twin wears every wheel at exactly c_s * P (no rate scatter, no area scatter); the
    # service's areas come from cleaning + alignment of noisy (5 um) profiles, which the
    # statistics core reproduces to well under 1 % per profile: we allow 3 %.
    summary = loaded["model"]["summary"]
    assert summary["tread"]["c_s"] == pytest.approx(C_S["tread"], rel=0.03)
    assert summary["flange"]["c_s"] == pytest.approx(C_S["flange"], rel=0.03)
    assert loaded["model"]["n_calibration_measurements"] == 32
    again = loaded["client"].get(f"/v1/models/{loaded['model']['id']}")
    assert again.status_code == 200 and again.json() == loaded["model"]


def test_prediction_on_the_calibration_route_reproduces_the_measurements(
        loaded: dict, fleet: ft.FleetTwin) -> None:
    truth = fleet.truth[(fleet.truth.bogie_type == "motor") & (fleet.truth.axle == 1)
                        & (fleet.truth.side == "left")].sort_values("mileage_km")
    response = loaded["client"].post(f"/v1/models/{loaded['model']['id']}/predict", json={
        "route_id": "metro", "bogie_type": "motor", "axle": 1, "side": "left",
        "mileage_km": truth.mileage_km.tolist()})
    assert response.status_code == 200, response.text
    body = response.json()
    predicted_tread = [p["tread_area_mm2"]["p50"] for p in body["points"]]
    predicted_flange = [p["flange_area_mm2"]["p50"] for p in body["points"]]
    np.testing.assert_allclose(predicted_tread, truth.tread_area_mm2, rtol=0.04)
    np.testing.assert_allclose(predicted_flange, truth.flange_area_mm2, rtol=0.04)
    # the weighted measure is the twin's P for that wheel (same table, same route, eq. 2)
    assert body["weighted_measure"]["tread"] == pytest.approx(truth.p_tread.iloc[0], rel=1e-9)
    for point in body["points"]:
        assert point["tread_area_mm2"]["p10"] <= point["tread_area_mm2"]["p50"] \
            <= point["tread_area_mm2"]["p90"]
        assert len(point["z_mm"]) == len(body["y_mm"]) == len(body["reference_z_mm"])
    # tread wear lowers the tape circle, so the flange height Sh grows with mileage
    sh = [p["sh_mm"] for p in body["points"]]
    assert 28.0 < sh[0] and all(a < b for a, b in zip(sh, sh[1:], strict=False)), sh


def test_prediction_accepts_the_route_by_id_or_inline(loaded: dict) -> None:
    client, model_id = loaded["client"], loaded["model"]["id"]
    route = client.get("/v1/routes/metro").json()
    common = {"bogie_type": "trailer", "axle": 2, "side": "right", "mileage_km": [50_000]}
    by_id = client.post(f"/v1/models/{model_id}/predict", json={**common,
                                                                 "route_id": route["id"]})
    inline = client.post(f"/v1/models/{model_id}/predict", json={
        **common, "route": {"classes": route["classes"]}})
    assert by_id.status_code == inline.status_code == 200
    assert by_id.json()["points"] == inline.json()["points"]


def test_reprofiling_new_wheel_and_from_a_wheels_latest_measurement(loaded: dict) -> None:
    client, model_id = loaded["client"], loaded["model"]["id"]
    new = client.post(f"/v1/models/{model_id}/reprofiling", json={
        "route_id": "aosta", "bogie_type": "motor", "axle": 1, "side": "left"})
    assert new.status_code == 200, new.text
    body = new.json()
    assert body["governing_limit"] in {"sd", "sh", "qr"}
    assert body["mileage_km"]["p10"] < body["mileage_km"]["p50"] < body["mileage_km"]["p90"]
    worn = client.post(f"/v1/models/{model_id}/reprofiling", json={
        "route_id": "aosta", "wheel_id": "B1-M1L"})
    assert worn.status_code == 200, worn.text
    w = worn.json()
    assert w["start_mileage_km"] == pytest.approx(180_000)
    assert (w["bogie_type"], w["axle"], w["side"]) == ("motor", 1, "left")
    # it starts from the wheel's latest measured profile and its measured wear areas
    latest = client.get("/v1/measurements", params={"wheel_id": "B1-M1L",
                                                    "mileage_km": 180_000}).json()["items"][0]
    assert w["start_measurement_id"] == latest["id"]
    assert w["start_areas_mm2"] == {"flange": pytest.approx(latest["flange_area_mm2"]),
                                    "tread": pytest.approx(latest["tread_area_mm2"])}
    assert w["remaining_km"]["p50"] != body["remaining_km"]["p50"]
    assert w["mileage_km"]["p50"] == pytest.approx(180_000 + w["remaining_km"]["p50"])
    # a tighter Sd limit is reached earlier
    tight = client.post(f"/v1/models/{model_id}/reprofiling", json={
        "route_id": "aosta", "bogie_type": "motor", "axle": 1, "side": "left",
        "limits": {"sd_min_mm": 31.5, "qr_min_mm": 1.0}}).json()
    assert tight["governing_limit"] == "sd"
    assert tight["mileage_km"]["p50"] < body["mileage_km"]["p50"]


def test_measurement_listing_filters_on_metadata_and_covariates(loaded: dict) -> None:
    client = loaded["client"]
    everything = client.get("/v1/measurements").json()
    assert everything["total"] == 32
    motors = client.get("/v1/measurements", params={"bogie_type": "motor", "axle": ["1", "2"]})
    assert motors.json()["total"] == 16
    one = client.get("/v1/measurements", params={"filter": '{"wheel_id": "B1-T2R"}'}).json()
    assert one["total"] == 4 and {i["side"] for i in one["items"]} == {"right"}
    assert client.get("/v1/measurements", params={"depot": "north"}).json()["total"] == 32
    assert client.get("/v1/measurements", params={"depot": "south"}).json()["total"] == 0
    assert client.get("/v1/measurements", params={"lubricated": "0"}).json()["total"] == 32
    route_id = client.get("/v1/routes/metro").json()["id"]
    assert client.get("/v1/measurements",
                      params={"route_id": str(route_id)}).json()["total"] == 32
    ranged = client.get("/v1/measurements", params={"mileage_km_min": 100_000}).json()
    assert ranged["total"] == 16
    page = client.get("/v1/measurements", params={"limit": 5, "offset": 30}).json()
    assert page["total"] == 32 and len(page["items"]) == 2
    first = client.get(f"/v1/measurements/{page['items'][0]['id']}").json()
    assert len(first["y_mm"]) == len(first["z_mm"]) == 300
    bad = client.get("/v1/measurements", params={"axle": "one"})
    assert bad.status_code == 422 and _field(bad) == "filter.axle"


# --- idempotency, duplicates, atomicity -------------------------------------------------

def test_reimport_of_the_same_content_or_key_creates_nothing(client: TestClient,
                                                             fleet_csv: bytes) -> None:
    first = client.post("/v1/measurements/import", headers={"Idempotency-Key": "abc"},
                        files={"file": ("fleet.csv", fleet_csv, "text/csv")}).json()
    same_content = client.post("/v1/measurements/import",
                               files={"file": ("renamed.csv", fleet_csv, "text/csv")}).json()
    same_key = client.post("/v1/measurements/import", headers={"Idempotency-Key": "abc"},
                           files={"file": ("fleet.csv", fleet_csv, "text/csv")}).json()
    for again in (same_content, same_key):
        assert again["duplicate"] is True and again["batch_id"] == first["batch_id"]
        assert again["created"] == 0
    # the key reused with different bytes: refused (IETF idempotency-key draft), not dropped
    other = fleet_csv.replace(b"\n", b"\r\n")
    reused = client.post("/v1/measurements/import", headers={"Idempotency-Key": "abc"},
                         files={"file": ("other.csv", other, "text/csv")})
    assert reused.status_code == 422 and "Idempotency-Key" in reused.text
    assert _count(client, db.Measurement) == 32
    assert _count(client, db.ImportBatch) == 1
    # different bytes without the key: a new batch whose measurements are all duplicates
    new_batch = client.post("/v1/measurements/import",
                            files={"file": ("other.csv", other, "text/csv")}).json()
    assert new_batch["duplicate"] is False and new_batch["batch_id"] != first["batch_id"]
    assert (new_batch["created"], new_batch["duplicates"]) == (0, 32)
    assert _count(client, db.Measurement) == 32


def test_a_bad_row_at_the_end_leaves_the_database_unchanged(tmp_path: Path,
                                                            fleet: ft.FleetTwin) -> None:
    client = _client(tmp_path)
    frame = fleet.profiles.copy()
    frame["side"] = frame["side"].astype(object)
    frame.loc[frame.index[-1], "side"] = "up"
    data = frame.to_csv(index=False).encode()
    response = client.post("/v1/measurements/import",
                           files={"file": ("bad.csv", data, "text/csv")})
    assert response.status_code == 422
    item = response.json()["errors"][0]
    assert item["field"] == "side" and item["file"] == "bad.csv"
    assert item["line"] == len(frame) + 1  # header is line 1
    assert "up" in item["reason"]
    for table in (db.Measurement, db.ImportBatch, db.Wheel, db.Vehicle, db.RawFile):
        assert _count(client, table) == 0
    assert not [p for p in (tmp_path / "raw").rglob("*") if p.is_file()]
    # the corrected file imports afterwards
    ok = client.post("/v1/measurements/import",
                     files={"file": ("good.csv", fleet.profiles.to_csv(index=False).encode(),
                                     "text/csv")})
    assert ok.status_code == 200 and ok.json()["created"] == 32


def test_import_of_a_zip_and_of_parameter_only_rows(client: TestClient,
                                                    fleet: ft.FleetTwin) -> None:
    buffer = io.BytesIO()
    first_wheel = fleet.profiles[fleet.profiles.wheel_id == "B1-M1L"]
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("a/one.csv", first_wheel.to_csv(index=False))
    response = client.post("/v1/measurements/import",
                           files={"file": ("bundle.zip", buffer.getvalue(), "application/zip")})
    assert response.status_code == 200, response.text
    assert response.json()["created"] == 4
    params = pd.DataFrame({"wheel_id": ["P1", "P1"], "vehicle_id": ["V9", "V9"],
                           "bogie_type": ["trailer", "trailer"], "axle": [2, 2],
                           "side": ["left", "left"], "mileage_km": [0, 40_000],
                           "sd_mm": [32.5, 31.9], "sh_mm": [28.0, 28.4], "qr_mm": [10.8, 10.1]})
    response = client.post("/v1/measurements/import", files={
        "file": ("params.csv", params.to_csv(index=False).encode(), "text/csv")})
    assert response.status_code == 200, response.text
    listed = client.get("/v1/measurements", params={"kind": "parameters"}).json()
    assert listed["total"] == 2
    assert listed["items"][1]["sd_mm"] == listed["items"][1]["reported_sd_mm"] == 31.9


def test_one_measurement_as_json(client: TestClient, fleet: ft.FleetTwin) -> None:
    rows = fleet.profiles[(fleet.profiles.wheel_id == "B1-M1L")
                          & (fleet.profiles.mileage_km == 80_000)]
    body = {"wheel_id": "B1-M1L", "vehicle_id": "B1", "bogie_type": "motor", "axle": 1,
            "side": "left", "mileage_km": 80_000, "covariates": {"depot": "east"},
            "y_mm": rows.y_mm.tolist(), "z_mm": rows.z_mm.tolist(),
            "instrument_parameters": {"sd_mm": 31.2}}
    created = client.post("/v1/measurements", json=body)
    assert created.status_code == 201, created.text
    out = created.json()
    truth = fleet.truth[(fleet.truth.wheel_id == "B1-M1L") & (fleet.truth.mileage_km == 80_000)]
    assert out["tread_area_mm2"] == pytest.approx(truth.tread_area_mm2.iloc[0], rel=0.03)
    assert out["reported_sd_mm"] == 31.2 and out["sd_mm"] != 31.2
    assert out["rms_residual_mm"] < 0.05
    assert client.post("/v1/measurements", json=body).status_code == 409
    moved = client.post("/v1/measurements", json={**body, "mileage_km": 1.0, "side": "right"})
    assert moved.status_code == 422 and _field(moved) == "side"
    junk = client.post("/v1/measurements", json={**body, "mileage_km": 2.0,
                                                  "z_mm": [0.0] * len(body["y_mm"])})
    assert junk.status_code == 422 and _field(junk) == "y_mm"
    assert _count(client, db.Measurement) == 1


# --- bad input: 4xx naming the field ----------------------------------------------------

@pytest.mark.parametrize(("body", "field"), [
    ({"name": "r", "classes": [{"radius_m": 300, "direction": "left", "speed_kmh": 60,
                                "share": 0.5}]}, "classes.share"),
    ({"name": "r", "classes": [{"radius_m": 300, "direction": "up", "speed_kmh": 60,
                                "share": 1}]}, "classes[0].direction"),
    ({"name": "r", "classes": [{"radius_m": -5, "direction": "left", "speed_kmh": 60,
                                "share": 1}]}, "classes[0].radius_m"),
    ({"name": "r", "classes": [{"radius_m": 300, "speed_kmh": 60, "share": 1}]},
     "classes[0].direction"),
    ({"name": "r", "segments": [{"length_m": 0, "speed_kmh": 60}]}, "segments[0].length_m"),
    ({"name": "r"}, "classes"),  # neither classes nor segments: both named
    ({"name": "r", "classes": [{"radius_m": None, "speed_kmh": 60, "share": 1}],
      "colour": "red"}, "colour"),
])
def test_bad_routes_are_refused_naming_the_field(client: TestClient, body: dict,
                                                 field: str) -> None:
    response = client.post("/v1/routes", json=body)
    assert response.status_code == 422, response.text
    assert _field(response) == field
    assert response.json()["errors"][0]["reason"]


def test_nan_and_infinity_are_refused(client: TestClient) -> None:
    for literal in (b"NaN", b"Infinity"):
        body = (b'{"name": "r", "classes": [{"radius_m": null, "speed_kmh": ' + literal
                + b', "share": 1}]}')
        response = client.post("/v1/routes", content=body,
                               headers={"content-type": "application/json"})
        assert response.status_code == 422 and _field(response) == "classes[0].speed_kmh"


def test_route_names_are_unique_and_unknown_ids_are_404(client: TestClient) -> None:
    body = twin_routes.tangent_route("flat").to_json()
    assert client.post("/v1/routes", json=body).status_code == 201
    again = client.post("/v1/routes", json=body)
    assert again.status_code == 409 and _field(again) == "name"
    assert client.get("/v1/routes/flat").json()["classes"][0]["share"] == 1.0
    assert client.get("/v1/routes/nowhere").status_code == 404
    assert client.get("/v1/wear-tables/99").status_code == 404
    assert client.get("/v1/models/99").status_code == 404
    assert client.get("/v1/measurements/99").status_code == 404
    missing = client.post("/v1/models/99/predict", json={
        "route_id": "flat", "bogie_type": "motor", "axle": 1, "side": "left",
        "mileage_km": [1.0]})
    assert missing.status_code == 404 and _field(missing) == "model_id"


def test_wear_table_upload_and_its_refusals(client: TestClient, table_csv: bytes) -> None:
    created = client.post("/v1/wear-tables", files={"file": ("t.csv", table_csv, "text/csv")})
    assert created.status_code == 201
    table = client.get(f"/v1/wear-tables/{created.json()['id']}").json()
    assert table["n_rows"] == len(table["rows"]) == len(twin_wear_table.synthetic_wear_table())
    tangent_rows = [r for r in table["rows"] if r["rail"] == "tangent"]
    assert tangent_rows and all(r["radius_m"] is None for r in tangent_rows)
    frame = twin_wear_table.synthetic_wear_table()
    no_tangent = frame[frame.rail != "tangent"].to_csv(index=False).encode()
    bad_enum = frame.assign(region=frame.region.where(frame.index != 3, "rim"))
    for data, field in ((no_tangent, "file.rail"),
                        (bad_enum.to_csv(index=False).encode(), "file.region"),
                        (frame.drop(columns="value").to_csv(index=False).encode(),
                         "file.value"), (b"", "file")):
        response = client.post("/v1/wear-tables", files={"file": ("t.csv", data, "text/csv")})
        assert response.status_code == 422 and _field(response) == field, response.text
    assert _count(client, db.WearTable) == 1 and _count(client, db.WearTableRow) == len(frame)


def test_model_requests_refused_naming_the_field(loaded: dict, table_csv: bytes) -> None:
    client = loaded["client"]
    model_id, table_id = loaded["model"]["id"], loaded["table"]["id"]
    base = {"name": "m", "measure": "tau_max", "running_mode": "lead", "wear_table_id": table_id,
            "calibration": {"route_id": "metro", "filter": {}}}
    cases = [
        ({**base, "measure": "energy"}, 422, "measure"),
        ({**base, "running_mode": "sideways"}, 422, "running_mode"),
        ({**base, "wear_table_id": 999}, 404, "wear_table_id"),
        ({**base, "calibration": {"route_id": "nowhere"}}, 404, "calibration.route_id"),
        ({**base, "calibration": {"route_id": "metro", "filter": {"depot": "south"}}}, 422,
         "calibration.filter"),
    ]
    for body, status, field in cases:
        response = client.post("/v1/models", json=body)
        assert response.status_code == status and _field(response) == field, response.text
    predict = {"route_id": "metro", "bogie_type": "motor", "axle": 1, "side": "left",
               "mileage_km": [1000.0]}
    for change, field in (({"mileage_km": [-1.0]}, "mileage_km"),
                          ({"mileage_km": []}, "mileage_km"), ({"side": "top"}, "side"),
                          ({"route_id": None}, "route_id"),
                          ({"route_id": None, "route": {"classes": [
                              {"radius_m": 80, "direction": "left", "speed_kmh": 30,
                               "share": 1}]}}, "route.classes.radius_m")):
        response = client.post(f"/v1/models/{model_id}/predict", json={**predict, **change})
        assert response.status_code == 422 and _field(response) == field, response.text
    # a model whose table has no trailer rows refuses trailer wheels
    motor_only = twin_wear_table.synthetic_wear_table().query("bogie_type == 'motor'")
    table = client.post("/v1/wear-tables", files={
        "file": ("m.csv", motor_only.to_csv(index=False).encode(), "text/csv")}).json()
    model = client.post("/v1/models", json={**base, "name": "motors", "wear_table_id": table["id"],
                                            "calibration": {"route_id": "metro",
                                                            "filter": {"bogie_type": "motor"}}})
    assert model.status_code == 201, model.text
    refused = client.post(f"/v1/models/{model.json()['id']}/predict",
                          json={**predict, "bogie_type": "trailer"})
    assert refused.status_code == 422 and _field(refused) == "bogie_type"
    # calibrating on measurements of a bogie type the table lacks is refused too
    wrong = client.post("/v1/models", json={**base, "wear_table_id": table["id"],
                                            "calibration": {"route_id": "metro"}})
    assert wrong.status_code == 422 and _field(wrong) == "bogie_type"
    reprofile = client.post(f"/v1/models/{model_id}/reprofiling",
                            json={"route_id": "metro", "wheel_id": "nobody"})
    assert reprofile.status_code == 404 and _field(reprofile) == "wheel_id"


# --- pictures ---------------------------------------------------------------------------

def test_pictures_of_a_model(loaded: dict) -> None:
    client, model_id = loaded["client"], loaded["model"]["id"]
    where = {"route_id": "metro", "bogie_type": "motor", "axle": 1, "side": "left"}
    area = client.get(f"/v1/models/{model_id}/pictures/wear-area", params=where)
    assert area.status_code == 200 and area.headers["content-type"] == "image/svg+xml"
    assert b"<svg" in area.content[:500] and b"measured" in area.content
    profile = client.get(f"/v1/models/{model_id}/pictures/profile",
                         params={**where, "mileage_km": 130_000, "format": "png"})
    assert profile.status_code == 200 and profile.content.startswith(b"\x89PNG")
    for change, status, field in (({"axle": 3}, 422, "axle"), ({"format": "gif"}, 422, "format"),
                                  ({"route_id": "nowhere"}, 404, "route_id"),
                                  ({"bogie_type": "tram"}, 422, "bogie_type")):
        response = client.get(f"/v1/models/{model_id}/pictures/wear-area",
                              params={**where, **change})
        assert response.status_code == status and _field(response) == field, response.text
