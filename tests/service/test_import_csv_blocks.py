"""Long CSVs parsed a block of whole measurements at a time in the import pool's workers:
the same records and the same first error as the reader of the whole file."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.service import import_csv_blocks, import_pool
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import iter_profile_records
from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame

HEADER = "wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm,route_id\n"


def _csv(n_profiles: int, points: int = 60, newline: str = "\n") -> str:
    """Worn S1002 profiles; a blank line inside every fifth measurement and between others,
    padded wheel ids (the reader strips them), a quoted route id."""
    y = np.linspace(-70.0, 60.0, points)
    out = [HEADER]
    for i in range(n_profiles):
        z = s1002_height_mm(y) - 0.003 * i * np.exp(-((y - 5.0) / 15.0) ** 2)
        wheel = f"W{i // 3:03d}" + (" " if i % 2 else "")
        prefix = f"{wheel},V{i // 12},motor,{1 + (i // 3) % 2},left,{1000.0 * (i % 3 + 1)},"
        rows = [f"{prefix}{a:.4f},{b:.5f},\"route, {i % 4}\"" for a, b in zip(y, z, strict=True)]
        if i % 5 == 0:
            rows.insert(points // 2, "")
        out.extend(row + "\n" for row in rows)
        if i % 7 == 0:
            out.append("\n")
    return "".join(out).replace("\n", newline)


def _records(text: str, reader) -> list[tuple]:  # type: ignore[no-untyped-def]
    return [(r.meta, r.y_mm.tolist(), r.z_mm.tolist())
            for r in reader(io.BytesIO(text.encode()), "fleet.csv")]


def _block_bytes(text: str, block_bytes: int) -> list[tuple[int, bytes]]:
    stream = io.BytesIO(text.encode())
    stream.readline()
    return [(line, head + body[:end]) for line, head, body, end in
            import_csv_blocks.blocks(stream, 0, 5, block_bytes=block_bytes)]


def _key(line: bytes) -> bytes:
    fields = line.split(b",")
    return fields[0].strip() + b"/" + fields[5]


def test_blocks_end_on_measurement_boundaries_and_count_lines():
    text = _csv(40)
    parts = _block_bytes(text, 3000)
    assert len(parts) > 10
    assert b"".join(data for _, data in parts) == text.encode().split(b"\n", 1)[1]
    line = 2
    for first_line, data in parts:
        assert first_line == line
        line += data.count(b"\n")
        assert data.endswith(b"\n")
    # no measurement goes on in the next block
    lasts = [_key(data.rstrip(b"\n").rsplit(b"\n", 1)[-1]) for _, data in parts]
    firsts = [_key(data.lstrip(b"\n").split(b"\n", 1)[0]) for _, data in parts]
    assert all(last != first for last, first in zip(lasts[:-1], firsts[1:], strict=True))


def test_a_measurement_longer_than_a_read_stays_whole():
    text = _csv(3, points=300)
    parts = _block_bytes(text, 500)
    assert len(parts) >= 2
    assert b"".join(data for _, data in parts) == text.encode().split(b"\n", 1)[1]
    for _, data in parts:  # whole measurements: 300 rows each
        assert len([row for row in data.split(b"\n") if row]) % 300 == 0


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize("workers", ["0", "2"])
def test_blocks_read_the_records_of_the_whole_file_reader(workers, newline, monkeypatch):
    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", workers)
    text = _csv(30, newline=newline)

    def blocked(stream, name):  # type: ignore[no-untyped-def]
        return import_csv_blocks.read_profiles(stream, name, block_bytes=4000)

    try:
        assert _records(text, blocked) == _records(text, iter_profile_records)
    finally:
        import_pool.discard_pool()


def _first_error(text: str, reader) -> tuple:  # type: ignore[no-untyped-def]
    with pytest.raises(ImportFileError) as caught:
        _records(text, reader)
    e = caught.value
    return e.file, e.line, e.field, e.reason


@pytest.mark.parametrize("workers", ["0", "2"])
def test_the_first_error_is_the_whole_file_readers(workers, monkeypatch):
    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", workers)
    lines = _csv(30).splitlines(keepends=True)
    bad_value = lines.copy()
    bad_value[1200] = bad_value[1200].replace(",motor,", ",tram,")
    bad_number = lines.copy()
    bad_number[1500] = ",".join(bad_number[1500].split(",")[:6]) + ",1.2.3,4,x\n"
    # the first measurement's rows again after others (across blocks)
    reappears = lines + lines[1:5]

    def blocked(stream, name):  # type: ignore[no-untyped-def]
        return import_csv_blocks.read_profiles(stream, name, block_bytes=4000)

    try:
        for text in ("".join(bad_value), "".join(bad_number), "".join(reappears)):
            expected = _first_error(text, iter_profile_records)
            assert _first_error(text, blocked) == expected
    finally:
        import_pool.discard_pool()


def _stored(database) -> list[tuple]:  # type: ignore[no-untyped-def]
    from sqlalchemy import select

    from wearcast.service import models_db as db

    m = db.Measurement
    with database.session_factory() as session:
        return [tuple(r) for r in session.execute(
            select(m.wheel_id, m.mileage_km, m.route_id, m.source_line, m.n_points, m.y_mm,
                   m.z_mm, m.wear_mm, m.flange_area_mm2, m.sd_mm, m.placement, m.warnings)
            .order_by(m.wheel_id, m.mileage_km))]


def test_an_import_parsed_in_the_workers_stores_what_the_importer_parsing_stores(
        tmp_path, monkeypatch, backend_url):
    from wearcast.service import importing
    from wearcast.service.db import Database
    from wearcast.service.settings import Settings

    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", "2")
    monkeypatch.setattr(import_csv_blocks, "BLOCK_BYTES", 20_000)
    data = _csv(40, points=120).encode()
    stored = []
    # parsed here into SQLite, then in the workers into the backend under test
    for in_workers, url in ((False, None), (True, backend_url)):
        settings = Settings(data_dir=tmp_path / f"w{in_workers}", database_url=url,
                            import_parse_in_workers=in_workers)
        database = Database(settings)
        database.migrate()
        with database.session_factory() as session:
            result = importing.import_upload(session, settings.raw_dir, io.BytesIO(data),
                                             "fleet.csv", settings=settings)
        assert result.created == 40
        stored.append(_stored(database))
        database.dispose()
    import_pool.discard_pool()
    assert stored[0] == stored[1]
    assert {row[2] for row in stored[1]} == {f"route, {i}" for i in range(4)}


def test_workers_parse_from_min_workers_on_unless_the_setting_says(monkeypatch):
    few, many = import_csv_blocks.MIN_WORKERS - 1, import_csv_blocks.MIN_WORKERS
    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", str(few))
    assert not import_csv_blocks.parse_in_workers()
    assert import_csv_blocks.parse_in_workers(True)
    monkeypatch.setenv("WEARCAST_IMPORT_WORKERS", str(many))
    assert import_csv_blocks.parse_in_workers()
    assert not import_csv_blocks.parse_in_workers(False)


def test_block_parsing_equals_the_whole_file_on_measured_miniprof_wheels(
        reference_dir: Path) -> None:
    """Real data: the raw points of every measured MiniProf wheel in
    ``../shared/reference/miniprof`` written as one long CSV (measured values as the instrument
    gave them, full precision), parsed a few kB at a time, give exactly the records of the
    whole-file reader."""
    paths = sorted((reference_dir / "miniprof").glob("*.whl"))
    assert len(paths) >= 5
    out = [HEADER]
    for i, path in enumerate(paths):
        y, z = to_wheel_frame(parse_miniprof(path.read_bytes(), path.name))
        prefix = f"{path.stem},U1,trailer,{1 + i % 2},left,{1000.0 * (i + 1)},"
        out.extend(f"{prefix}{float(a)!r},{float(b)!r},r1\n" for a, b in zip(y, z, strict=True))
    text = "".join(out)
    whole = _records(text, iter_profile_records)
    assert len(whole) == len(paths)

    def by_blocks(stream, name):  # type: ignore[no-untyped-def]
        return import_csv_blocks.read_profiles(stream, name, block_bytes=4000)

    assert _records(text, by_blocks) == whole
