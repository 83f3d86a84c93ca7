"""``wearcast rail-import`` / ``wearcast rails`` / ``--rail-id``: the rail walk-through of the
README on the real MiniProf rail files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from wearcast.service import cli as cli_module
from wearcast.service.cli import app


@pytest.fixture
def datadir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    monkeypatch.setenv("COLUMNS", "160")
    # the CLI's console is made when wearcast.service.cli is first imported (by whichever
    # test comes first in this process); give it the width too
    monkeypatch.setattr(cli_module.console, "width", 160)
    return tmp_path


def _json(output: str) -> dict:
    return json.loads(output[output.index("{"):])


def test_cli_rail_walk_through(datadir: Path, reference_dir: Path) -> None:
    runner = CliRunner()
    folder = reference_dir / "miniprof"
    low = runner.invoke(app, ["rail-import", str(folder / "avg_low2.ban")])
    assert low.exit_code == 0, low.output
    body = _json(low.stdout)
    assert body["created"][0]["wear"]["reference_fits"] is False
    assert body["created"][0]["head_width_mm"] == pytest.approx(76.776, abs=0.01)
    snx = runner.invoke(app, ["rail-import", str(folder / "SNX00500.mpt"),
                              "--reference", "60E2"])
    assert snx.exit_code == 0, snx.output
    wear = _json(snx.stdout)["created"][0]["wear"]
    assert wear["reference"] == "60E2" and wear["W3_45deg_mm"] == pytest.approx(0.109, abs=0.01)
    again = runner.invoke(app, ["rail-import", str(folder / "SNX00500.mpt")])
    assert _json(again.stdout)["created"] == []
    listing = runner.invoke(app, ["rails", "--reference", "60E2"])
    assert listing.exit_code == 0, listing.output
    assert "SNX00500.mpt#2" in listing.stdout and "1.42" in listing.stdout
    bad = runner.invoke(app, ["rail-import", str(folder / "avg_low2.ban"),
                              "--gauge-side", "left"])
    assert bad.exit_code == 2 and "gauge_side" in bad.output
    missing = runner.invoke(app, ["wear-table-compute", "--name", "x", "--vehicle",
                                  "manchester", "--radius", "1000", "--rail-id", "9"])
    assert missing.exit_code == 2 and "rail_id" in missing.output
    for flag, field in (("--high-rail-id", "high_rail_id"), ("--low-rail-id", "low_rail_id")):
        missing = runner.invoke(app, ["wear-table-compute", "--name", "x", "--vehicle",
                                      "manchester", "--radius", "1000", flag, "9"])
        assert missing.exit_code == 2 and field in missing.output, missing.output
    rail_id = str(body["created"][0]["id"])
    high = runner.invoke(app, ["wear-table-compute", "--name", "high", "--vehicle",
                               "manchester", "--radius", "1000", "--high-rail-id", rail_id])
    assert high.exit_code == 0, high.output
    assert _json(high.stdout)["spec"]["rail"]["high_rail"]["rail_id"] == int(rail_id)
