"""Manifests written by European spreadsheets (';', decimal comma) and usual spellings of
side and bogie type."""

from __future__ import annotations

import io

import pytest

from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.manifest import read_manifest


def test_semicolon_manifest_with_decimal_comma_and_spelled_sides() -> None:
    text = ("file;wheel_id;vehicle_id;bogie_type;axle;side;mileage_km;load_t\n"
            "a.whl;W1;V1;Trieb;1;L;12345,5;12,5\n"
            "b.whl;W2;V1;T;2;rechts;0;10\n"
            "c.whl;W3;V1;motor bogie;1;Right;1;10\n"
            "d.whl;W4;V1;Laufdrehgestell;2;links;2;10\n")
    rows = read_manifest(io.BytesIO(text.encode()), "m.csv")
    got = {k: (v.bogie_type, v.side, v.mileage_km) for k, v in rows.items()}
    assert got == {"a.whl": ("motor", "left", 12345.5), "b.whl": ("trailer", "right", 0.0),
                   "c.whl": ("motor", "right", 1.0), "d.whl": ("trailer", "left", 2.0)}
    assert rows["a.whl"].load_t == 12.5


def test_comma_manifest_still_reads_and_bad_spelling_names_the_field() -> None:
    ok = b"file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km\na.whl,W1,V1,M,1,R,10\n"
    assert read_manifest(io.BytesIO(ok), "m.csv")["a.whl"].side == "right"
    bad = b"file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km\na.whl,W1,V1,M,1,up,10\n"
    with pytest.raises(ImportFileError) as caught:
        read_manifest(io.BytesIO(bad), "m.csv")
    assert caught.value.field == "side" and caught.value.line == 2
