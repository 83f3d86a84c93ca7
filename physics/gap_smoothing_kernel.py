"""The gap smoothing's Gaussian filters as a compiled kernel (``gap_smoothing``).

``gaussian_rows(values, taps0, taps1, taps2)`` filters each row of ``values`` (R, n) with a
Gaussian and with its first and second derivatives at once: what
``scipy.ndimage.gaussian_filter1d(values, sigma, axis=-1, order=o, mode="nearest")`` gives
for o = 0, 1, 2, with its arithmetic (the row extended by its end values, each output the
centre sample times the centre tap plus, from the farthest pair inwards, the pair's sum (even
taps) or difference (odd taps) times the tap), so the results equal scipy's bit for bit
(``tests/physics/test_gap_smoothing_kernel.py``). The taps are read off scipy's own response to a
unit impulse (:func:`gaussian_taps`). The masked smoothing of the curving contact table
(``gap_smoothing.masked_gaussian``) needs six such filters of an (n_shift, n_wheel) array per
table, about two thirds of the table's build time with scipy's filter one order at a time;
the kernel shares the row's extension and its loop over the three orders.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.ndimage import gaussian_filter1d

#: Truncation of the Gaussian [standard deviations] (scipy's default ``truncate``).
TRUNCATE_SD = 4.0


@lru_cache(maxsize=16)
def gaussian_taps(sigma_samples: float, order: int) -> NDArray[np.float64]:
    """The taps scipy's Gaussian filter of ``order`` (0, 1, 2) with standard deviation
    ``sigma_samples`` [samples] applies at offsets 0 ... radius [samples] (the weight of the
    sample that far after the output; the sample as far before it takes the same weight for an
    even order and its negative for an odd one): scipy's response to a unit impulse."""
    if order not in (0, 1, 2):
        raise ValueError(f"order must be 0, 1 or 2, got {order!r}")
    radius = int(TRUNCATE_SD * float(sigma_samples) + 0.5)
    impulse = np.zeros(2 * radius + 1)
    impulse[radius] = 1.0
    response = gaussian_filter1d(impulse, sigma_samples, order=order, mode="constant",
                                 cval=0.0, truncate=TRUNCATE_SD)
    # scipy's symmetric (even order) or antisymmetric (odd) branch, whose order of summation
    # the kernel follows: the response before the impulse mirrors the one after it
    sign = -1.0 if order % 2 else 1.0
    if not np.array_equal(response[:radius][::-1], sign * response[radius + 1:]):
        raise ValueError("scipy's Gaussian filter is not symmetric here; the kernel does not "
                         "reproduce it")
    taps = response[radius:].copy()
    taps.setflags(write=False)
    return taps


@njit(cache=True)
def gaussian_rows(values: NDArray[np.float64], taps0: NDArray[np.float64],
                  taps1: NDArray[np.float64], taps2: NDArray[np.float64]
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Each row of ``values`` (R, n) filtered with the Gaussian (``taps0``) and its first
    (``taps1``) and second (``taps2``) derivatives (:func:`gaussian_taps`, one radius), mode
    ``nearest``: three (R, n) arrays, scipy's numbers (module docstring). The units are the
    values' per sample^order."""
    n_rows, n = values.shape
    r = taps0.size - 1
    out0 = np.empty((n_rows, n))
    out1 = np.empty((n_rows, n))
    out2 = np.empty((n_rows, n))
    extended = np.empty(n + 2 * r)  # the row and r copies of each end value beyond it
    acc0 = np.empty(n)
    acc1 = np.empty(n)
    acc2 = np.empty(n)
    for i in range(n_rows):
        for q in range(n + 2 * r):
            extended[q] = values[i, min(max(q - r, 0), n - 1)]
        for col in range(n):
            centre = extended[col + r]
            acc0[col] = centre * taps0[0]
            acc1[col] = centre * taps1[0]
            acc2[col] = centre * taps2[0]
        for d in range(r, 0, -1):  # scipy's order: the farthest pair first
            w0 = taps0[d]
            w1 = taps1[d]
            w2 = taps2[d]
            before = extended[r - d: r - d + n]
            after = extended[r + d: r + d + n]
            for col in range(n):
                pair = before[col] + after[col]
                acc0[col] += pair * w0
                acc1[col] += (before[col] - after[col]) * w1
                acc2[col] += pair * w2
        out0[i] = acc0
        out1[i] = acc1
        out2[i] = acc2
    return out0, out1, out2
