"""One upload mixing the real MiniProf wheels (with their manifest), long-CSV profiles with
covariates and a parameter CSV: the rows of one insert chunk then carry different keys
(a parameter record has no points, no reference fits). Every record is stored, with the
values each file gave, on SQLite and PostgreSQL (before stop 26 such a chunk failed with
"A value is required for bind parameter 'reference_fits'")."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import select

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.service import importing
from wearcast.service import models_db as db
from wearcast.service.db import Database
from wearcast.service.settings import Settings

MINIPROF = ("Car7216_0001r.whl", "Car7358_0001r.whl", "avg_wheel.whl",
            "left-wheel-v1-pre-dry.whl", "whl_left_iter288.whl")


def _upload(reference_dir: Path) -> bytes:
    manifest = ["file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,reference_profile"]
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for i, name in enumerate(MINIPROF):
            archive.writestr(name, (reference_dir / "miniprof" / name).read_bytes())
            manifest.append(f"{name},M{i},VM,motor,1,{'left' if i % 2 else 'right'},"
                            f"{1000 * i},S1002")
        archive.writestr("manifest.csv", "\n".join(manifest) + "\n")
        y = np.linspace(-68.0, 58.0, 120)
        rows = ["wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm,measured_on,"
                "route_id,running_mode,load_t"]
        for i in range(12):
            z = s1002_height_mm(y) - 0.01 * i * np.exp(-((y - 5.0) / 15.0) ** 2)
            rows += [f"F{i // 3},VF,trailer,{1 + (i // 3) % 2},left,{2500.5 * (i % 3)},"
                     f"{float(a)!r},{float(b)!r},2024-03-{1 + i:02d},r{i % 2},lead,{12.5 + i}"
                     for a, b in zip(y, z, strict=True)]
        archive.writestr("fleet.csv", "\n".join(rows) + "\n")
        archive.writestr("parameters.csv", "wheel_id,vehicle_id,bogie_type,axle,side,"
                         "mileage_km,sd_mm,sh_mm,qr_mm\n" + "".join(
                             f"P{i},VP,motor,1,right,{500 * i},32.1,28.{i},10.5\n"
                             for i in range(4)))
    return buffer.getvalue()


def test_a_zip_mixing_miniprof_profiles_and_parameters_imports_whole(backend_url, reference_dir,
                                                                      tmp_path) -> None:
    settings = Settings(data_dir=tmp_path, database_url=backend_url)
    database = Database(settings)
    database.migrate()
    try:
        with database.session_factory() as session:
            result = importing.import_upload(session, settings.raw_dir,
                                             io.BytesIO(_upload(reference_dir)), "mixed.zip",
                                             settings=settings)
            assert result.created == 5 + 12 + 4 and not result.duplicate
            stored = session.execute(select(
                db.Measurement.wheel_id, db.Measurement.kind, db.Measurement.n_points,
                db.Measurement.sd_mm, db.Measurement.sh_mm)).all()
    finally:
        database.dispose()
    by_wheel: dict[str, list] = {}
    for wheel_id, kind, n_points, sd_mm, sh_mm in stored:
        by_wheel.setdefault(wheel_id[0], []).append((kind, n_points, sd_mm, sh_mm))
    assert len(by_wheel["M"]) == 5 and len(by_wheel["F"]) == 12 and len(by_wheel["P"]) == 4
    assert all(kind == "profile" and n > 100 for kind, n, _, _ in by_wheel["M"] + by_wheel["F"])
    # the parameter records as the file gave them: no points, Sd 32.1 mm, Sh 28.0-28.3 mm
    assert sorted(sh for kind, n, sd, sh in by_wheel["P"]) == pytest.approx(
        [28.0, 28.1, 28.2, 28.3])
    assert all(kind == "parameters" and n == 0 and sd == pytest.approx(32.1)
               for kind, n, sd, _ in by_wheel["P"])
