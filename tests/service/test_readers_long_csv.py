"""Long profile CSV reader: round trip, every kind of bad input, chunking, bounded memory."""

from __future__ import annotations

import io
import tracemalloc
from datetime import date

import numpy as np
import pytest

from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import iter_profile_records, sniff_kind

HEADER = ("wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,measured_on,route_id,"
          "running_mode,load_t,lubricated,y_mm,z_mm")
N_POINTS = 12
Y = np.linspace(-70.0, 60.0, N_POINTS)


def _rows(wheel: str, mileage: float, *, side: str = "left", z_scale: float = 1.0,
          y: np.ndarray = Y) -> list[str]:
    z = z_scale * 0.002 * (y + 5.0) ** 2
    return [f"{wheel},V1,motor,1,{side},{mileage:g},2024-03-01,R1,lead,12.5,yes,"
            f"{a:.6f},{b:.6f}" for a, b in zip(y, z, strict=True)]


def _csv(*blocks: list[str], header: str = HEADER) -> bytes:
    lines = [header] + [row for block in blocks for row in block]
    return ("\n".join(lines) + "\n").encode()


def _read(data: bytes, **kw) -> list:
    return list(iter_profile_records(io.BytesIO(data), "fleet.csv", **kw))


def test_valid_file_round_trips_every_field():
    data = _csv(_rows("W1", 0), _rows("W1", 12_000), _rows("W2", 500, side="right"))
    records = _read(data)
    assert [(r.meta.wheel_id, r.meta.mileage_km) for r in records] == [
        ("W1", 0.0), ("W1", 12_000.0), ("W2", 500.0)]
    first = records[0]
    meta = first.meta
    assert (meta.vehicle_id, meta.bogie_type, meta.axle, meta.side) == ("V1", "motor", 1, "left")
    assert meta.measured_on == date(2024, 3, 1)
    assert (meta.route_id, meta.running_mode, meta.load_t) == ("R1", "lead", 12.5)
    assert meta.reference_profile == "S1002"
    assert meta.covariates == {"lubricated": "yes"}
    assert (meta.source_file, meta.source_line) == ("fleet.csv", 2)
    assert records[1].meta.source_line == 2 + N_POINTS
    assert records[2].meta.side == "right"
    np.testing.assert_allclose(first.y_mm, Y, atol=1e-6)
    np.testing.assert_allclose(first.z_mm, 0.002 * (Y + 5.0) ** 2, atol=1e-6)
    assert first.instrument_parameters is None


def test_numeric_covariates_become_floats_and_blank_lines_are_counted():
    header = "wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,temperature_c,y_mm,z_mm"
    body = [f"W1,V1,trailer,2,right,100,21.5,{y:g},{0.01 * y * y:g}" for y in Y]
    data = (header + "\n" + "\n".join(body[:5]) + "\n\n" + "\n".join(body[5:]) + "\n").encode()
    (record,) = _read(data)
    assert record.meta.covariates == {"temperature_c": 21.5}
    assert record.meta.axle == 2 and record.meta.bogie_type == "trailer"
    assert record.y_mm.size == N_POINTS
    bad = data.replace(b",21.5,-70,", b",21.5,oops,")
    with pytest.raises(ImportFileError) as err:
        _read(bad)
    assert err.value.line == 2


@pytest.mark.parametrize("chunk_rows", [1, 5, 7, N_POINTS, N_POINTS + 1, 1000])
def test_chunk_boundaries_inside_a_measurement_are_carried_over(chunk_rows):
    data = _csv(_rows("W1", 0), _rows("W1", 5000), _rows("W2", 0))
    expected = _read(data)
    got = _read(data, chunk_rows=chunk_rows)
    assert len(got) == 3
    for a, b in zip(expected, got, strict=True):
        assert a.meta == b.meta
        np.testing.assert_array_equal(a.y_mm, b.y_mm)
        np.testing.assert_array_equal(a.z_mm, b.z_mm)


def test_missing_required_column_is_named():
    data = _csv(_rows("W1", 0), header=HEADER.replace("side,", "sides,"))
    with pytest.raises(ImportFileError) as err:
        _read(data)
    assert (err.value.file, err.value.line, err.value.field) == ("fleet.csv", 1, "side")
    assert "missing" in err.value.reason


@pytest.mark.parametrize(("old", "new", "line", "field", "reason"), [
    (",left,", ",up,", 4, "side", "'up' is not one of left, right"),
    (",motor,", ",diesel,", 4, "bogie_type", "not one of motor, trailer"),
    (",motor,1,", ",motor,3,", 4, "axle", "not one of 1, 2"),
    (",lead,", ",always,", 4, "running_mode", "not one of lead, mixed"),
    (",2024-03-01,", ",01/03/2024,", 4, "measured_on", "not an ISO date"),
    (",12.5,", ",-3,", 4, "load_t", "> 0"),
    ("W1,V1,", ",V1,", 4, "wheel_id", "missing"),
    (",yes,-46.363636,", ",yes,abc,", 4, "y_mm", "'abc' is not a number"),
    (",yes,-46.363636,", ",yes,inf,", 4, "y_mm", "not finite"),
    (",yes,-46.363636,", ",yes,nan,", 4, "y_mm", "is not a number"),
])
def test_bad_values_name_line_and_field(old, new, line, field, reason):
    rows = _rows("W1", 0)
    rows[2] = rows[2].replace(old, new, 1)
    assert rows[2] != _rows("W1", 0)[2]
    with pytest.raises(ImportFileError) as err:
        _read(_csv(rows))
    assert err.value.line == line
    assert err.value.field == field
    assert reason in err.value.reason
    assert str(err.value).startswith(f"fleet.csv line {line}, field '{field}': ")


