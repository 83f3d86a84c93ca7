"""CLI: ``wear-table-compute``, ``diagnose`` and ``simulate`` on WEARCAST_DATA_DIR."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from wearcast.service.cli import app
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators import twin_wear_table


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    return tmp_path


def _json(output: str) -> dict:
    return json.loads(output[output.index("{"):])


def test_cli_wear_table_compute(workdir: Path) -> None:
    runner = CliRunner()
    out_csv = workdir / "t.csv"
    result = runner.invoke(app, ["wear-table-compute", "--name", "r", "--vehicle",
                                 "metro_b,manchester", "--radius", "400:80",
                                 "--radius", "1200:40:90", "--csv", str(out_csv)])
    assert result.exit_code == 0, result.output
    body = _json(result.stdout)
    assert body["kind"] == "computed" and body["n_rows"] > 0
    table = pd.read_csv(out_csv)
    assert len(table) == body["n_rows"]
    assert set(table["radius_m"].dropna()) == {400.0, 1200.0}
    bad = runner.invoke(app, ["wear-table-compute", "--name", "x", "--vehicle", "tgv",
                              "--radius", "300"])
    assert bad.exit_code == 2 and "vehicle" in bad.stderr and "minuetto" in bad.stderr


def test_cli_simulate(workdir: Path) -> None:
    runner = CliRunner()
    out = workdir / "sim.json"
    result = runner.invoke(app, ["simulate", "--vehicle", "metro_b", "--class",
                                 "tangent:0:70:0.6", "--class", "500:60:60:0.4:left",
                                 "--steps", "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    body = json.loads(out.read_text())
    assert body["status"] == "done" and len(body["result"]["mileage_km"]) == 3
    bad = runner.invoke(app, ["simulate", "--vehicle", "metro_b", "--class", "500:60"])
    assert bad.exit_code == 2


def test_cli_diagnose_with_report_and_save(workdir: Path) -> None:
    table = twin_wear_table.synthetic_wear_table()
    cfg = te.scenario_config(seed=0, wear_effects=(te.traction(1.3),))
    twin = ft.generate_fleet(cfg, table)
    twin.profiles.to_csv(workdir / "fleet.csv", index=False)
    table.to_csv(workdir / "table.csv", index=False)
    runner = CliRunner()
    for unit in cfg.units:
        path = workdir / f"{unit.route.name}.json"
        if not path.exists():
            path.write_text(json.dumps(unit.route.to_json()))
            assert runner.invoke(app, ["route", str(path)]).exit_code == 0
    assert runner.invoke(app, ["import", str(workdir / "fleet.csv")]).exit_code == 0
    made = runner.invoke(app, ["wear-table", str(workdir / "table.csv")])
    table_id = _json(made.stdout)["id"]
    model = runner.invoke(app, ["calibrate", "--name", "m", "--wear-table-id", str(table_id),
                                "--route", "aosta", "--filter",
                                json.dumps({"vehicle_id": ["A1", "A2", "A3"],
                                            "bogie_type": "motor"})])
    assert model.exit_code == 0, model.output
    model_id = _json(model.stdout)["id"]
    report = workdir / "report.html"
    result = runner.invoke(app, ["diagnose", str(model_id), "--report", str(report),
                                 "--save-as", "with traction", "--cause", "traction",
                                 "--cause", "vehicle_load"])
    assert result.exit_code == 0, result.output
    assert "verdict traction" in result.stdout and "saved the extended model" in result.stdout
    assert "<svg" in report.read_text()
    bad = runner.invoke(app, ["diagnose", str(model_id), "--filter", "[1]"])
    assert bad.exit_code == 2
