"""The ``wearcast`` CLI drives the same service layer as the API, on WEARCAST_DATA_DIR."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from wearcast.service.cli import app
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes, twin_wear_table


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    fleet = ft.generate_fleet(ft.FleetConfig(
        units=(ft.UnitConfig("C", twin_routes.metro_route(), running_mode="lead"),),
        mileages_km=(40_000, 100_000, 160_000), mileage_jitter_km=0.0, rate_scatter=0.0,
        area_scatter=0.0, points_per_profile=200, seed=11))
    fleet.profiles.to_csv(tmp_path / "fleet.csv", index=False)
    twin_wear_table.synthetic_wear_table().to_csv(tmp_path / "table.csv", index=False)
    (tmp_path / "route.json").write_text(json.dumps(twin_routes.metro_route().to_json()))
    return tmp_path


def _json(output: str) -> dict:
    return json.loads(output[output.index("{"):])


def test_cli_walk_import_calibrate_predict_reprofile(workdir: Path) -> None:
    runner = CliRunner()
    imported = runner.invoke(app, ["import", str(workdir / "fleet.csv")])
    assert imported.exit_code == 0, imported.output
    assert _json(imported.stdout)["created"] == 24
    again = runner.invoke(app, ["import", str(workdir / "fleet.csv")])
    assert _json(again.stdout)["duplicate"] is True
    assert runner.invoke(app, ["route", str(workdir / "route.json")]).exit_code == 0
    table = runner.invoke(app, ["wear-table", str(workdir / "table.csv")])
    assert table.exit_code == 0, table.output
    model = runner.invoke(app, ["calibrate", "--name", "cli", "--wear-table-id",
                                str(_json(table.stdout)["id"]), "--route", "metro",
                                "--running-mode", "lead"])
    assert model.exit_code == 0, model.output
    summary = _json(model.stdout)["summary"]
    assert summary["tread"]["c_s"] == pytest.approx(1.5e-6, rel=0.03)
    picture = workdir / "area.svg"
    predicted = runner.invoke(app, ["predict", "1", "--route", "metro", "--bogie-type", "motor",
                                    "--axle", "1", "--side", "left", "--mileage-km", "50000",
                                    "--mileage-km", "150000", "--picture", str(picture)])
    assert predicted.exit_code == 0, predicted.output
    assert "150,000" in predicted.stdout
    assert picture.read_bytes().lstrip().startswith(b"<?xml")
    profile = workdir / "profile.png"
    drawn = runner.invoke(app, ["picture", "1", "profile", str(profile), "--route", "metro",
                                "--bogie-type", "motor", "--axle", "1", "--side", "left",
                                "--mileage-km", "100000"])
    assert drawn.exit_code == 0, drawn.output
    assert profile.read_bytes().startswith(b"\x89PNG")
    remaining = runner.invoke(app, ["reprofile", "1", "--route", "metro", "--wheel-id",
                                    "C1-M1L"])
    assert remaining.exit_code == 0, remaining.output
    assert _json(remaining.stdout)["start_mileage_km"] == 160_000


def test_cli_reports_the_field_of_bad_input(workdir: Path) -> None:
    runner = CliRunner()
    bad = workdir / "bad.csv"
    bad.write_text((workdir / "fleet.csv").read_text().replace(",left,", ",upper,", 1))
    result = runner.invoke(app, ["import", str(bad)])
    assert result.exit_code == 2
    assert "side" in result.stderr and "bad.csv" in result.stderr
    result = runner.invoke(app, ["predict", "7", "--route", "metro", "--bogie-type", "tram",
                                 "--axle", "1", "--side", "left", "--mileage-km", "1"])
    assert result.exit_code == 2 and "bogie_type" in result.stderr
    result = runner.invoke(app, ["reprofile", "7", "--route", "metro", "--wheel-id", "x"])
    assert result.exit_code == 2 and "model_id" in result.stderr
