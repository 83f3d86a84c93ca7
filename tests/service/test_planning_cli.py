"""``wearcast plan ...`` against a temporary database: fleet, vehicle, state, create, show."""

from __future__ import annotations

import csv
import datetime as dt
import io
import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from wearcast.service.cli import app
from wearcast.statistics.maintenance.synthetic import generate_fleet


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    (tmp_path / "fleet.csv").write_text(generate_fleet(1, seed=4).long_csv())
    # parameter-only measurements carry a diameter too
    (tmp_path / "params.csv").write_text(
        "wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,sd_mm,sh_mm,qr_mm,diameter_mm\n"
        "P1,V900,motor,1,left,1000,32.1,28.1,10.7,901.5\n")
    return tmp_path


def test_plan_cli_walk(workdir: Path) -> None:
    runner = CliRunner()
    for name in ("fleet.csv", "params.csv"):
        r = runner.invoke(app, ["import", str(workdir / name)])
        assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["plan", "fleet", "F", "--limits", '{"scrap_diameter_mm": 850}',
                            "--vehicle", "V001"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["limits"]["scrap_diameter_mm"] == 850
    r = runner.invoke(app, ["plan", "vehicle", "V001", "--km-per-day", "450"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["plan", "state", "--fleet", "F", "--format", "csv"])
    assert r.exit_code == 0, r.output
    rows = list(csv.DictReader(io.StringIO(r.stdout)))
    assert len(rows) == 8 and all(row["vehicle_id"] == "V001" for row in rows)
    r = runner.invoke(app, ["plan", "state", "--format", "json"])
    wheels = {w["wheel_id"]: w for w in json.loads(r.stdout)["wheels"]}
    assert wheels["P1"]["diameter_mm"] == 901.5 and wheels["P1"]["urgency"] == "unknown"
    out = workdir / "plan.csv"
    r = runner.invoke(app, ["plan", "create", "--fleet", "F", "--capacity", "2", "--weeks",
                            "40", "--start", dt.date(2026, 6, 1).isoformat(), "--format",
                            "csv", "--out", str(out)])
    assert r.exit_code == 0, r.output
    rows = list(csv.DictReader(out.open()))
    assert rows and {row["action"] for row in rows} <= {"turn", "replace"}
    r = runner.invoke(app, ["plan", "show", "1"])
    assert r.exit_code == 0, r.output
    plan = json.loads(r.stdout)
    assert plan["capacity_per_week"] == 2 and plan["fleet_id"] == "F"
    assert runner.invoke(app, ["plan", "show", "9"]).exit_code == 2
    bad = runner.invoke(app, ["plan", "state", "--format", "xml"])
    assert bad.exit_code == 2
    bad = runner.invoke(app, ["plan", "fleet", "G", "--limits", '{"nope": 1}'])
    assert bad.exit_code == 2 and "nope" in bad.output
