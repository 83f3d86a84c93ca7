"""The progression a simulation of the route expects: the finder's null for wear that is not
linear in mileage.

The hybrid model (seed 001 eqs. 2-4) grows every wear area linearly in mileage,
A_r = c_s,r P_r s. The physics wear loop does not: as the profile wears, the contact moves and
the rate changes (seed 003 §6; ``physics.wear_loop``), so measured wheels that wear exactly as
the simulation of their route says are curved in s. Tested against the linear law, the finder
names ``nonlinear_progression`` on such data although nothing is wrong with the route, the
vehicle or the measurements: the linear null is misspecified for them.

``ExpectedProgression`` is the progression shape of a simulation of the same route and
vehicle, per bogie type, wheelset (leading / trailing) and region:

    g(s) = A_sim(s) / (k s),   k = sum A_sim(s_j) s_j / sum s_j^2

the simulated area over the least-squares linear growth through the origin on the same
mileages (the rate a curve-radius table made from the same simulation carries,
``generators.scenarios.loop_rate_table``). The finder's baseline then predicts, per
measurement and region,

    A_r = c_s,r s [p P_lead g_lead(s) + (1 - p) P_trail g_trail(s)] / [p P_lead + (1 - p) P_trail]

(p the leading share of the row's running mode, P_lead / P_trail the route's wear measures of
the two wheelset positions), and every cause -- ``nonlinear_progression`` included -- is
scored and resampled against that baseline: a cause is a departure from the simulated
progression, not from a straight line. g is interpolated linearly in log s between the grid
mileages and held at its end values outside them.

``exponent_offset`` is the power-law exponent minus 1 that the expected progression itself
has over the data's own mileages (least squares of log g on the life-centred log s that
``nonlinear_progression`` uses), so a named ``nonlinear_progression`` reports and saves the
total exponent (expected plus departure) for the linear hybrid model.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vocabulary import REGION_SPLIT_Y_MM, REGIONS, WHEELSETS

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ExpectedProgression:
    """Simulated progression shapes g(s) [-] on a mileage grid [km] (module docstring).

    mileage_km : (k,) increasing positive mileages of the grid, in the fleet's km
    factors : {(bogie_type, wheelset, region): (k,) g at the grid mileages}
    source : plain-language origin (e.g. the simulation), reported with the diagnosis
    """

    mileage_km: Array
    factors: Mapping[tuple[str, str, str], Array]
    source: str = "simulation"

    def __post_init__(self) -> None:
        s = np.asarray(self.mileage_km, dtype=float)
        if s.ndim != 1 or s.size < 2 or np.any(s <= 0) or np.any(np.diff(s) <= 0):
            raise ValueError("expected_progression.mileage_km: needs >= 2 increasing mileages "
                             "> 0")
        for key, g in self.factors.items():
            g = np.asarray(g, dtype=float)
            if g.shape != s.shape or not np.all(np.isfinite(g)) or np.any(g <= 0):
                raise ValueError(f"expected_progression.factors[{key}]: needs {s.size} finite "
                                 "values > 0")
            if key[1] not in WHEELSETS or key[2] not in REGIONS:
                raise ValueError(f"expected_progression.factors: bad key {key}; wheelset in "
                                 f"{WHEELSETS}, region in {REGIONS}")

    @classmethod
    def from_areas(cls, mileage_km: ArrayLike,
                   areas_mm2: Mapping[tuple[str, str, str], ArrayLike],
                   source: str = "simulation") -> ExpectedProgression:
        """From simulated wear areas [mm^2] at ``mileage_km`` per (bogie type, wheelset,
        region): g = A / (k s) with k the least-squares rate through the origin. A region
        that does not wear in the simulation (all areas <= 0) gets g = 1."""
        s = np.asarray(mileage_km, dtype=float)
        out: dict[tuple[str, str, str], Array] = {}
        for key, a in areas_mm2.items():
            area = np.asarray(a, dtype=float)
            k = float(np.sum(area * s) / np.sum(s * s))
            if k <= 0 or np.any(area <= 0):
                out[key] = np.ones_like(s)
            else:
                out[key] = area / (k * s)
        return cls(s, out, source)

    def factor(self, bogie_type: str, wheelset: str, region: str, mileage_km: ArrayLike
               ) -> Array:
        """g(s) at ``mileage_km`` (log-log interpolation, ends held; 1 at s <= 0)."""
        key = (str(bogie_type), wheelset, region)
        if key not in self.factors:
            raise ValueError(f"expected_progression: no progression for bogie type "
                             f"{bogie_type!r}, {wheelset} wheelset, {region}")
        s = np.asarray(mileage_km, dtype=float)
        grid = np.log(np.asarray(self.mileage_km, dtype=float))
        logg = np.log(np.asarray(self.factors[key], dtype=float))
        out = np.exp(np.interp(np.log(np.maximum(s, 1e-9)), grid, logg))
        return np.asarray(np.where(s > 0, out, 1.0))

    def row_factors(self, bogie_type: ArrayLike, mileage_km: ArrayLike, parts: Array,
                    lead_share: ArrayLike, measure_index: int) -> Array:
        """(n, 2) expected factor per measurement and region: each wheelset position's g
        weighted by its share of the row's wear measure (module docstring).

        parts : (n, measure, region, wheelset, part) route parts (``residuals``)
        """
        bogie = np.asarray(bogie_type).astype(str)
        s = np.asarray(mileage_km, dtype=float)
        p = np.asarray(lead_share, dtype=float)
        per_ws = np.asarray(parts)[:, measure_index].sum(axis=3)     # (n, region, wheelset)
        w = np.stack([per_ws[:, :, 0] * p[:, None], per_ws[:, :, 1] * (1.0 - p[:, None])],
                     axis=2)                                          # (n, region, wheelset)
        out = np.ones((s.size, 2))
        for b in np.unique(bogie):
            rows = bogie == b
            for r, region in enumerate(REGIONS):
                g = np.stack([self.factor(b, ws, region, s[rows]) for ws in WHEELSETS], axis=1)
                ww = w[rows, r]
                tot = ww.sum(axis=1)
                mix = np.sum(ww * g, axis=1) / np.where(tot > 0, tot, 1.0)
                out[rows, r] = np.where(tot > 0, mix, g.mean(axis=1))
        return out

    def describe(self) -> dict[str, Any]:
        """JSON-able summary: the source and g at the grid per key."""
        return {"source": self.source, "mileage_km": [float(v) for v in self.mileage_km],
                "factors": {"/".join(k): [float(v) for v in g] for k, g in self.factors.items()}}


@dataclass(frozen=True)
class SimulatedWheel:
    """One wheel's wear-loop run (``physics.wear_simulation.WearSimulation``): its bogie
    type and axle (1 leads in the reference direction), lateral grid y [mm], profiles z after
    each step [mm] (row 0 the initial one) and the mileage of each row [km]."""

    bogie_type: str
    axle: int
    y_mm: Array
    profiles_mm: Array
    mileage_km: Array

    def region_areas_mm2(self, mileage_km: Array) -> dict[str, Array]:
        """Worn area of each region at ``mileage_km`` [mm^2]: the vertical wear
        z_initial - z, linear between steps, integrated over the region (flange
        y < ``REGION_SPLIT_Y_MM``, tread y >= it), as the measured areas are."""
        y = np.asarray(self.y_mm, dtype=float)
        z = np.asarray(self.profiles_mm, dtype=float)
        m = np.asarray(self.mileage_km, dtype=float)
        if z.ndim != 2 or z.shape != (m.size, y.size) or m.size < 2 or np.any(np.diff(m) <= 0):
            raise ValueError("simulation: needs profiles (steps x points) at >= 2 increasing "
                             "mileages")
        wear = z[0] - z
        out: dict[str, Array] = {}
        for region in REGIONS:
            sel = y < REGION_SPLIT_Y_MM if region == "flange" else y >= REGION_SPLIT_Y_MM
            per_step = np.trapezoid(wear[:, sel], y[sel], axis=1)
            out[region] = np.interp(mileage_km, m, per_step)
        return out


def progression_from_simulations(wheels: Sequence[SimulatedWheel], source: str,
                                 n_points: int = 20) -> ExpectedProgression:
    """The expected progression of wear-loop runs of the route: per bogie type, wheelset
    (axle 1 leading, 2 trailing) and region the mean worn area of its runs (e.g. the left
    and right wheels) at ``n_points`` mileages up to the shortest run's end, through
    :meth:`ExpectedProgression.from_areas`."""
    if not wheels:
        raise ValueError("simulations: needs at least one wear-loop run")
    top = min(float(np.asarray(w.mileage_km)[-1]) for w in wheels)
    if not top > 0:
        raise ValueError("simulations: a run covers no mileage")
    grid = np.linspace(0.0, top, n_points + 1)[1:]
    groups: dict[tuple[str, str], list[dict[str, Array]]] = {}
    for w in wheels:
        if w.axle not in (1, 2):
            raise ValueError(f"simulations: axle must be 1 or 2, got {w.axle!r}")
        wheelset = WHEELSETS[w.axle - 1]
        groups.setdefault((w.bogie_type, wheelset), []).append(w.region_areas_mm2(grid))
    areas: dict[tuple[str, str, str], Array] = {
        (bogie, wheelset, str(region)): np.mean([a[region] for a in runs], axis=0)
        for (bogie, wheelset), runs in groups.items() for region in REGIONS}
    return ExpectedProgression.from_areas(grid, areas, source=source)


def exponent_offset(log_factor: Array, centred_log_s: Array) -> Array:
    """(2,) exponent minus 1 of the expected progression over the data, per region: least
    squares of the life-centred log factor on the life-centred log mileage (the
    ``nonlinear_progression`` feature)."""
    x = np.asarray(centred_log_s, dtype=float)
    den = float(np.sum(x * x))
    if den <= 0:
        return np.zeros(2)
    return np.asarray([float(np.sum(x * log_factor[:, r]) / den) for r in range(2)])


def centred(values: Array, life: NDArray[Any], mileage_km: Array) -> Array:
    """``values`` (n,) or (n, m) minus their mean within each wheel life (rows with s > 0)."""
    v = np.asarray(values, dtype=float)
    pos = np.asarray(mileage_km) > 0
    key = np.where(pos, np.asarray(life).astype(str), "_")
    frame = pd.DataFrame(v.reshape(v.shape[0], -1))
    mean = frame.groupby(key).transform("mean").to_numpy().reshape(v.shape)
    return np.asarray(np.where(pos.reshape((-1,) + (1,) * (v.ndim - 1)), v - mean, 0.0))
