"""Reprofiling starts from what was measured: a real wheel already past a limit answers
0 km with the crossed limit (whl_left_iter288.whl: qR 5.43 mm < 6.5 mm)."""

from __future__ import annotations

import io
import warnings
import zipfile
from pathlib import Path

import pytest

from tests.service.conftest import calibrate_on_metro
from wearcast.service.app import create_app
from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

FILES = {"whl_left_iter288.whl": ("W288", 120_000), "avg_wheel.whl": ("WAVG", 80_000)}


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> dict:
    from tests.conftest import REFERENCE_DIR

    if not REFERENCE_DIR.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DIR}")
    client = TestClient(create_app(Settings(data_dir=tmp_path_factory.mktemp("reprof"))))
    fleet = ft.generate_fleet(ft.metro_calibration_config())
    model = calibrate_on_metro(client, fleet.profiles, "metro", {"route_id": "metro"})["model"]
    buffer = io.BytesIO()
    rows = ["file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km"]
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, (wheel, km) in FILES.items():
            archive.writestr(name, (REFERENCE_DIR / "miniprof" / name).read_bytes())
            rows.append(f"{name},{wheel},VM,motor,1,left,{km}")
        archive.writestr("manifest.csv", "\n".join(rows) + "\n")
    imported = client.post("/v1/measurements/import",
                           files={"file": ("wheels.zip", buffer.getvalue())})
    assert imported.status_code == 200, imported.text
    return {"client": client, "model_id": model["id"]}


def _reprofiling(setup: dict, **body) -> dict:
    response = setup["client"].post(f"/v1/models/{setup['model_id']}/reprofiling",
                                    json={"route_id": "metro", **body})
    assert response.status_code == 200, response.text
    return response.json()


def test_a_wheel_past_its_qr_limit_has_zero_km_left(setup: dict) -> None:
    answer = _reprofiling(setup, wheel_id="W288")
    assert answer["remaining_km"] == {"p10": 0.0, "p50": 0.0, "p90": 0.0}
    assert answer["mileage_km"]["p50"] == 120_000
    assert answer["governing_limit"] == "qr"
    assert answer["crossed_limits"]["qr"] == pytest.approx(6.5 - 5.43, abs=0.02)
    assert answer["start_parameters_mm"]["qr_mm"] == pytest.approx(5.43, abs=0.02)
    assert "already past" in answer["reason"]
    # its shape does not fit S1002: areas start at 0 and the answer says so
    assert any("does not fit" in note for note in answer["start_notes"])


def test_a_measurement_id_or_an_uploaded_profile_start_there_too(reference_dir: Path,
                                                                 setup: dict) -> None:
    client = setup["client"]
    item = client.get("/v1/measurements", params={"wheel_id": "W288"}).json()["items"][0]
    by_id = _reprofiling(setup, measurement_id=item["id"])
    assert by_id["remaining_km"]["p50"] == 0.0 and "qr" in by_id["crossed_limits"]
    mp = parse_miniprof((reference_dir / "miniprof" / "whl_left_iter288.whl").read_bytes(),
                        "whl_left_iter288.whl")
    y, z = to_wheel_frame(mp)
    uploaded = _reprofiling(setup, profile={"y_mm": y.tolist(), "z_mm": z.tolist()},
                            bogie_type="motor", axle=1, side="left")
    assert uploaded["remaining_km"]["p50"] == 0.0
    assert uploaded["crossed_limits"]["qr"] == pytest.approx(1.07, abs=0.02)


def test_a_wheel_within_its_limits_starts_from_its_measured_parameters(setup: dict) -> None:
    new = _reprofiling(setup, bogie_type="motor", axle=1, side="left")
    worn = _reprofiling(setup, wheel_id="WAVG")
    assert worn["crossed_limits"] == {}
    assert worn["start_parameters_mm"]["qr_mm"] == pytest.approx(8.08, abs=0.02)
    assert worn["start_measurement_id"] is not None
    assert 0.0 < worn["remaining_km"]["p50"] < new["remaining_km"]["p50"]
    limit = {"sd": ("sd_mm", 22.0), "sh": ("sh_mm", 36.0), "qr": ("qr_mm", 6.5)}
    key, value = limit[worn["governing_limit"]]
    assert worn[key] == pytest.approx(value, abs=0.05)


def test_start_choices_are_exclusive(setup: dict) -> None:
    response = setup["client"].post(f"/v1/models/{setup['model_id']}/reprofiling",
                                    json={"route_id": "metro", "wheel_id": "W288",
                                          "measurement_id": 1})
    assert response.status_code == 422 and "measurement_id" in response.text


def test_wheel_pictures_draw_limits_band_and_crossing(setup: dict, tmp_path: Path) -> None:
    client = setup["client"]
    for wheel in ("W288", "WAVG"):
        response = client.get(f"/v1/wheels/{wheel}/pictures/parameters",
                              params={"model_id": setup["model_id"], "route_id": "metro"})
        assert response.status_code == 200, response.text
        assert response.headers["content-type"] == "image/svg+xml"
        text = response.text
        assert "limit min 6.5 mm" in text and "measured" in text
        if wheel == "W288":
            assert "past by 1.07 mm" in text and "crossed by 1.07 mm" in text
        else:
            assert "predicted P10" in text and "predicted crossing" in text
    png = client.get("/v1/wheels/WAVG/pictures/parameters",
                     params={"model_id": setup["model_id"], "route_id": "metro",
                             "format": "png"})
    assert png.status_code == 200 and png.content[:4] == b"\x89PNG"
    item = client.get("/v1/measurements", params={"wheel_id": "W288"}).json()["items"][0]
    profile = client.get(f"/v1/measurements/{item['id']}/pictures/profile")
    assert profile.status_code == 200
    assert "reference S1002" in profile.text and "does NOT fit" in profile.text
    assert client.get("/v1/wheels/nope/pictures/parameters", params={
        "model_id": setup["model_id"], "route_id": "metro"}).status_code == 404


def test_predict_starts_from_the_measured_wheel(setup: dict) -> None:
    client = setup["client"]
    url = f"/v1/models/{setup['model_id']}/predict"
    worn = client.post(url, json={"route_id": "metro", "wheel_id": "WAVG",
                                  "mileage_km": [0.0, 100_000.0]})
    assert worn.status_code == 200, worn.text
    body = worn.json()
    measured = body["start_parameters_mm"]
    first, later = body["points"]
    for key in ("sd_mm", "sh_mm", "qr_mm"):
        assert first[key] == pytest.approx(measured[key], abs=1e-9)
    assert later["sh_mm"] > first["sh_mm"]  # the tread wears on: Sh grows from the measured
    assert body["start_mileage_km"] == 80_000 and body["bogie_type"] == "motor"
    # avg_wheel does not fit S1002 (material above it): its areas are not used, they start
    # at 0 and the answer says so
    assert body["start_areas_mm2"] == {"flange": 0.0, "tread": 0.0}
    assert any("does not fit" in note for note in body["start_notes"])
    new = client.post(url, json={"route_id": "metro", "bogie_type": "motor", "axle": 1,
                                 "side": "left", "mileage_km": [0.0]}).json()
    assert new["start_parameters_mm"] is None
    assert new["points"][0]["qr_mm"] == pytest.approx(10.8, abs=0.05)
