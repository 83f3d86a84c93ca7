"""A measured wheel starts a curve-radius table and a simulation (issue 10: the physics no
longer starts from a new S1002 every time). Real MiniProf wheels from the reference data."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from tests.service.conftest import wait_for_job
from wearcast.physics import curving
from wearcast.physics.profiles.measured_wheel import MeasuredWheel
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicles import vehicle_preset
from wearcast.service.app import create_app
from wearcast.service.settings import Settings

FILES = {"whl_left_iter288.whl": "W288", "CarA_Axle1_Left.whl": "CA1L"}


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> dict:
    from tests.conftest import REFERENCE_DIR

    if not REFERENCE_DIR.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DIR}")
    names = {p.name for p in (REFERENCE_DIR / "miniprof").iterdir()}
    files = {n: w for n, w in FILES.items() if n in names}
    if not files:
        pytest.skip("no reference MiniProf wheels")
    tmp = tmp_path_factory.mktemp("mwheel")
    client = TestClient(create_app(Settings(data_dir=tmp,
                                            database_url=f"sqlite:///{tmp / 'w.db'}")))
    buffer = io.BytesIO()
    rows = ["file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km"]
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, wheel in files.items():
            archive.writestr(name, (REFERENCE_DIR / "miniprof" / name).read_bytes())
            rows.append(f"{name},{wheel},VM,motor,1,left,100000")
        archive.writestr("manifest.csv", "\n".join(rows) + "\n")
    r = client.post("/v1/measurements/import", files={"file": ("w.zip", buffer.getvalue())})
    assert r.status_code == 200, r.text
    listing = client.get("/v1/measurements", params={"wheel_id": next(iter(files.values()))})
    assert listing.status_code == 200, listing.text
    body = listing.json()
    items = body["items"] if isinstance(body, dict) else body
    return {"client": client, "measurement_id": items[0]["id"]}


def _table(client: TestClient, **extra) -> dict:
    r = client.post("/v1/wear-tables/compute", json={
        "name": "t", "vehicle": "manchester", "radii": [{"radius_m": 400},
                                                         {"radius_m": 1500}], **extra})
    assert r.status_code == 201, r.text
    return r.json()


def test_a_measured_wheel_makes_its_own_curve_radius_table(setup: dict) -> None:
    client, mid = setup["client"], setup["measurement_id"]
    nominal = _table(client)
    measured = _table(client, measurement_id=mid)
    wheel = measured["spec"]["wheel"]
    assert wheel["measurement_id"] == mid and wheel["placement"]
    assert "measured wheel" in measured["source"]
    a = np.array([row["tau_max_mpa"] if "tau_max_mpa" in row else row.get("tau_max")
                  for row in nominal["rows"]], dtype=float)
    b = np.array([row["tau_max_mpa"] if "tau_max_mpa" in row else row.get("tau_max")
                  for row in measured["rows"]], dtype=float)
    assert a.shape == b.shape and not np.allclose(a, b)  # another wheel, other contacts


def test_missing_or_unusable_measurements_are_named(setup: dict) -> None:
    client = setup["client"]
    r = client.post("/v1/wear-tables/compute", json={
        "name": "t", "vehicle": "manchester", "radii": [{"radius_m": 400}],
        "measurement_id": 999_999})
    assert r.status_code == 404 and "measurement_id" in r.text
    r = client.post("/v1/simulations", json={
        "vehicle": "metro_b", "classes": [{"radius_m": None, "speed_kmh": 70, "share": 1.0}],
        "measurement_id": 999_999})
    assert r.status_code == 404 and "measurement_id" in r.text


def test_a_simulation_starts_from_the_measured_wheel(setup: dict) -> None:
    client, mid = setup["client"], setup["measurement_id"]
    r = client.post("/v1/simulations", json={
        "vehicle": "metro_b", "law": "archard_kth", "application": "global",
        "classes": [{"radius_m": None, "speed_kmh": 70, "share": 0.6},
                    {"radius_m": 500, "cant_mm": 60, "speed_kmh": 60, "direction": "left",
                     "share": 0.4}],
        "steps": {"mode": "adaptive", "count": 1}, "measurement_id": mid})
    assert r.status_code == 202, r.text
    sim_id = r.json()["id"]
    body = wait_for_job(client, f"/v1/simulations/{sim_id}", 120.0)
    assert body["status"] == "done", body.get("error")
    start = np.array(body["result"]["profiles_mm"][0])
    y = np.array(body["result"]["y_mm"])
    resolved = body["spec"]["resolved_wheel"]
    assert resolved["measurement_id"] == mid
    # the first profile is the measured wheel (on the loop's grid), not S1002
    assert np.allclose(np.interp(y, resolved["y_mm"], resolved["z_mm"]), start, atol=1e-9)
    inside = (y > -60.0) & (y < 50.0)
    assert np.max(np.abs(start - s1002_height_mm(y))[inside]) > 0.3


def test_measured_s1002_points_reproduce_the_analytic_wheel() -> None:
    y = np.arange(-70.0, 60.01, 0.1)
    # exact points, so no smoothing: the pipeline itself must reproduce the analytic wheel
    wheel = MeasuredWheel("S1002 points", y, s1002_height_mm(y), smoothing_mm=0.0)
    vehicle = vehicle_preset("manchester", "trailer")
    cases = [curving.curve_case(r, 0.0, None, "left") for r in (300.0, 1000.0)]
    a = curving.solve_curving_cases(vehicle, cases)
    b = curving.solve_curving_cases(vehicle.with_(wheel_profile=wheel), cases)
    for x, z in zip(a, b, strict=True):
        assert np.allclose(x.wheelset_shift_mm, z.wheelset_shift_mm, atol=1e-3)
        assert np.allclose(x.t_gamma_n, z.t_gamma_n, rtol=1e-3, atol=0.05)


def test_a_profile_too_short_for_the_contact_search_is_refused() -> None:
    y = np.arange(-40.0, 40.0, 0.5)
    with pytest.raises(ValueError, match="contact search needs"):
        MeasuredWheel("short", y, s1002_height_mm(y))



def test_a_wheel_id_or_an_uploaded_profile_start_there_too(setup: dict,
                                                          reference_dir: Path) -> None:
    from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame

    client, mid = setup["client"], setup["measurement_id"]
    by_id = _table(client, measurement_id=mid)
    wheel_id = by_id["spec"]["wheel"]["wheel_id"]
    by_wheel = _table(client, wheel_id=wheel_id)
    assert by_wheel["spec"]["wheel"]["measurement_id"] == mid  # its latest (only) profile
    assert [r["value"] for r in by_wheel["rows"]] == [r["value"] for r in by_id["rows"]]
    name = "whl_left_iter288.whl"
    y, z = to_wheel_frame(parse_miniprof((reference_dir / "miniprof" / name).read_bytes(),
                                         name))
    uploaded = _table(client, profile={"y_mm": y.tolist(), "z_mm": z.tolist()})
    assert uploaded["spec"]["wheel"]["placement"].startswith("instrument datum")
    r = client.post("/v1/wear-tables/compute", json={
        "name": "t", "vehicle": "manchester", "radii": [{"radius_m": 400}],
        "measurement_id": mid, "wheel_id": wheel_id})
    assert r.status_code == 422 and "at most one of wheel_id, measurement_id" in r.text
    r = client.post("/v1/wear-tables/compute", json={
        "name": "t", "vehicle": "manchester", "radii": [{"radius_m": 400}],
        "wheel_id": "no-such-wheel"})
    assert r.status_code == 404 and "wheel_id" in r.text


def test_a_worn_wheel_on_a_measured_worn_rail_has_a_table_in_sharp_curves(setup: dict) -> None:
    """The real worn wheel (whl_left_iter288, 100,000 km here) on the real worn rail
    avg_low2.ban: stop 30 answered 422 at 250 m, the continuation repeating its last cut
    step (tests/physics/test_equilibrium_solvers.py) instead of halving it."""
    from tests.conftest import REFERENCE_DIR

    client = setup["client"]
    rail = client.post("/v1/rails/import", files={
        "file": ("avg_low2.ban", (REFERENCE_DIR / "miniprof" / "avg_low2.ban").read_bytes())})
    assert rail.status_code in (200, 201), rail.text
    body = rail.json()
    rail_id = body["created"][0]["id"] if body.get("created") else body["duplicates"][0]["id"]
    r = client.post("/v1/wear-tables/compute", json={
        "name": "worn on worn", "vehicle": "manchester", "rail_id": rail_id,
        "measurement_id": setup["measurement_id"],
        "radii": [{"radius_m": r} for r in (150, 200, 250, 300)]})
    assert r.status_code == 201, r.text
    flange = [row["value"] for row in r.json()["rows"]
              if row["region"] == "flange" and row["measure"] == "tau_max"]
    assert flange and all(np.isfinite(v) and v >= 0.0 for v in flange)
    assert max(flange) > 0.0
