"""``wearcast physics build`` / ``diagnose`` against a temporary database.

The measurements come from the whole-vehicle loop itself (metro_b on two 250 m curves and
tangent track, USFD, D_step 1 mm, 2,000 km) at a wear scale of 1.2: every wheel of two
vehicles at 0 km and four mileages, imported as a parameter CSV through ``wearcast import``,
the route through ``wearcast route``. The CLI's model must recover the scale and be
diagnosed; bad input exits 2 naming the field.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from wearcast.physics.vocabulary import CurveClass
from wearcast.service.cli import app
from wearcast.statistics.generators.scenarios import cached_vehicle_simulator

ROUTE = {"name": "curvy", "classes": [
    {"radius_m": 250, "direction": "left", "cant_mm": 100, "speed_kmh": 60, "share": 0.15},
    {"radius_m": 250, "direction": "right", "cant_mm": 100, "speed_kmh": 60, "share": 0.15},
    {"radius_m": None, "speed_kmh": 100, "share": 0.7}]}
LOOP_ROUTE = [CurveClass(250.0, 100.0, 60.0, "left", 0.15),
              CurveClass(250.0, 100.0, 60.0, "right", 0.15),
              CurveClass(None, 0.0, 100.0, share=0.7)]
RUN_KM = 2000.0
SCALE = 1.2
SIMULATION = json.dumps({"depth_per_step_mm": 1.0, "mileage_km": RUN_KM})


def _measurements_csv(path: Path) -> None:
    truth = cached_vehicle_simulator(LOOP_ROUTE, "metro_b", law="usfd", mileage_km=RUN_KM,
                                     depth_per_step_mm=1.0)({})
    rng = np.random.default_rng(3)
    lines = ["wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,sd_mm,sh_mm,qr_mm"]
    for v in range(2):
        for km in np.concatenate([[0.0], np.sort(rng.uniform(200.0, 1500.0, 4))]):
            for j, wheel in enumerate(truth.wheels):      # e.g. "motor0-1R"
                bogie = "motor" if wheel.startswith("motor") else "trailer"
                side = "left" if wheel.endswith("L") else "right"
                values = [float(np.interp(SCALE * km, truth.mileage_km, getattr(truth, q)[:, j])
                                + rng.normal(0, 0.02)) for q in ("sd_mm", "sh_mm", "qr_mm")]
                lines.append(f"V{v}-{wheel},V{v},{bogie},{wheel[-2]},{side},{km:.1f},"
                             + ",".join(f"{x:.4f}" for x in values))
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("physics_cli")


@pytest.fixture
def loaded(workdir: Path, monkeypatch: pytest.MonkeyPatch) -> CliRunner:
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(workdir / "data"))
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    runner = CliRunner()
    if not (workdir / "route.json").exists():
        (workdir / "route.json").write_text(json.dumps(ROUTE))
        _measurements_csv(workdir / "params.csv")
        for command in (["route", str(workdir / "route.json")],
                        ["import", str(workdir / "params.csv")]):
            r = runner.invoke(app, command)
            assert r.exit_code == 0, r.output
    return runner


def test_build_and_diagnose_a_physics_model(loaded: CliRunner) -> None:
    r = loaded.invoke(app, ["physics", "build", "--name", "cli", "--route", "curvy",
                            "--vehicle", "metro_b", "--simulation", SIMULATION, "--json"])
    assert r.exit_code == 0, r.output
    model = json.loads(r.stdout)
    assert model["kind"] == "physics" and model["name"] == "cli"
    physics = model["physics"]
    assert physics["wear_scale"] == pytest.approx(SCALE, rel=0.03)
    assert physics["calibrated_on"]["vehicles"] == ["V0", "V1"]
    assert {e["quantity"] for e in physics["errors"]["overall"]} == {"FT_mm", "FH_mm",
                                                                       "QR_mm"}
    r = loaded.invoke(app, ["physics", "diagnose", str(model["id"]), "--cause", "patch_model",
                            "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["model_id"] == model["id"] and [f["cause"] for f in d["findings"]] == [
        "patch_model"]
    assert d["findings"][0]["gain"]["metric"] == "ft_fh_qr_squared_error_mm2"
    assert d["null_fit"]["wear_scale"] == pytest.approx(SCALE, rel=0.03)
    r = loaded.invoke(app, ["physics", "diagnose", str(model["id"]), "--cause",
                            "patch_model"])
    assert r.exit_code == 0 and "patch_model" in r.output and "verdict" in r.output


def test_bad_input_exits_2_naming_the_field(loaded: CliRunner) -> None:
    def error(*args: str) -> str:
        r = loaded.invoke(app, ["physics", *args])
        assert r.exit_code == 2, r.output
        return r.output

    assert "vehicle" in error("build", "--name", "x", "--route", "curvy", "--vehicle", "tram")
    assert "route_id" in error("build", "--name", "x", "--route", "nowhere", "--vehicle",
                               "metro_b")
    assert "simulation" in error("build", "--name", "x", "--route", "curvy", "--vehicle",
                                 "metro_b", "--simulation", "[1]")
    assert "calibration.filter" in error("build", "--name", "x", "--route", "curvy",
                                         "--vehicle", "metro_b", "--filter",
                                         '{"vehicle_id": "none"}')
    for flag, field in (("--rail-id", "rail_id"), ("--high-rail-id", "high_rail_id"),
                        ("--low-rail-id", "low_rail_id")):
        assert field in error("build", "--name", "x", "--route", "curvy", "--vehicle",
                              "metro_b", flag, "999")
    assert "model_id" in error("diagnose", "999")
    assert "causes[0]" in error("diagnose", "1", "--cause", "traction")


def test_build_on_a_measured_high_rail(loaded: CliRunner, reference_dir: Path) -> None:
    r = loaded.invoke(app, ["rail-import", str(reference_dir / "miniprof" / "avg_low2.ban")])
    assert r.exit_code == 0, r.output
    body = json.loads(r.stdout[r.stdout.index("{"):])
    rail_id = (body["created"] or body["duplicates"])[0]["id"]
    r = loaded.invoke(app, ["physics", "build", "--name", "high", "--route", "curvy",
                            "--vehicle", "metro_b", "--simulation", SIMULATION,
                            "--high-rail-id", str(rail_id)])
    assert r.exit_code == 0, r.output
    assert f"high rail: stored rail {rail_id} (avg_low2.ban)" in r.output
