"""MiniProf files (with a manifest) through the import service, checked against the
instrument's own Sd/Sh/qR printed in the files (CONTACT test bank, ../shared/reference)."""

from __future__ import annotations

import io
import warnings
import zipfile
from pathlib import Path

import pytest

from tests.service.conftest import import_miniprof
from wearcast.service.app import create_app
from wearcast.service.settings import Settings

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

MANIFEST = "file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,depot\n"

# Header lines "Sd=…, Sh=…, qR=…" of the files: the MiniProf software's own values [mm].
INSTRUMENT = {
    "left-wheel-v1-pre-dry.whl": (36.1416, 27.8749, 9.0991),
    "whl_left_iter795.whl": (34.3347, 34.9985, 10.0658),
}


def test_miniprof_zip_with_manifest_keeps_and_reproduces_instrument_parameters(
        reference_dir: Path, tmp_path: Path) -> None:
    client = TestClient(create_app(Settings(data_dir=tmp_path)))
    buffer = io.BytesIO()
    rows = [MANIFEST]
    with zipfile.ZipFile(buffer, "w") as archive:
        for i, name in enumerate(INSTRUMENT):
            archive.writestr(f"campaign/{name}", (reference_dir / "miniprof" / name).read_bytes())
            rows.append(f"campaign/{name},W{i},V1,trailer,2,left,{10_000 * (i + 1)},south\n")
        archive.writestr("manifest.csv", "".join(rows))
    response = client.post("/v1/measurements/import",
                           files={"file": ("campaign.zip", buffer.getvalue())})
    assert response.status_code == 200, response.text
    assert response.json()["created"] == 2
    items = client.get("/v1/measurements", params={"depot": "south"}).json()["items"]
    assert [item["wheel_id"] for item in items] == ["W0", "W1"]
    for item, (name, (sd, sh, qr)) in zip(items, INSTRUMENT.items(), strict=True):
        assert item["source_file"] == f"campaign.zip:campaign/{name}"
        assert item["instrument_id"].startswith("miniprof:")
        assert (item["reported_sd_mm"], item["reported_sh_mm"], item["reported_qr_mm"]) \
            == (sd, sh, qr)
        # recomputed from the points, in the instrument's frame: the instrument's algorithm
        # is not published, so we allow 0.05 mm (measured agreement: <= 0.025 mm)
        assert item["sd_mm"] == pytest.approx(sd, abs=0.05)
        assert item["sh_mm"] == pytest.approx(sh, abs=0.05)
        assert item["qr_mm"] == pytest.approx(qr, abs=0.05)


def test_miniprof_without_its_manifest_row_is_refused(reference_dir: Path,
                                                      tmp_path: Path) -> None:
    client = TestClient(create_app(Settings(data_dir=tmp_path)))
    name = "left-wheel-v1-pre-dry.whl"
    manifest = MANIFEST + "other.whl,W9,V1,motor,1,left,0,x\n"
    response = import_miniprof(client, reference_dir, name, manifest)
    assert response.status_code == 422
    assert response.json()["errors"][0]["file"] == name
    assert client.get("/v1/measurements").json()["total"] == 0
