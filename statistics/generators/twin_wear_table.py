"""The fleet twin's synthetic curve-radius table (docs/conventions.md "Curve-radius table CSV"):
smooth wear measures against curvature per bogie type, wheelset, rail and region, a stand-in
for the physics core's tables that follows seed 001 Fig. 10 qualitatively.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS, WEAR_MEASURES, Region
from wearcast.statistics.wear_tables import TABLE_COLUMNS

Array = NDArray[np.float64]


#: The twin draws its random numbers and writes its table rows region by region in this order
#: (tread first); kept so that seeded fleets and the bundled example fleet stay the same.
TWIN_REGION_ORDER: tuple[Region, ...] = REGIONS[::-1]
WEAR_TABLE_COLUMNS = list(TABLE_COLUMNS)


def synthetic_wear_table(radii_m: Sequence[float] = (150, 200, 250, 300, 400, 500, 700, 1000,
                                                     1500, 2000, 3000)) -> pd.DataFrame:
    """A smooth, synthetic curve-radius table in the docs/conventions.md CSV format.

    Stand-in for the physics core's tables; follows seed 001 Fig. 10 qualitatively:

    - flange: zero on tangent track and in wide curves; on the leading wheelset's high-rail
      wheel it rises from curvature 1/1500 m^-1 and grows fast as the radius falls
      (P ~ (kappa - kappa0)^1.3); the trailing wheelset's high-rail wheel flanges only below
      ~400 m and far less; low-rail wheels never flange.
    - tread: nonzero on tangent track, rising moderately with curvature, more on the low rail
      (longitudinal creep) than on the high rail.
    - motor bogies carry a higher T_gamma than trailer bogies (x1.8 in curves, x1.3 on
      tangent: traction creep and stiffer steering), tau_max is similar (x1.05).

    Units: tau_max [MPa] (maximum surface shear traction), t_gamma [N] (wear number).
    Returns a DataFrame with columns ``WEAR_TABLE_COLUMNS``; tangent rows have radius_m NaN.
    """
    rows: list[tuple[object, ...]] = []
    kappa = 1.0 / np.asarray(radii_m, dtype=float)  # [1/m]
    for bogie in ("motor", "trailer"):
        for wheelset in ("leading", "trailing"):
            for measure in WEAR_MEASURES:
                tangent = _synthetic_values(bogie, wheelset, "tangent", np.zeros(1), measure)
                for region in TWIN_REGION_ORDER:
                    rows.append((bogie, wheelset, "tangent", np.nan, region, measure,
                                 float(tangent[region][0])))
                for rail in ("high", "low"):
                    values = _synthetic_values(bogie, wheelset, rail, kappa, measure)
                    for region in TWIN_REGION_ORDER:
                        for r, v in zip(radii_m, values[region], strict=True):
                            rows.append((bogie, wheelset, rail, float(r), region, measure,
                                         round(float(v), 4)))
    return pd.DataFrame(rows, columns=WEAR_TABLE_COLUMNS)


def _synthetic_values(bogie: str, wheelset: str, rail: str, kappa: Array,
                      measure: str) -> dict[str, Array]:
    """Smooth synthetic wear measures vs curvature kappa [1/m] (see ``synthetic_wear_table``)."""
    k = kappa * 1000.0  # curvature in 1/km: 6.67 at R = 150 m
    leading = wheelset == "leading"
    if measure == "tau_max":  # [MPa]
        tread0, tread_slope, flange_scale = 180.0, 22.0, 110.0
        motor_curve, motor_tangent = 1.05, 1.05
    else:  # t_gamma [N]
        tread0, tread_slope, flange_scale = 25.0, 14.0, 90.0
        motor_curve, motor_tangent = 1.8, 1.3
    tread = tread0 + tread_slope * k * (1.25 if rail == "low" else 1.0 if rail == "high" else 0.0)
    if not leading:
        tread = tread0 + 0.8 * (tread - tread0)
    if rail == "high":
        k0 = 1000.0 / 1500.0 if leading else 1000.0 / 400.0
        scale = flange_scale if leading else 0.25 * flange_scale
        flange = scale * np.clip(k - k0, 0.0, None) ** 1.3
    else:
        flange = np.zeros_like(k)
    if bogie == "motor":
        factor = np.where(k > 0, motor_curve, motor_tangent)
        tread = tread * factor
        flange = flange * factor
    return {"tread": np.asarray(tread, dtype=float), "flange": np.asarray(flange, dtype=float)}
