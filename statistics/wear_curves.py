"""Wear curves and wear areas (seed 001 §3.1; docs/conventions.md).

The wear curve is the vertical distance between the reference (new) profile and the aligned
worn profile, w(y) = z_ref(y) - z_worn(y) [mm], positive where material is gone. Seed 001
splits it at y = -30 mm into a flange region (y < -30) and a tread region (y >= -30), where
the averaged wear curves have their minimum; the wear area of a region is A = ∫ w dy [mm²].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import ReferenceHeight, reference_table
from wearcast.statistics.cleaning import resample_profile

#: Common lateral grid of wear curves [mm]: -58 ... +50 every 0.5 mm (217 points). It spans
#: the flange from 3 mm behind the S1002 tip (y = -55) over the flange flank and the tread
#: up to the field-side end of the running band; the flange back (y < -58) does not wear.
DEFAULT_GRID_Y_MM: NDArray[np.float64] = np.linspace(-58.0, 50.0, 217)
DEFAULT_GRID_Y_MM.setflags(write=False)
#: Flange/tread split of seed 001 §3.1 [mm].
DEFAULT_SPLIT_Y_MM = -30.0


@dataclass(frozen=True)
class WearAreas:
    """Wear areas of the two regions of a wear curve.

    Attributes
    ----------
    flange_mm2 : ∫ w dy over y < split [mm²]
    tread_mm2 : ∫ w dy over y >= split [mm²]
    """

    flange_mm2: float
    tread_mm2: float

    @property
    def total_mm2(self) -> float:
        """Sum of both regions [mm²]."""
        return self.flange_mm2 + self.tread_mm2


def reference_on_grid(
    grid_y_mm: ArrayLike = DEFAULT_GRID_Y_MM,
    reference_height: ReferenceHeight = s1002_height_mm,
) -> NDArray[np.float64]:
    """Reference heights [mm] on a lateral grid [mm] (tabulated, NaN where undefined)."""
    return reference_table(reference_height).height_mm(np.asarray(grid_y_mm, dtype=float))


def wear_curve_mm(
    y_aligned_mm: ArrayLike,
    z_aligned_mm: ArrayLike,
    grid_y_mm: ArrayLike = DEFAULT_GRID_Y_MM,
    reference_height: ReferenceHeight = s1002_height_mm,
) -> NDArray[np.float64]:
    """Wear curve w(y) = z_ref(y) - z_worn(y) on a lateral grid.

    Parameters
    ----------
    y_aligned_mm, z_aligned_mm : aligned worn profile [mm], ascending y
        (``AlignedProfile.y_mm``, ``.z_mm``)
    grid_y_mm : lateral grid [mm]
    reference_height : reference profile z(y) [mm] (default S1002)

    Returns
    -------
    w on the grid [mm]; NaN where the profile (or the reference) has no data.

    Seed 001 §3.1: "vertical distance between a reference (new) profile shape and a worn
    profile shape".
    """
    grid = np.asarray(grid_y_mm, dtype=float)
    z_worn = resample_profile(y_aligned_mm, z_aligned_mm, grid)
    return reference_on_grid(grid, reference_height) - z_worn


def wear_areas_mm2(
    grid_y_mm: ArrayLike,
    wear_mm: ArrayLike,
    split_y_mm: float = DEFAULT_SPLIT_Y_MM,
) -> WearAreas:
    """Flange and tread wear areas of a wear curve (:func:`wear_areas_rows` of one row).

    Parameters
    ----------
    grid_y_mm : ascending lateral grid [mm]
    wear_mm : wear curve on the grid [mm], NaN where unknown
    split_y_mm : flange/tread boundary [mm] (seed 001: -30)

    Returns
    -------
    WearAreas with ∫ w dy [mm²] (:func:`wear_areas_rows`).
    """
    y = np.asarray(grid_y_mm, dtype=float)
    w = np.asarray(wear_mm, dtype=float)
    if y.shape != w.shape:
        raise ValueError(f"grid_y_mm and wear_mm differ in length ({y.size} vs {w.size})")
    flange, tread = wear_areas_rows(y, w[None, :], split_y_mm)
    return WearAreas(flange_mm2=float(flange[0]), tread_mm2=float(tread[0]))


def wear_areas_rows(grid_y_mm: NDArray[np.float64], wear_mm: NDArray[np.float64],
                    split_y_mm: float = DEFAULT_SPLIT_Y_MM
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Flange and tread wear areas (M,) [mm²] of each row of ``wear_mm`` (M, g) [mm] on the
    ascending grid (g,) [mm] (seed 001 §3.1: A = ∫ w dy over y < split and y >= split).

    The trapezoid rule; intervals with a NaN end are left out (NaN-aware). An interval
    straddling the split is cut there, w at the split taken by linear interpolation, so that
    flange + tread equals the integral over the whole grid.
    """
    m, g = wear_mm.shape
    if g < 2:
        return np.zeros(m), np.zeros(m)
    dy = np.diff(grid_y_mm)
    segment = 0.5 * (wear_mm[:, 1:] + wear_mm[:, :-1]) * dy  # NaN where an end is NaN
    # intervals [y_i, y_i+1]: flange if y_i+1 <= split, tread if y_i >= split, else straddling
    n_flange = max(int(np.searchsorted(grid_y_mm, split_y_mm, side="right")) - 1, -1)
    cut = max(n_flange, 0)
    flange = np.nansum(segment[:, :cut], axis=1)
    tread = np.nansum(segment[:, cut:], axis=1)
    if 0 <= n_flange < g - 1 and grid_y_mm[n_flange] < split_y_mm:
        # the interval containing the split: cut it, w at the split by linear interpolation
        i = n_flange
        y0, y1 = float(grid_y_mm[i]), float(grid_y_mm[i + 1])
        w0, w1 = wear_mm[:, i], wear_mm[:, i + 1]
        both = np.isfinite(w0) & np.isfinite(w1)
        w_split = w0 + (split_y_mm - y0) * (w1 - w0) / (y1 - y0)
        left = np.where(both, 0.5 * (w0 + w_split) * (split_y_mm - y0), 0.0)
        flange = flange + left
        tread = tread - left
    return flange, tread
