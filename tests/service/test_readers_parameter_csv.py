"""Parameter-only CSV reader (Sd, Sh, qR per measurement)."""

from __future__ import annotations

import io

import pytest

from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.parameter_csv import iter_parameter_records

HEADER = "wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,depot,sd_mm,sh_mm,qr_mm"


def _read(*rows: str) -> list:
    data = ("\n".join([HEADER, *rows]) + "\n").encode()
    return list(iter_parameter_records(io.BytesIO(data), "params.csv"))


def test_rows_become_parameter_records():
    records = _read("W1,V1,motor,1,left,0,North,32.5,28.0,10.8",
                    "W1,V1,motor,1,left,50000,North,30.1,29.2,9.9")
    assert [r.meta.mileage_km for r in records] == [0.0, 50_000.0]
    first = records[0]
    assert (first.sd_mm, first.sh_mm, first.qr_mm) == (32.5, 28.0, 10.8)
    assert first.meta.covariates == {"depot": "North"}
    assert records[1].meta.source_line == 3


def test_metres_repeats_and_bad_values_are_refused():
    with pytest.raises(ImportFileError, match=r"line 2, field 'sd_mm'.*looks like metres"):
        _read("W1,V1,motor,1,left,0,N,0.0325,0.028,0.0108")
    with pytest.raises(ImportFileError, match="line 3, field 'wheel_id'.*already given on line 2"):
        _read("W1,V1,motor,1,left,0,N,32.5,28,10.8", "W1,V1,motor,1,left,0,N,32.0,28,10.8")
    with pytest.raises(ImportFileError, match="line 2, field 'qr_mm': 'x' is not a number"):
        _read("W1,V1,motor,1,left,0,N,32.5,28,x")
    with pytest.raises(ImportFileError, match="line 2, field 'side'"):
        _read("W1,V1,motor,1,up,0,N,32.5,28,10.8")
    data = b"wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,sd_mm,sh_mm\n"
    with pytest.raises(ImportFileError, match="line 1, field 'qr_mm'"):
        list(iter_parameter_records(io.BytesIO(data), "params.csv"))
