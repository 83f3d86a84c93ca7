"""Curve-radius tables of wear measures (docs/conventions.md "The hybrid model" 5).

A table gives, per bogie type, wheelset position (leading/trailing), rail (high/low/tangent),
curve radius, wheel region (tread/flange) and wear measure (tau_max/t_gamma), one value of the
wear measure P_i (seed 001 Fig. 10; MBD simulations there, the physics core or an upload here).
Radii between rows are interpolated linearly in curvature 1/R, the tangent row being
curvature 0.

The long table is a pandas DataFrame with columns ``bogie_type, wheelset, rail, radius_m,
region, measure, value`` (``radius_m`` NaN on tangent rows). For repeated look-ups compile it
once with :func:`compile_wear_table`; every function here accepts either form.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import pandas as pd

from wearcast.physics.vocabulary import (
    BOGIE_TYPES,
    RAILS,
    REGIONS,
    WEAR_MEASURES,
    WEAR_TABLE_COLUMNS,
    WHEELSETS,
)
from wearcast.statistics.frames import check_frame

#: Columns of the curve-radius table (``vocabulary.WEAR_TABLE_COLUMNS``).
TABLE_COLUMNS = WEAR_TABLE_COLUMNS
#: Relative slack on the table's smallest radius (rounding of uploaded radii) [-].
RADIUS_RTOL = 1e-9


class RadiusOutOfTableError(ValueError):
    """A curve radius lies outside the radii a wear table covers."""

    def __init__(self, radius_m: float, min_radius_m: float, key: tuple[str, ...]):
        self.radius_m = radius_m
        self.min_radius_m = min_radius_m
        self.key = key
        super().__init__(
            f"radius_m: {radius_m:g} m is outside the wear table's range "
            f"[{min_radius_m:g} m, tangent] for {'/'.join(key)}"
        )


class UnknownTableEntryError(ValueError):
    """The table has no rows for the requested bogie type/wheelset/rail/region/measure."""


def validate_wear_table(table: pd.DataFrame) -> pd.DataFrame:
    """Check a curve-radius table and return a normalised copy.

    Raises ValueError naming the column and row for: missing columns, unknown enum values,
    non-finite or negative values, a missing or non-positive radius on a curve row, a radius
    on a tangent row, duplicate rows, and a missing tangent row for any
    (bogie_type, wheelset, region, measure) that has curve rows.
    """
    check_frame(table, TABLE_COLUMNS, field="table", what="the wear table",
                no_rows="the wear table has no rows")
    df = table.loc[:, list(TABLE_COLUMNS)].reset_index(drop=True).copy()
    df["bogie_type"] = df["bogie_type"].astype(str).str.strip()
    if (df["bogie_type"] == "").any() or table["bogie_type"].isna().any():
        raise ValueError(f"bogie_type: empty in row {int(np.argmax(table['bogie_type'].isna()))}")
    for column, allowed in (
        ("wheelset", WHEELSETS),
        ("rail", RAILS),
        ("region", REGIONS),
        ("measure", WEAR_MEASURES),
    ):
        values = df[column].astype(str).str.strip().str.lower()
        bad = ~values.isin(allowed)
        if bad.any():
            i = int(np.argmax(bad.to_numpy()))
            raise ValueError(
                f"{column}: unknown value {df[column].iloc[i]!r} in row {i} (allowed: {allowed})"
            )
        df[column] = values
    value = pd.to_numeric(df["value"], errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(value)
    if bad.any():
        raise ValueError(f"value: not a finite number in row {int(np.argmax(bad))}")
    if (value < 0).any():
        raise ValueError(f"value: negative in row {int(np.argmax(value < 0))}")
    df["value"] = value
    radius_raw = df["radius_m"].replace("", np.nan)
    radius = pd.to_numeric(radius_raw, errors="coerce").to_numpy(dtype=float)
    unparsable = radius_raw.notna().to_numpy() & np.isnan(radius)
    if unparsable.any():
        raise ValueError(f"radius_m: not a number in row {int(np.argmax(unparsable))}")
    tangent = (df["rail"] == "tangent").to_numpy()
    radius = np.where(tangent & np.isinf(radius), np.nan, radius)
    bad = tangent & ~np.isnan(radius)
    if bad.any():
        raise ValueError(f"radius_m: must be empty on tangent row {int(np.argmax(bad))}")
    bad = ~tangent & ~(np.isfinite(radius) & (radius > 0))
    if bad.any():
        raise ValueError(
            f"radius_m: a curve row needs a finite radius > 0 (row {int(np.argmax(bad))})"
        )
    df["radius_m"] = radius
    key = ["bogie_type", "wheelset", "rail", "radius_m", "region", "measure"]
    dup = df.duplicated(subset=key, keep="first").to_numpy()
    if dup.any():
        raise ValueError(f"row {int(np.argmax(dup))}: duplicate of an earlier row ({key})")
    group = ["bogie_type", "wheelset", "region", "measure"]
    has_tangent = set(map(tuple, df.loc[tangent, group].drop_duplicates().to_numpy()))
    for combo in map(tuple, df.loc[:, group].drop_duplicates().to_numpy()):
        if combo not in has_tangent:
            raise ValueError(
                "rail: missing tangent row for "
                + ", ".join(f"{g}={v}" for g, v in zip(group, combo, strict=True))
            )
    return df


@dataclass(frozen=True)
class WearTable:
    """A compiled, validated wear table: fast look-ups by key.

    ``curves[(bogie_type, wheelset, rail, region, measure)]`` holds ``(curvature_1_per_m,
    value)`` arrays sorted by curvature, for rail high/low including the tangent value at
    curvature 0; ``tangent[(bogie_type, wheelset, region, measure)]`` the tangent value.
    """

    frame: pd.DataFrame
    curves: Mapping[tuple[str, str, str, str, str], tuple[np.ndarray, np.ndarray]]
    tangent: Mapping[tuple[str, str, str, str], float]

    @property
    def bogie_types(self) -> tuple[str, ...]:
        return tuple(sorted({k[0] for k in self.tangent}))

    @property
    def measures(self) -> tuple[str, ...]:
        return tuple(sorted({k[3] for k in self.tangent}))


def compile_wear_table(table: pd.DataFrame | WearTable) -> WearTable:
    """Validate a long wear table and index it for fast interpolation."""
    if isinstance(table, WearTable):
        return table
    df = validate_wear_table(table)
    tangent: dict[tuple[str, str, str, str], float] = {}
    for row in df[df["rail"] == "tangent"].itertuples(index=False):
        tkey = cast(tuple[str, str, str, str],
                    (row.bogie_type, row.wheelset, row.region, row.measure))
        tangent[tkey] = float(cast(float, row.value))
    curves: dict[tuple[str, str, str, str, str], tuple[np.ndarray, np.ndarray]] = {}
    curved = df[df["rail"] != "tangent"]
    for group_key, rows in curved.groupby(
        ["bogie_type", "wheelset", "rail", "region", "measure"], sort=False
    ):
        bogie, wheelset, rail, region, measure = cast(tuple[str, str, str, str, str], group_key)
        k = 1.0 / rows["radius_m"].to_numpy(dtype=float)
        v = rows["value"].to_numpy(dtype=float)
        order = np.argsort(k)
        t0 = tangent[(bogie, wheelset, region, measure)]
        curves[(bogie, wheelset, rail, region, measure)] = (
            np.concatenate([[0.0], k[order]]),
            np.concatenate([[t0], v[order]]),
        )
    return WearTable(frame=df, curves=curves, tangent=tangent)


def table_value(
    table: pd.DataFrame | WearTable,
    bogie_type: str,
    wheelset: str,
    rail: str,
    radius_m: float | None,
    region: str,
    measure: str,
) -> float:
    """Wear measure P_i for one curve class, interpolated linearly in curvature 1/R.

    Parameters
    ----------
    table : long wear table or its compiled :class:`WearTable`
    bogie_type, wheelset ('leading'|'trailing'), rail ('high'|'low'|'tangent'), region
    ('tread'|'flange'), measure ('tau_max'|'t_gamma') : the table key
    radius_m : curve radius [m]; ignored (may be None) for rail 'tangent'

    Returns
    -------
    the wear measure in the table's unit. Between the largest tabulated radius and tangent
    track the value is interpolated towards the tangent row (curvature 0).

    Raises
    ------
    RadiusOutOfTableError if the radius is tighter than the table's smallest radius;
    UnknownTableEntryError (ValueError) if the key has no rows.
    """
    wt = compile_wear_table(table)
    if rail == "tangent":
        try:
            return wt.tangent[(bogie_type, wheelset, region, measure)]
        except KeyError:
            raise UnknownTableEntryError(
                f"bogie_type/wheelset/region/measure: no tangent row for "
                f"{bogie_type}/{wheelset}/{region}/{measure}"
            ) from None
    key = (bogie_type, wheelset, rail, region, measure)
    if key not in wt.curves:
        if (bogie_type, wheelset, region, measure) in wt.tangent:
            raise UnknownTableEntryError(f"rail: no {rail}-rail rows for {'/'.join(key)}")
        raise UnknownTableEntryError(f"bogie_type/measure: no rows for {'/'.join(key)}")
    if radius_m is None or not math.isfinite(float(radius_m)):
        return wt.tangent[(bogie_type, wheelset, region, measure)]
    radius = float(radius_m)
    if radius <= 0:
        raise ValueError(f"radius_m: must be > 0, got {radius}")
    curvature, values = wt.curves[key]
    k = 1.0 / radius
    if k > curvature[-1] * (1.0 + RADIUS_RTOL):
        raise RadiusOutOfTableError(radius, 1.0 / curvature[-1], key)
    return float(np.interp(min(k, curvature[-1]), curvature, values))


def wear_table_to_records(table: pd.DataFrame | WearTable) -> list[dict[str, Any]]:
    """JSON-friendly rows of a table (``radius_m`` None on tangent rows)."""
    df = compile_wear_table(table).frame
    records = cast(list[dict[str, Any]], df.to_dict(orient="records"))
    for r in records:
        if isinstance(r["radius_m"], float) and math.isnan(r["radius_m"]):
            r["radius_m"] = None
    return records


#: A wear measure as a function of (bogie_type, wheelset, rail, radius_m, region, measure);
#: ``radius_m`` None on tangent track.
MeasureFunction = Callable[[str, str, str, float | None, str, str], float]


def sample_wear_table(measure_function: MeasureFunction, radii_m: Sequence[float],
                      decimals: int = 5) -> pd.DataFrame:
    """The long curve-radius table (docs/conventions.md "Curve-radius table CSV") sampling an
    analytic wear measure at ``radii_m`` [m] for both bogie types, wheelset positions,
    measures and regions: one tangent row (unrounded) and one row per high/low rail and radius
    (rounded to ``decimals``)."""
    rows = []
    for bogie in BOGIE_TYPES:
        for ws in WHEELSETS:
            for measure in WEAR_MEASURES:
                for region in REGIONS:
                    rows.append((bogie, ws, "tangent", np.nan, region, measure,
                                 measure_function(bogie, ws, "tangent", None, region, measure)))
                    for rail in ("high", "low"):
                        for r in radii_m:
                            value = measure_function(bogie, ws, rail, r, region, measure)
                            rows.append((bogie, ws, rail, r, region, measure,
                                         round(value, decimals)))
    return pd.DataFrame(rows, columns=list(TABLE_COLUMNS))
