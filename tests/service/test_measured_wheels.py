"""The nine real MiniProf wheels (CONTACT test bank, ../shared/reference/miniprof) through
``POST /v1/measurements/import``: kept on the instrument's datum, wear taken against a named
reference and flagged when the shape does not fit it, warnings per file and line."""

from __future__ import annotations

import io
import warnings
import zipfile
from pathlib import Path

import pytest

from tests.service.conftest import import_miniprof
from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.service.app import create_app
from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame
from wearcast.service.settings import Settings
from wearcast.statistics.cleaning import clean_profile
from wearcast.statistics.processing import process_profile

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

NAMES = ("Car7216_0001r.whl", "Car7358_0001r.whl", "Car7422_0001r.whl", "Car7813_0001r.whl",
         "avg_wheel.whl", "left-wheel-v1-pre-dry.whl", "right-wheel-v1-pre-dry.whl",
         "whl_left_iter288.whl", "whl_left_iter795.whl")
# old-style headers print the template's 32.58/37.11/14.71, which the points do not match
PLACEHOLDER_HEADERS = {n for n in NAMES if n.startswith("Car") or n == "avg_wheel.whl"}


def _zip(reference_dir: Path) -> bytes:
    """The nine files and a ';' manifest as a European spreadsheet writes it, sides and
    bogies spelled L/R/rechts and T/M."""
    rows = ["file;wheel_id;vehicle_id;bogie_type;axle;side;mileage_km;reference_profile"]
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for i, name in enumerate(NAMES):
            archive.writestr(name, (reference_dir / "miniprof" / name).read_bytes())
            side = "rechts" if name.startswith("right") else ("R" if name.startswith("Car")
                                                              else "L")
            rows.append(f"{name};{name.split('.')[0]};V{i};{'M' if i % 2 else 'T'};1;{side};"
                        f"{1000 * i},5;S1002")
        archive.writestr("manifest.csv", "\n".join(rows) + "\n")
    return buffer.getvalue()


@pytest.fixture(scope="module")
def imported(tmp_path_factory: pytest.TempPathFactory) -> tuple[TestClient, dict, bytes]:
    from tests.conftest import REFERENCE_DIR

    if not REFERENCE_DIR.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DIR}")
    client = TestClient(create_app(Settings(data_dir=tmp_path_factory.mktemp("measured"))))
    upload = _zip(REFERENCE_DIR)
    response = client.post("/v1/measurements/import",
                           files={"file": ("miniprof.zip", upload)})
    assert response.status_code == 200, response.text
    return client, response.json(), upload


def _items(client: TestClient) -> dict[str, dict]:
    items = client.get("/v1/measurements", params={"limit": 100}).json()["items"]
    return {item["source_file"].split(":")[-1]: item for item in items}


def _raw_parameters(reference_dir: Path, name: str):
    mp = parse_miniprof((reference_dir / "miniprof" / name).read_bytes(), name)
    y, z = to_wheel_frame(mp)
    cleaned = clean_profile(y, z)
    return y, z, flange_parameters(cleaned.y_mm, cleaned.z_mm)


def test_every_wheel_keeps_its_lateral_datum_and_measured_parameters(
        reference_dir: Path, imported) -> None:
    client, answer, _ = imported
    assert answer["created"] == 9
    items = _items(client)
    for name in NAMES:
        item = items[name]
        y, z, raw = _raw_parameters(reference_dir, name)
        # the wear alignment: no lateral shift, no free rotation
        assert abs(item["lateral_shift_mm"]) < 0.5, name
        assert abs(item["rotation_rad"]) < 5e-3, name
        assert item["placement"]["alignment"] == "datum"
        for key, value in (("sd_mm", raw.sd_mm), ("sh_mm", raw.sh_mm), ("qr_mm", raw.qr_mm)):
            assert item[key] == pytest.approx(value, abs=0.2), (name, key)
        # the profile the wear is computed on has the measured Sd/Sh/qR too
        p = process_profile(y, z, alignment="datum")
        on_wear = flange_parameters(p.y_aligned_mm, p.z_aligned_mm)
        assert (on_wear.sd_mm, on_wear.sh_mm, on_wear.qr_mm) == pytest.approx(
            (raw.sd_mm, raw.sh_mm, raw.qr_mm), abs=0.2), name
        # the stored points are the file's
        stored = client.get(f"/v1/measurements/{item['id']}").json()
        assert stored["y_mm"][:3] == pytest.approx(y[:3].tolist(), abs=1e-4)


def test_no_wheel_gets_negative_wear_and_mismatches_are_flagged(imported) -> None:
    client, _, _ = imported
    items = _items(client)
    for name, item in items.items():
        assert item["reference_profile"] == "S1002"
        if item["reference_fits"]:
            # within the noise of the vertical datum (0.05 mm over the 80 mm tread)
            assert item["flange_area_mm2"] > -5.0 and item["tread_area_mm2"] > -5.0, name
        else:
            assert item["flange_area_mm2"] is None and item["tread_area_mm2"] is None, name
            assert any(w["code"] == "reference_mismatch" for w in item["warnings"]), name
    # none of the nine is S1002 as measured: the 36 mm flanges, the worn Car* wheels (flange
    # back off S1002, treads above it) and avg_wheel (0.46 mm above S1002 over y = -32 … 2)
    for name in NAMES:
        assert items[name]["reference_fits"] is False, name
    flagged = client.get("/v1/measurements", params={"reference_fits": "false"}).json()
    assert flagged["total"] == 9


