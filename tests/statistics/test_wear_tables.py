import numpy as np
import pandas as pd
import pytest

from wearcast.statistics.wear_tables import (
    TABLE_COLUMNS,
    RadiusOutOfTableError,
    compile_wear_table,
    table_value,
    validate_wear_table,
    wear_table_to_records,
)


def _table() -> pd.DataFrame:
    rows = []
    for wheelset in ("leading", "trailing"):
        for region in ("flange", "tread"):
            rows.append(("motor", wheelset, "tangent", np.nan, region, "tau_max", 1.0))
            rows.append(("motor", wheelset, "high", 300.0, region, "tau_max", 10.0))
            rows.append(("motor", wheelset, "high", 600.0, region, "tau_max", 4.0))
            rows.append(("motor", wheelset, "low", 300.0, region, "tau_max", 2.0))
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)


def test_interpolation_is_linear_in_curvature():
    table = _table()
    # 1/400 lies half-way between 1/600 and 1/300 in curvature -> (10 + 4) / 2 = 7
    # (linear in radius would give 8.67)
    assert table_value(table, "motor", "leading", "high", 400.0, "tread", "tau_max") == \
        pytest.approx(7.0)
    # 1/1200 is half-way between tangent (curvature 0, value 1) and 1/600 (value 4)
    assert table_value(table, "motor", "leading", "high", 1200.0, "tread", "tau_max") == \
        pytest.approx(2.5)
    assert table_value(table, "motor", "leading", "tangent", None, "tread", "tau_max") == 1.0
    assert table_value(table, "motor", "leading", "high", 300.0, "flange", "tau_max") == 10.0
    assert table_value(table, "motor", "leading", "high", 1e9, "flange", "tau_max") == \
        pytest.approx(1.0, abs=1e-5)


def test_compiled_table_gives_the_same_values():
    table = _table()
    compiled = compile_wear_table(table)
    for radius in (300.0, 350.0, 500.0, 800.0, 5000.0):
        assert table_value(compiled, "motor", "trailing", "high", radius, "flange", "tau_max") \
            == table_value(table, "motor", "trailing", "high", radius, "flange", "tau_max")
    assert compiled.bogie_types == ("motor",)


def test_radius_tighter_than_the_table_raises_a_dedicated_error():
    with pytest.raises(RadiusOutOfTableError, match="250") as info:
        table_value(_table(), "motor", "leading", "high", 250.0, "tread", "tau_max")
    assert isinstance(info.value, ValueError)
    assert "300" in str(info.value)


def test_unknown_key_raises_value_error():
    with pytest.raises(ValueError, match="bogie_type"):
        table_value(_table(), "trailer", "leading", "high", 400.0, "tread", "tau_max")
    with pytest.raises(ValueError, match="measure"):
        table_value(_table(), "motor", "leading", "high", 400.0, "tread", "t_gamma")


@pytest.mark.parametrize(
    ("mutate", "field"),
    [
        (lambda d: d.assign(wheelset=["middle"] + list(d.wheelset[1:])), "wheelset"),
        (lambda d: d.assign(rail=["outer"] + list(d.rail[1:])), "rail"),
        (lambda d: d.assign(region=["web"] + list(d.region[1:])), "region"),
        (lambda d: d.assign(measure=["archard"] + list(d.measure[1:])), "measure"),
        (lambda d: d.assign(value=[np.inf] + list(d.value[1:])), "value"),
        (lambda d: d.assign(value=[-1.0] + list(d.value[1:])), "value"),
        (lambda d: d.assign(radius_m=[500.0] + list(d.radius_m[1:])), "radius_m"),
        (lambda d: d.drop(index=0), "tangent"),
        (lambda d: pd.concat([d, d.iloc[[1]]]), "duplicate"),
        (lambda d: d.drop(columns="value"), "value"),
    ],
)
def test_validation_names_the_field(mutate, field):
    with pytest.raises(ValueError, match=field):
        validate_wear_table(mutate(_table()))


def test_records_are_json_friendly():
    records = wear_table_to_records(_table())
    assert records[0]["radius_m"] is None and records[1]["radius_m"] == 300.0
    assert validate_wear_table(pd.DataFrame(records)).shape == (16, 7)
