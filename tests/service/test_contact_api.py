"""``POST /v1/contact``: the loaded wheel-rail contact at given poses over HTTP."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from tests.service.conftest import sqlite_client
from wearcast.physics.contact.geometry import s1002_60e1
from wearcast.physics.contact.pose_contact import Pose, contact_at_poses


@pytest.fixture
def client(tmp_path: Path) -> TestClient:
    return sqlite_client(tmp_path)


def test_s1002_on_60e1_answers_what_the_physics_computes(client):
    body = {"poses": [{"shift_mm": 0.0}, {"shift_mm": 7.0, "yaw_rad": 0.002,
                                          "wheel_load_n": 40_000}]}
    r = client.post("/v1/contact", json=body)
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["wheel"]["source"].startswith("S1002") and out["rail"]["source"] == "60E1"
    direct = contact_at_poses(s1002_60e1(), "left",
                              [Pose(0.0), Pose(7.0, 0.002, None, 40_000.0)])
    for got, want in zip(out["poses"], direct, strict=True):
        w = want.to_dict()
        assert got["n_patches"] == w["n_patches"] and got["roll_solved"]
        assert got["vertical_force_n"] == pytest.approx(w["wheel_load_n"], rel=2e-4)
        for pg, pw in zip(got["patches"], w["patches"], strict=True):
            assert pg["y_wheel_mm"] == pytest.approx(pw["y_wheel_mm"], abs=1e-9)
            assert pg["fx_n"] == pytest.approx(pw["fx_n"], rel=1e-9, abs=1e-9)


def test_contact_files_are_read_from_the_request(client, reference_dir):
    bench = reference_dir / "contact-benchmark"
    body = {"wheel_file": {"text": (bench / "MBench_S1002_v3.prw").read_text()},
            "rail_file": {"text": (bench / "MBench_UIC60_v3.prr").read_text()},
            "inclination": 0.0, "shear_modulus_mpa": 82_000,
            "poses": [{"shift_mm": 7.0, "yaw_rad": 0.0084, "roll_rad": 0.0}]}
    r = client.post("/v1/contact", json=body)
    assert r.status_code == 200, r.text
    pose = r.json()["poses"][0]
    assert not pose["roll_solved"] and pose["n_patches"] == 1
    assert abs(pose["patches"][0]["contact_angle_rad"]) > 0.9  # on the flank (> 52 deg)


@pytest.mark.parametrize(("body", "field"), [
    ({"poses": []}, "poses"),
    ({"poses": [{"shift_mm": 40}]}, "poses.0.shift_mm"),
    ({"poses": [{"shift_mm": 0}], "side": "middle"}, "side"),
    ({"poses": [{"shift_mm": 0}], "wheel_file": {"text": "nonsense"}}, "wheel_file.text"),
    ({"poses": [{"shift_mm": 0}], "rail_file": {"text": "x"}, "rail_id": 3}, "rail_id"),
    ({"poses": [{"shift_mm": 0}], "measurement_id": 12345}, "measurement_id"),
    ({"poses": [{"shift_mm": 0}], "normal_method": "magic"}, "normal_method"),
    # one wheel's contact takes one rail: the curving requests' high/low rails are refused
    ({"poses": [{"shift_mm": 0}], "high_rail_id": 1}, "high_rail_id"),
])
def test_bad_requests_name_the_field(client, body, field):
    r = client.post("/v1/contact", json=body)
    assert 400 <= r.status_code < 500, r.text
    text = r.text
    assert field.split(".")[0] in text


def test_a_wheel_off_its_rail_is_a_422(client):
    y = [45.0 + 0.5 * k for k in range(31)]
    body = {"profile": {"y_mm": y, "z_mm": [0.0] * len(y)}, "poses": [{"shift_mm": 0.0}]}
    r = client.post("/v1/contact", json=body)
    assert r.status_code == 422, r.text


def test_the_command_line_prints_the_same_patches():
    from typer.testing import CliRunner

    from wearcast.service.cli import app

    result = CliRunner().invoke(app, ["contact", "--shift", "0,7", "--json"])
    assert result.exit_code == 0, result.output
    import json

    poses = json.loads(result.output)["poses"]
    direct = contact_at_poses(s1002_60e1(), "left", [Pose(0.0), Pose(7.0)])
    assert [p["patches"][0]["y_wheel_mm"] for p in poses] == pytest.approx(
        [d.to_dict()["patches"][0]["y_wheel_mm"] for d in direct], abs=1e-9)
    bad = CliRunner().invoke(app, ["contact", "--shift", "50"])
    assert bad.exit_code == 2 and "shift_mm" in bad.output


def test_the_fine_bem_takes_at_most_max_fine_bem_poses(tmp_path):
    """``normal_method: bem`` costs ~0.15 s of one core per pose on S1002 (up to seconds on
    measured wheels): more poses than the setting allows are a 422 naming ``poses`` and the
    limit, before anything is computed; as many as it allows are answered, and the other
    methods keep the schema's 100."""
    from tests.service.conftest import sqlite_settings
    from wearcast.service.app import create_app

    settings = sqlite_settings(tmp_path).model_copy(update={"max_fine_bem_poses": 2})
    client = TestClient(create_app(settings))
    three = [{"shift_mm": s} for s in (0.0, 1.0, 2.0)]
    r = client.post("/v1/contact", json={"poses": three, "normal_method": "bem"})
    assert r.status_code == 422, r.text
    item = r.json()["errors"][0]
    assert item["field"] == "poses"
    assert item["limit"] == "max_fine_bem_poses" and item["limit_value"] == 2
    r = client.post("/v1/contact", json={"poses": three[:2], "normal_method": "bem"})
    assert r.status_code == 200, r.text
    assert len(r.json()["poses"]) == 2
    r = client.post("/v1/contact", json={"poses": three, "normal_method": "bem-coarse"})
    assert r.status_code == 200, r.text
