"""The fleet twin's routes: seed 003's Aosta line (Table 3), seed 000's metro lines (Table 1)
and plain tangent track, as curve classes with free attributes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.routes import Route, RouteClass

Array = NDArray[np.float64]


@dataclass(frozen=True)
class TwinRoute(Route):
    """A route (curve classes with shares summing to 1) plus free attributes."""

    attributes: Mapping[str, object] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """The ``POST /v1/routes`` body for this route."""
        return {**self.to_dict(), "attributes": dict(self.attributes)}


def split_directions(radius_m: float | None, cant_mm: float, speed_kmh: float,
                     share: float) -> list[RouteClass]:
    """The route classes of a (radius, share) row whose direction is not given: a tangent
    class (``radius_m`` None), or the curve split into equal left- and right-hand halves."""
    if radius_m is None:
        return [RouteClass(None, None, 0.0, speed_kmh, share)]
    return [RouteClass(radius_m, d, cant_mm, speed_kmh, share / 2.0) for d in ("left", "right")]


# Seed 003 (003_c55c21cb74d435ad), Table 3: Aosta – Pré-Saint-Didier line, statistical track
# description with n_class = 7, N_c = 20 curve tracks. Columns: representative radius R_c [m]
# (None = tangent, "inf" in the paper), superelevation H [mm], speed V [km/h], share p_k [%].
AOSTA_TABLE3 = (
    (162.0, 110.0, 57.0, 0.93), (162.0, 131.0, 60.0, 1.30),
    (195.0, 90.0, 60.0, 7.09), (195.0, 103.0, 60.0, 7.42), (195.0, 126.0, 60.0, 5.48),
    (237.0, 70.0, 60.0, 0.87), (237.0, 83.0, 60.0, 8.76), (237.0, 109.0, 60.0, 4.63),
    (237.0, 120.0, 60.0, 0.47),
    (293.0, 50.0, 60.0, 0.28), (293.0, 65.0, 60.0, 3.05), (293.0, 83.0, 60.0, 0.90),
    (293.0, 100.0, 60.0, 0.31),
    (376.0, 49.0, 60.0, 1.13), (376.0, 62.0, 60.0, 1.26),
    (774.0, 24.0, 60.0, 1.73), (774.0, 40.0, 60.0, 0.42),
    (3572.0, 5.0, 60.0, 2.40), (3572.0, 20.0, 60.0, 0.91),
    (None, 0.0, 130.0, 50.65),
)

# Seed 000 (000_67a233c1b13bf7f0), Table 1: track conditions of metro lines 1 and 2 (type B
# vehicle): radius band [m], share of track length [%], running speed [km/h].
METRO_TABLE1 = (
    (1200.0, math.inf, 75.0, 70.0),
    (800.0, 1200.0, 11.0, 70.0),
    (600.0, 800.0, 11.0, 60.0),
    (350.0, 600.0, 3.0, 40.0),
)


def aosta_route(name: str = "aosta") -> TwinRoute:
    """The Aosta – Pré-Saint-Didier line as 39 curve classes (seed 003 Table 3).

    Each of the 19 curved classes is split into equal left- and right-hand halves (the table
    gives no direction); shares are the printed p_k [%] normalised to sum to 1 (they sum to
    99.99 % as printed).
    """
    total = sum(row[3] for row in AOSTA_TABLE3)
    classes: list[RouteClass] = []
    for radius_m, cant_mm, speed_kmh, share_pct in AOSTA_TABLE3:
        classes += split_directions(radius_m, cant_mm, speed_kmh, share_pct / total)
    return TwinRoute(name, tuple(classes), {
        "source": "seed 003 Table 3 (Aosta - Pre Saint Didier, n_class=7)",
        "line_type": "regional, mountain", "flange_lubrication": False,
    })


def metro_route(name: str = "metro", max_cant_mm: float = 120.0) -> TwinRoute:
    """Metro lines 1/2 of seed 000 Table 1 as curve classes.

    The band R > 1200 m (75 %) is taken as tangent track; each other band is represented by
    its mid radius. Cant is not printed: it is set to the equilibrium cant
    11.8 V^2 / R [mm] (V km/h, R m, standard gauge), capped at ``max_cant_mm``. Curves are
    split into equal left and right halves (the lines are built of S-curves, seed 000 §V).
    """
    classes: list[RouteClass] = []
    for r_min, r_max, share_pct, speed_kmh in METRO_TABLE1:
        if math.isinf(r_max):
            classes += split_directions(None, 0.0, speed_kmh, share_pct / 100.0)
            continue
        radius_m = 0.5 * (r_min + r_max)
        cant_mm = min(max_cant_mm, round(11.8 * speed_kmh**2 / radius_m))
        classes += split_directions(radius_m, float(cant_mm), speed_kmh, share_pct / 100.0)
    return TwinRoute(name, tuple(classes), {
        "source": "seed 000 Table 1 (metro lines 1 and 2, type B vehicle)",
        "line_type": "metro", "flange_lubrication": False,
    })


def tangent_route(name: str = "tangent", speed_kmh: float = 100.0) -> TwinRoute:
    """100 % tangent track (the application example of seed 001 Fig. 15)."""
    return TwinRoute(name, (RouteClass(None, None, 0.0, speed_kmh, 1.0),),
                     {"source": "seed 001 Fig. 15 (100 % tangent track)", "line_type": "tangent"})