def test_empty_numeric_cell_and_negative_mileage():
    rows = _rows("W1", 0)
    rows[3] = rows[3].rsplit(",", 1)[0] + ","
    with pytest.raises(ImportFileError, match="line 5, field 'z_mm': value is missing"):
        _read(_csv(rows))
    with pytest.raises(ImportFileError, match="field 'mileage_km'.*below 0"):
        _read(_csv(_rows("W1", -5)))


def test_inconsistent_metadata_within_a_measurement():
    rows = _rows("W1", 0)
    rows[6] = rows[6].replace(",V1,", ",V9,")
    with pytest.raises(ImportFileError) as err:
        _read(_csv(rows))
    assert (err.value.line, err.value.field) == (8, "vehicle_id")
    assert "constant within a measurement" in err.value.reason


def test_inconsistent_metadata_across_a_chunk_boundary():
    rows = _rows("W1", 0)
    rows[8:] = [row.replace(",12.5,", ",13.5,") for row in rows[8:]]
    with pytest.raises(ImportFileError, match="differs from its first row on line 2") as err:
        _read(_csv(rows), chunk_rows=8)
    assert err.value.line == 10


@pytest.mark.parametrize("chunk_rows", [5, 200_000])
def test_measurement_that_reappears_is_refused(chunk_rows):
    data = _csv(_rows("W1", 0), _rows("W2", 0), _rows("W1", 0))
    with pytest.raises(ImportFileError) as err:
        _read(data, chunk_rows=chunk_rows)
    assert err.value.line == 2 + 2 * N_POINTS
    assert "appears again; it started on line 2" in err.value.reason


def test_profile_in_metres_or_instrument_coordinates_is_refused():
    with pytest.raises(ImportFileError, match="looks like metres"):
        _read(_csv(_rows("W1", 0, y=Y / 1000.0, z_scale=1e-3)))
    flat = _rows("W1", 0, y=np.linspace(0.0, 0.5, N_POINTS))
    with pytest.raises(ImportFileError, match="lateral extent"):
        _read(_csv(flat))
    with pytest.raises(ImportFileError, match="MiniProf X"):
        _read(_csv(_rows("W1", 0, y=Y + 70.0)))
    with pytest.raises(ImportFileError, match="fewer than 5 points"):
        _read(_csv(_rows("W1", 0)[:3]))


def test_too_many_fields_is_reported_with_the_file_line():
    rows = _rows("W1", 0)
    rows[4] += ",extra"
    with pytest.raises(ImportFileError) as err:
        _read(_csv(rows))
    assert err.value.line == 6


def test_sniff_kind():
    assert sniff_kind(HEADER.split(",")) == "profile"
    assert sniff_kind(["wheel_id", "sd_mm", "sh_mm", "qr_mm"]) == "parameter"
    with pytest.raises(ValueError):
        sniff_kind(["wheel_id", "mileage_km"])


class _GeneratedCsv(io.RawIOBase):
    """A long CSV of ``n_profiles`` x 50 points produced on the fly (never held whole)."""

    def __init__(self, n_profiles: int) -> None:
        self.n_profiles = n_profiles
        self.index = -1
        self.buffer = b""
        y = np.linspace(-70.0, 60.0, 50)
        self.points = [f"{a:.3f},{0.002 * a * a:.3f}\n" for a in y]

    def readable(self) -> bool:
        return True

    def _more(self) -> bytes:
        self.index += 1
        if self.index == 0:
            return b"wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm\n"
        i = self.index - 1
        if i >= self.n_profiles:
            return b""
        prefix = f"W{i // 20},V{i // 160},motor,1,left,{(i % 20) * 1000},"
        return "".join(prefix + p for p in self.points).encode()

    def readinto(self, buffer) -> int:
        while len(self.buffer) < len(buffer):
            more = self._more()
            if not more:
                break
            self.buffer += more
        n = min(len(buffer), len(self.buffer))
        buffer[:n] = self.buffer[:n]
        self.buffer = self.buffer[n:]
        return n


def _peak_bytes(n_profiles: int) -> tuple[int, int]:
    stream = io.BufferedReader(_GeneratedCsv(n_profiles))
    tracemalloc.start()
    count = 0
    for _ in iter_profile_records(stream, "big.csv", chunk_rows=10_000):
        count += 1
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return count, peak


def test_memory_does_not_grow_with_file_size():
    # 1,000 vs 10,000 profiles (50k vs 500k rows): the peak is set by chunk_rows; only one
    # small key per measurement accumulates (for the contiguity check).
    small_count, small_peak = _peak_bytes(1_000)
    big_count, big_peak = _peak_bytes(10_000)
    assert (small_count, big_count) == (1_000, 10_000)
    # Measured: 2.6 MB vs 3.9 MB; reading the whole file as one chunk gives 7.6 vs 76 MB.
    assert big_peak < 2.0 * small_peak, (small_peak, big_peak)
