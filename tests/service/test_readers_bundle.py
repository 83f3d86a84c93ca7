"""Upload dispatch: CSVs, MiniProf + manifest, zip bundles, raw members and zip limits."""

from __future__ import annotations

import hashlib
import io
import zipfile
from datetime import date

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.service.readers.bundle import ZipLimits, iter_upload, iter_upload_with_raw
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.manifest import read_manifest
from wearcast.service.readers.records import ParameterRecord, ProfileRecord

Y = np.linspace(-69.0, 60.0, 200)
MANIFEST_HEADER = "file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,measured_on,route_id"


def _whl(side: str = "%R", date_text: str = "02/05/2023") -> bytes:
    z = s1002_height_mm(Y)
    head = (f"Date={date_text}\nSide={side}\nMPSerNo=777\nColumnDef=X,Y\nXYPoints={Y.size}\n"
            "Sd=32.4\nSh=28.1\nqR=10.7\n\n")
    return (head + "\n".join(f"{a + 70:.4f},{b:.4f}" for a, b in zip(Y, z, strict=True))
            + "\n").encode()


def _mpt() -> bytes:
    z = s1002_height_mm(Y)
    text = "[FileInfo]\nDate=18/09/2022\n\n"
    for k in (1, 2):
        text += f"[Profile{k}Info]\nColumnDef=X,Y\n\n[Profile{k}Points]\n"
        text += "".join(f"{a + 70:.4f} {b:.4f}\n" for a, b in zip(Y, z, strict=True)) + "\n"
    return text.encode()


LONG_CSV = ("wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm\n" + "".join(
    f"W9,V9,trailer,2,left,1000,{a:.3f},{b:.3f}\n"
    for a, b in zip(Y, s1002_height_mm(Y), strict=True))).encode()
PARAM_CSV = (b"wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,sd_mm,sh_mm,qr_mm\n"
             b"W8,V8,motor,1,right,2000,31.0,29.0,10.0\n")


