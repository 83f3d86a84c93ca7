"""``np.interp`` on an evenly spaced table, by direct index instead of binary search.

The reference profile is tabulated on an even 0.01 mm grid (:func:`.alignment.reference_table`,
16,001 points). ``np.interp`` finds each query's interval by binary search; on an even grid
the interval is ``floor((x - x0) / step)``, corrected by one where rounding put it next door,
so a lookup costs a few array operations whatever the table's length. The value is then
computed with ``np.interp``'s own formula, slope of the interval times the distance from its
left node plus the left value, so the results are the same numbers as ``np.interp``'s
(tests/statistics/test_alignment_batch.py compares them).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.alignment import ReferenceHeight, reference_table


class EvenTable:
    """Values tabulated on an evenly spaced ascending grid ``x`` [any unit].

    ``columns`` are the tabulated value arrays (each as long as ``x``).
    """

    def __init__(self, x: NDArray[np.float64], *columns: NDArray[np.float64]) -> None:
        if x.size < 2:
            raise ValueError("a table needs at least two grid points")
        steps = np.diff(x)
        self.even = bool(np.all(steps > 0)
                         and np.ptp(steps) <= 1e-9 * float(np.abs(steps).max()))
        self.x = x
        self.x0 = float(x[0])
        self.x_last = float(x[-1])
        self.inv_step = (x.size - 1) / (self.x_last - self.x0)
        self.columns = columns
        # np.interp's slope of each interval, (f[j+1] - f[j]) / (x[j+1] - x[j])
        self.slopes = [(c[1:] - c[:-1]) / steps for c in columns]

    def locate(self, xq: NDArray[np.float64]) -> NDArray[np.intp]:
        """Interval j of each query, x[j] <= xq < x[j+1] (clipped to the table's ends)."""
        last = self.x.size - 2
        with np.errstate(invalid="ignore"):
            j = np.clip(np.floor((xq - self.x0) * self.inv_step), 0, last)
        j = np.nan_to_num(j).astype(np.intp)
        j -= (xq < self.x[j]) & (j > 0)
        j += (xq >= self.x[j + 1]) & (j < last)
        return j

    def interp(self, xq: NDArray[np.float64], j: NDArray[np.intp], column: int,
               left: float | None = None, right: float | None = None) -> NDArray[np.float64]:
        """``np.interp(xq, x, columns[column], left, right)`` for queries located at ``j``."""
        if not self.even:
            return np.interp(xq, self.x, self.columns[column], left=left, right=right)
        f = self.columns[column]
        out = self.slopes[column][j] * (xq - self.x[j]) + f[j]
        out = np.where(xq == self.x[j], f[j], out)
        out = np.where(xq >= self.x_last, f[-1], out)
        out = np.where(xq < self.x0, f[0] if left is None else left, out)
        if right is not None:
            out = np.where(xq > self.x_last, right, out)
        return np.where(np.isnan(xq), np.nan, out)


@lru_cache(maxsize=16)
def reference_even_table(reference_height: ReferenceHeight) -> EvenTable:
    """The reference's table (:func:`.alignment.reference_table`): columns height z [mm]
    (0) and slope dz/dy (1) on its lateral grid y [mm]."""
    table = reference_table(reference_height)
    return EvenTable(table.y_mm, table.z_mm, table.slope)