def test_the_import_answer_warns_per_file_and_line(imported) -> None:
    _, answer, _ = imported
    by_file: dict[str, set[str]] = {}
    for w in answer["warnings"]:
        assert w["file"].startswith("miniprof.zip:") and w["line"] >= 2
        assert w["level"] in ("info", "warning") and w["message"]
        by_file.setdefault(w["file"].split(":")[-1], set()).add(w["code"])
    for name in NAMES:
        codes = by_file[name]
        assert ("header_parameters" in codes) == (name in PLACEHOLDER_HEADERS), name
        assert codes & {"datum_found", "datum_guessed"}, name
        assert "wear_alignment" in codes
    for name in NAMES:
        if name.startswith("Car"):
            assert "reference_mismatch" in by_file[name]
    assert "datum_guessed" in by_file["avg_wheel.whl"]  # starts 1.55 mm off the back face
    assert "datum_found" in by_file["whl_left_iter288.whl"]
    assert "points_dropped" in by_file["Car7216_0001r.whl"]
    assert answer["warnings_total"] == len(answer["warnings"])


def test_a_repeated_import_creates_nothing_and_repeats_the_warnings(imported) -> None:
    client, answer, upload = imported
    again = client.post("/v1/measurements/import", files={"file": ("miniprof.zip", upload)})
    assert again.status_code == 200
    body = again.json()
    assert body["duplicate"] and body["created"] == 0
    assert len(body["warnings"]) == len(answer["warnings"])


def test_a_reference_given_later_takes_the_wheel_out_of_quarantine(imported) -> None:
    client, _, _ = imported
    items = _items(client)
    left = items["left-wheel-v1-pre-dry.whl"]
    # the measured left wheel becomes a reference profile ("a measured new wheel")
    made = client.post("/v1/reference-profiles",
                       json={"name": "talent-left-measured", "measurement_id": left["id"]})
    assert made.status_code == 201, made.text
    assert made.json()["sd_mm"] == pytest.approx(left["sd_mm"], abs=0.05)
    names = [r["name"] for r in client.get("/v1/reference-profiles").json()]
    assert names[:2] == ["S1002", "S1002/31.5"] and "talent-left-measured" in names
    response = client.put(f"/v1/wheels/{left['wheel_id']}/reference",
                          json={"reference_profile": "talent-left-measured"})
    assert response.status_code == 200, response.text
    taken = response.json()["measurements"][0]
    assert taken["reference_profile"] == "talent-left-measured"
    assert taken["reference_fits"] is True, taken["warnings"]
    assert abs(taken["flange_area_mm2"]) < 1.0 and abs(taken["tread_area_mm2"]) < 1.0
    # the right wheel of the same pair has the same 36 mm flange: no flange-thickness
    # complaint against it (its tread stands ~0.07 mm higher: -7.5 mm², flagged, not hidden)
    right = items["right-wheel-v1-pre-dry.whl"]
    other = client.put(f"/v1/wheels/{right['wheel_id']}/reference",
                       json={"reference_profile": "talent-left-measured"}).json()
    reasons = [w["message"] for w in other["measurements"][0]["warnings"]
               if w["code"] == "reference_mismatch"]
    assert not any("flange thickness" in r or "flange back" in r for r in reasons)
    # the wheel's own first measurement as its baseline: no wear against itself
    own = client.put(f"/v1/wheels/{left['wheel_id']}/reference",
                     json={"reference_profile": "own"}).json()["measurements"][0]
    assert own["reference_profile"] == f"own:{left['id']}"
    assert own["reference_fits"] and abs(own["tread_area_mm2"]) < 1.0
    assert abs(own["flange_area_mm2"]) < 1.0
    stored = client.get(f"/v1/measurements/{left['id']}").json()
    assert stored["sd_mm"] == left["sd_mm"] and stored["y_mm"][:5] == pytest.approx(
        client.get(f"/v1/measurements/{left['id']}").json()["y_mm"][:5])


def test_unknown_reference_names_the_field(imported) -> None:
    client, _, _ = imported
    wheel = next(iter(_items(client).values()))["wheel_id"]
    response = client.put(f"/v1/wheels/{wheel}/reference",
                          json={"reference_profile": "P8-unknown"})
    assert response.status_code == 422 and "reference_profile" in response.text
    response = client.put("/v1/wheels/nope/reference", json={"reference_profile": "S1002"})
    assert response.status_code == 404


def test_own_baseline_declared_in_the_manifest_and_datum_entries_reported(
        reference_dir: Path, tmp_path: Path) -> None:
    client = TestClient(create_app(Settings(data_dir=tmp_path)))
    name = "whl_left_iter288.whl"
    manifest = ("file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,reference_profile\n"
                f"{name},W1,V1,motor,1,left,0,own\n")
    response = import_miniprof(client, reference_dir, name, manifest)
    assert response.status_code == 200, response.text
    datum = [w for w in response.json()["warnings"] if w["code"] == "datum_found"]
    assert datum and "Xoffset/Yoffset are 0" in datum[0]["message"]
    assert "reference points" in datum[0]["message"]
    item = client.get("/v1/measurements").json()["items"][0]
    assert item["reference_profile"] == f"own:{item['id']}" and item["reference_fits"]
    assert abs(item["flange_area_mm2"]) < 1.0 and abs(item["tread_area_mm2"]) < 1.0
    bad = import_miniprof(client, reference_dir, name,
                          manifest.replace(",own", ",P8").replace("W1", "W2"))
    assert bad.status_code == 422 and "reference_profile" in bad.text
