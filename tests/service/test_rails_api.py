"""``/v1/rails``: measured rail import, rail frame, head wear, and a measured rail in place of
the nominal one in curve-radius tables and simulations (issue 10 item 5)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from tests.service.conftest import sqlite_client, wait_for_job
from wearcast.physics.profiles.rails import rail_profile


def _import(client: TestClient, name: str, data: bytes, **form: str):
    return client.post("/v1/rails/import", files={"file": (name, data)}, data=form)


def _ban(x: np.ndarray, y: np.ndarray, extra_header: str = "") -> bytes:
    """A regular-layout MiniProf rail file."""
    head = (f"ProgramName=MiniProf for Windows\nDate=01/02/2024\nMPSerNo=777\n"
            f"ColumnDef=X,Y\nXYPoints={x.size}\n{extra_header}\n")
    rows = "".join(f"{a:.4f} {b:.4f}\n" for a, b in zip(x, y, strict=True))
    return (head + rows).encode()


def test_synthetic_worn_60e1_file_gives_its_wear(tmp_path: Path) -> None:
    """A 60E1 head 1.2 mm lower on top, written as an instrument that counts X towards the
    gauge side and Y downwards: read in the rail frame and measured against 60E1."""
    y, z = rail_profile("60E1", step_mm=0.25, inclination=0.0)
    z = np.minimum(z, -1.2)
    keep = z > -30.0
    x_file, y_file = -y[keep], -z[keep]  # gauge side at +X, Y down
    client = sqlite_client(tmp_path)
    r = _import(client, "worn.ban", _ban(x_file, y_file), gauge_side="positive_x",
                inclination="1/40", reference="UIC60")
    assert r.status_code == 200, r.text
    rail = r.json()["created"][0]
    assert rail["kind"] == "rail" and rail["origin"] == "instrument"
    assert (tmp_path / "raw" / rail["raw_path"]).read_bytes() == _ban(x_file, y_file)
    assert rail["frame"]["y_down"] and rail["frame"]["gauge_side"] == "positive_x"
    assert rail["frame"]["gauge_side_source"] == "request"
    assert rail["frame"]["inclination"] == pytest.approx(1 / 40)
    # the gauge point is 14 mm below the MEASURED top: z = -15.2 on the 1:20 flank from
    # (-36.0, -14.3), y = -36.045; the contact frame puts it at -35.981 and the top at 0
    assert rail["frame"]["contact_shift_mm"] == pytest.approx([0.064, 1.2], abs=0.005)
    wear = rail["wear"]
    assert wear["reference"] == "UIC60" and wear["reference_fits"]
    assert wear["vertical"]["value_mm"] == pytest.approx(1.2, abs=0.01)
    assert abs(wear["lateral"]["value_mm"]) < 0.05
    # the file's numbers come back unchanged
    got = client.get(f"/v1/rails/{rail['id']}", params={"include_points": True}).json()
    np.testing.assert_allclose(got["x_mm"], np.round(x_file, 4), atol=1e-9)
    np.testing.assert_allclose(got["y_mm"], np.round(y_file, 4), atol=1e-9)
    # the same file again creates nothing
    again = _import(client, "worn.ban", _ban(x_file, y_file), gauge_side="positive_x",
                    inclination="1/40", reference="UIC60").json()
    assert again["created"] == [] and [d["id"] for d in again["duplicates"]] == [rail["id"]]
    assert len(client.get("/v1/rails").json()) == 1


def test_header_wear_and_gauge_point_depth_are_compared(tmp_path: Path) -> None:
    y, z = rail_profile("60E1", step_mm=0.25, inclination=0.0)
    z = np.minimum(z, -0.5)
    keep = z > -30.0
    data = _ban(y[keep], z[keep], extra_header="W1=0.52\nW2=1.5\nRailGaugePoint=16\n")
    body = _import(sqlite_client(tmp_path), "w.ban", data, gauge_side="negative_x").json()
    rail = body["created"][0]
    assert rail["instrument_wear_mm"] == {"W1": 0.52, "W2": 1.5}
    text = " ".join(body["warnings"])
    assert "header W2=1.5" in text and "header W1" not in text  # 0.50 vs 0.52: agrees
    assert "RailGaugePoint=16" in text


def test_bad_rail_imports_are_4xx_naming_the_field(tmp_path: Path) -> None:
    client = sqlite_client(tmp_path)
    y, z = rail_profile("60E1", step_mm=0.5, inclination=0.0)
    good = _ban(y, z)
    r = _import(client, "empty.ban", b"")
    assert r.status_code == 422 and "file" in r.text
    r = _import(client, "wheel.whl", good)
    assert r.status_code == 422 and "measurements/import" in r.text
    r = _import(client, "r.ban", good, reference="S49")
    assert r.status_code == 422 and "reference" in r.text
    r = _import(client, "r.ban", good, inclination="steep")
    assert r.status_code == 422 and "inclination" in r.text
    r = _import(client, "r.ban", good, gauge_side="left")
    assert r.status_code == 422 and "gauge_side" in r.text
    flat = _ban(np.linspace(-40, 40, 50), np.zeros(50))
    r = _import(client, "flat.ban", flat)
    assert r.status_code == 422 and "no rail profile" in r.text
    assert client.get("/v1/rails/99").status_code == 404
    assert client.get("/v1/rails").json() == []  # nothing half-written


def test_real_rail_files_import_with_warnings(tmp_path: Path, reference_dir: Path) -> None:
    folder = reference_dir / "miniprof"
    client = sqlite_client(tmp_path)
    low = _import(client, "avg_low2.ban", (folder / "avg_low2.ban").read_bytes()).json()
    (rail,) = low["created"]
    assert rail["kind"] == "rail" and rail["n_points"] == 526
    assert rail["added_points"] == [525]  # 'add point to extend gauge face', line 578
    assert rail["frame"]["gauge_side"] == "positive_x"
    assert rail["frame"]["gauge_side_source"] == "point note"
    assert rail["header"]["ColumnDef"] == "X,Y,A,C"  # the quoted line is a comment
    text = " ".join(low["warnings"])
    assert "line 578" in text and "XYPoints=525" in text and "line 74" in text
    assert not rail["wear"]["reference_fits"]  # 76.9 mm wide: not a 60E1, said so
    assert rail["wear"]["placement"]["fitted"]
    assert rail["wear"]["lateral"]["status"] == "reference_mismatch"

    roller = _import(client, "left-roller-v1-pre-dry.ban",
                     (folder / "left-roller-v1-pre-dry.ban").read_bytes()).json()
    assert roller["created"][0]["kind"] == "roller"
    assert roller["created"][0]["frame"]["y_down"]
    assert roller["created"][0]["measured_on"] == "2015-07-08"
    assert any("roller" in w for w in roller["warnings"])

    snx = _import(client, "SNX00500.mpt", (folder / "SNX00500.mpt").read_bytes()).json()
    assert [c["part"] for c in snx["created"]] == [2]
    assert snx["created"][0]["origin"] == "drawing"
    assert snx["skipped"][0]["part"] == 1 and "34.0 mm wide" in snx["skipped"][0]["reason"]
    stock = client.get(f"/v1/rails/{snx['created'][0]['id']}",
                       params={"reference": "60E2"}).json()["wear"]
    assert stock["reference_fits"] and stock["reference"] == "60E2"
    assert stock["vertical"]["value_mm"] == pytest.approx(0.0, abs=0.01)
    assert stock["lateral"]["value_mm"] == pytest.approx(1.42, abs=0.02)
    # a stored rail as uploaded reference: the drawing against itself has no wear
    own = client.get(f"/v1/rails/{snx['created'][0]['id']}",
                     params={"reference": f"rail:{snx['created'][0]['id']}"}).json()["wear"]
    assert own["lateral"]["value_mm"] == pytest.approx(0.0, abs=1e-6)
    # repeated imports create nothing
    for name in ("avg_low2.ban", "left-roller-v1-pre-dry.ban", "SNX00500.mpt"):
        again = _import(client, name, (folder / name).read_bytes()).json()
        assert again["created"] == [] and again["duplicates"]
    assert len(client.get("/v1/rails").json()) == 3


def test_measured_rail_in_a_wear_table_and_a_simulation(tmp_path: Path,
                                                        reference_dir: Path) -> None:
    client = sqlite_client(tmp_path)
    data = (reference_dir / "miniprof" / "avg_low2.ban").read_bytes()
    rail_id = _import(client, "avg_low2.ban", data).json()["created"][0]["id"]
    request = {"vehicle": "manchester", "radii": [{"radius_m": 1000}]}
    tables = {}
    for label, extra in (("nominal", {}), ("measured", {"rail_id": rail_id})):
        r = client.post("/v1/wear-tables/compute", json={"name": label, **request, **extra})
        assert r.status_code == 201, r.text
        tables[label] = r.json()
    assert tables["measured"]["spec"]["rail"]["rail_id"] == rail_id
    assert "avg_low2" in tables["measured"]["source"]
    nominal = {(x["bogie_type"], x["wheelset"], x["rail"], x["region"], x["measure"]): x["value"]
               for x in tables["nominal"]["rows"]}
    measured = {(x["bogie_type"], x["wheelset"], x["rail"], x["region"], x["measure"]):
                x["value"] for x in tables["measured"]["rows"]}
    assert all(math.isfinite(v) and v >= 0 for v in measured.values())
    # the worn, wider low-rail head changes the contact: the 1000 m curve brings the leading
    # high-rail wheel onto its flange on the measured rail, not on the nominal 60E1
    key = ("trailer", "leading", "high", "flange", "t_gamma")
    assert nominal[key] == 0.0 and measured[key] > 10.0
    contacts = client.get(f"/v1/wear-tables/{tables['measured']['id']}/contacts").json()
    loaded = [c for c in contacts["contacts"] if c["normal_force_n"] > 1.0]
    # every loaded contact lies on the measured head (its contact frame: gauge point at
    # y = -35.98, the head reaching 40 mm to the field side)
    assert loaded and all(-38.0 < c["rail_y_mm"] < 42.0 for c in loaded)
    # a short simulation on the measured rail: finite, and not the nominal rail's
    tiny = {"vehicle": "metro_b", "classes": [
        {"radius_m": None, "speed_kmh": 70, "share": 0.6},
        {"radius_m": 500, "cant_mm": 60, "speed_kmh": 60, "direction": "left", "share": 0.4}],
        "steps": {"mode": "adaptive", "count": 1, "depth_per_step_mm": 0.1}}
    results = {}
    for label, extra in (("nominal", {}), ("measured", {"rail_id": rail_id})):
        r = client.post("/v1/simulations", json={**tiny, **extra})
        assert r.status_code == 202, r.text
        body = wait_for_job(client, f"/v1/simulations/{r.json()['id']}", 120.0)
        assert body["status"] == "done", body
        results[label] = body
    assert results["measured"]["spec"]["resolved_rail"]["rail_id"] == rail_id
    worn = {k: np.asarray(v["result"]["profiles_mm"][-1]) - np.asarray(
        v["result"]["profiles_mm"][0]) for k, v in results.items()}
    km = {k: v["result"]["mileage_km"][-1] for k, v in results.items()}
    assert np.all(np.isfinite(worn["measured"])) and worn["measured"].min() < 0
    assert math.isfinite(km["measured"]) and km["measured"] > 0
    # the measured low rail's gauge-side kink (11.8 mm below its top) meets the flange root
    # in the 500 m curve: the 0.1 mm step is worn in a small fraction of the nominal mileage
    assert km["measured"] < 0.5 * km["nominal"]
    assert np.max(np.abs(worn["measured"] - worn["nominal"])) > 0.05
    assert client.post("/v1/simulations", json={**tiny, "rail_id": 999}).status_code == 404


def test_high_and_low_measured_rails_of_their_own(tmp_path: Path, reference_dir: Path) -> None:
    """``high_rail_id`` / ``low_rail_id``: the outer and inner rail of every curve (the curving
    contact per side), tangent track on ``rail_id`` or the nominal rail."""
    client = sqlite_client(tmp_path)
    data = (reference_dir / "miniprof" / "avg_low2.ban").read_bytes()
    rail_id = _import(client, "avg_low2.ban", data).json()["created"][0]["id"]
    request = {"vehicle": "manchester", "radii": [{"radius_m": 1000}]}

    def table(name: str, **rails: int) -> tuple[dict, dict]:
        r = client.post("/v1/wear-tables/compute", json={"name": name, **request, **rails})
        assert r.status_code == 201, r.text
        body = r.json()
        return body, {(x["radius_m"], x["bogie_type"], x["wheelset"], x["rail"], x["region"],
                       x["measure"]): x["value"] for x in body["rows"]}

    _, nominal = table("nominal")
    _, everywhere = table("everywhere", rail_id=rail_id)
    pair_body, pair = table("pair", high_rail_id=rail_id, low_rail_id=rail_id)
    high_body, high_only = table("high", high_rail_id=rail_id)
    assert pair_body["spec"]["rail"]["high_rail"]["rail_id"] == rail_id
    assert pair_body["spec"]["rail"]["low_rail"]["rail_id"] == rail_id
    assert "rail_id" not in pair_body["spec"]["rail"]  # tangent track: the nominal rail
    assert "high measured rail avg_low2" in high_body["source"]
    curve = [k for k in nominal if k[0] is not None]
    tangent = [k for k in nominal if k[0] is None]
    assert curve and tangent
    # the same measured rail on both sides of the curve: the curve rows of the table that
    # lays it everywhere; tangent track keeps the nominal rail's rows
    assert {k: pair[k] for k in curve} == pytest.approx({k: everywhere[k] for k in curve},
                                                        rel=1e-9, abs=1e-12)
    assert {k: pair[k] for k in tangent} == pytest.approx({k: nominal[k] for k in tangent},
                                                          rel=1e-9, abs=1e-12)
    # the worn head as the high rail alone brings the leading high-rail wheel onto its
    # flange at 1000 m (test above), and the table differs from both single-rail ones
    key = (1000.0, "trailer", "leading", "high", "flange", "t_gamma")
    assert nominal[key] == 0.0 and high_only[key] > 10.0
    assert any(high_only[k] != pytest.approx(everywhere[k], rel=1e-6) for k in curve)
    # an unknown rail is a 404 naming its field, for tables and simulations
    for path, body in (("/v1/wear-tables/compute", {"name": "x", **request}),
                       ("/v1/simulations", {"vehicle": "metro_b", "classes": [
                           {"radius_m": None, "speed_kmh": 70, "share": 1.0}]})):
        for field in ("high_rail_id", "low_rail_id"):
            r = client.post(path, json={**body, field: 999})
            assert r.status_code == 404, r.text
            assert [e["field"] for e in r.json()["errors"]] == [field]
    # a short simulation on the measured high rail: the spec records it, the wheel wears
    tiny = {"vehicle": "metro_b", "classes": [
        {"radius_m": None, "speed_kmh": 70, "share": 0.6},
        {"radius_m": 500, "cant_mm": 60, "speed_kmh": 60, "direction": "left", "share": 0.4}],
        "steps": {"mode": "adaptive", "count": 1, "depth_per_step_mm": 0.1}}
    r = client.post("/v1/simulations", json={**tiny, "high_rail_id": rail_id})
    assert r.status_code == 202, r.text
    done = wait_for_job(client, f"/v1/simulations/{r.json()['id']}", 120.0)
    assert done["status"] == "done", done
    assert done["spec"]["resolved_high_rail"]["rail_id"] == rail_id
    assert "resolved_rail" not in done["spec"] and "resolved_low_rail" not in done["spec"]
    worn = np.asarray(done["result"]["profiles_mm"][-1]) - np.asarray(
        done["result"]["profiles_mm"][0])
    assert np.all(np.isfinite(worn)) and worn.min() < 0