def _zip(members: dict[str, bytes]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return out.getvalue()


def _manifest(*rows: str) -> bytes:
    return ("\n".join([MANIFEST_HEADER, *rows]) + "\n").encode()


def test_zip_with_manifest_mixes_csvs_and_miniprof_files():
    manifest = _manifest("a.whl,W1,V1,motor,1,right,5000,,R1",
                         "sub/b.whl,W2,V1,motor,1,right,7000,2023-06-01,R1",
                         "c.mpt#1,W3,V2,trailer,2,left,0,,R2",
                         "c.mpt#2,W4,V2,trailer,2,right,0,,R2")
    data = _zip({"batch/manifest.csv": manifest, "batch/a.whl": _whl(),
                 "batch/sub/b.whl": _whl(), "c.mpt": _mpt(), "long.csv": LONG_CSV,
                 "params.csv": PARAM_CSV, "__MACOSX/._a.whl": b"junk"})
    records = list(iter_upload(data, "upload.zip"))
    by_wheel = {r.meta.wheel_id: r for r in records}
    assert sorted(by_wheel) == ["W1", "W2", "W3", "W4", "W8", "W9"]
    w1 = by_wheel["W1"]
    assert isinstance(w1, ProfileRecord)
    assert w1.meta.measured_on == date(2023, 5, 2)  # taken from the file's Date
    assert w1.meta.instrument_id == "miniprof:777"
    assert w1.meta.source_file == "upload.zip:batch/a.whl"
    assert w1.instrument_parameters == {"sd_mm": 32.4, "sh_mm": 28.1, "qr_mm": 10.7}
    np.testing.assert_allclose(w1.y_mm, Y, atol=1e-4)
    np.testing.assert_allclose(w1.z_mm, s1002_height_mm(Y), atol=1e-4)
    assert by_wheel["W2"].meta.measured_on == date(2023, 6, 1)  # the manifest wins
    assert by_wheel["W4"].meta.source_file == "upload.zip:c.mpt#2"
    assert isinstance(by_wheel["W8"], ParameterRecord)
    assert by_wheel["W9"].meta.source_file == "upload.zip:long.csv"


def test_raw_variant_returns_member_bytes_and_sha256():
    whl = _whl()
    data = _zip({"manifest.csv": _manifest("a.whl,W1,V1,motor,1,right,5000,,R1"),
                 "a.whl": whl, "long.csv": LONG_CSV})
    pairs = list(iter_upload_with_raw(data, "u.zip"))
    raws = {raw.path: raw for _, raw in pairs}
    assert raws["u.zip:a.whl"].data == whl
    assert raws["u.zip:a.whl"].sha256 == hashlib.sha256(whl).hexdigest()
    assert raws["u.zip:long.csv"].sha256 == hashlib.sha256(LONG_CSV).hexdigest()


def test_single_files_and_manifest_argument():
    (record,) = list(iter_upload(LONG_CSV, "long.csv"))
    assert record.meta.wheel_id == "W9"
    (param,) = list(iter_upload(io.BytesIO(PARAM_CSV), "p.csv"))
    assert param.sd_mm == 31.0
    manifest = _manifest("left.whl,W1,V1,motor,1,right,5000,,R1")
    (whl,) = list(iter_upload(_whl(), "left.whl", manifest=manifest))
    assert whl.meta.wheel_id == "W1"
    rows = read_manifest(io.BytesIO(manifest), "manifest.csv")
    (again,) = list(iter_upload(_whl(), "left.whl", manifest=rows))
    assert again.meta == whl.meta


def test_refusals_name_the_file():
    with pytest.raises(ImportFileError, match="no manifest row for file a.whl"):
        list(iter_upload(_whl(), "a.whl"))
    with pytest.raises(ImportFileError, match="no manifest row for file x.whl"):
        list(iter_upload(_whl(), "x.whl",
                         manifest=_manifest("a.whl,W1,V1,motor,1,right,5000,,R1")))
    with pytest.raises(ImportFileError, match="rail profile"):
        list(iter_upload(b"Rail=low\n\n1 2\n3 4\n", "r.ban"))
    with pytest.raises(ImportFileError, match="side 'left'.*Side=%R"):
        list(iter_upload(_whl(), "a.whl",
                         manifest=_manifest("a.whl,W1,V1,motor,1,left,5000,,R1")))
    with pytest.raises(ImportFileError, match="unsupported file type"):
        list(iter_upload(b"hello", "notes.txt"))
    with pytest.raises(ImportFileError) as err:
        list(iter_upload(_manifest("a.whl,W1,V1,motor,1,up,5000,,R1"), "m.csv"))
    assert err.value.line == 1  # a manifest is not an importable CSV: neither kind


def test_zip_structure_errors():
    with pytest.raises(ImportFileError, match="no manifest.csv"):
        list(iter_upload(_zip({"a.whl": _whl()}), "u.zip"))
    manifest = _manifest("a.whl,W1,V1,motor,1,right,5000,,R1",
                         "gone.whl,W2,V1,motor,1,right,5000,,R1")
    with pytest.raises(ImportFileError, match="'gone.whl', which is not in the upload") as err:
        list(iter_upload(_zip({"manifest.csv": manifest, "a.whl": _whl()}), "u.zip"))
    assert err.value.line == 3
    with pytest.raises(ImportFileError, match="more than one manifest"):
        list(iter_upload(_zip({"manifest.csv": manifest, "x/manifest.csv": manifest}), "u.zip"))
    with pytest.raises(ImportFileError, match="nested zip"):
        list(iter_upload(_zip({"inner.zip": _zip({"long.csv": LONG_CSV})}), "u.zip"))
    with pytest.raises(ImportFileError, match="u.zip:bad.csv line 3, field 'y_mm'"):
        list(iter_upload(_zip({"bad.csv": LONG_CSV.replace(b"-68.352", b"zz")}), "u.zip"))
    with pytest.raises(ImportFileError, match="not a readable zip"):
        list(iter_upload(b"PK\x03\x04garbage", "u.zip"))


def test_zip_bombs_and_absurd_sizes_are_refused_before_inflating():
    bomb = _zip({"zeros.csv": b"0" * 5_000_000})  # ~1000:1
    with pytest.raises(ImportFileError, match=r"compression ratio .* \(zip bomb\?\)"):
        list(iter_upload(bomb, "bomb.zip"))
    with pytest.raises(ImportFileError, match="expands to"):
        list(iter_upload(_zip({"long.csv": LONG_CSV}), "u.zip",
                         limits=ZipLimits(max_member_bytes=1000)))
    with pytest.raises(ImportFileError, match="members; at most 1"):
        list(iter_upload(_zip({"a.csv": LONG_CSV, "b.csv": LONG_CSV}), "u.zip",
                         limits=ZipLimits(max_members=1)))
