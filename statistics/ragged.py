"""Many 1-D arrays of different lengths as one padded 2-D array, for batched numpy work.

The batched profile processing (:mod:`wearcast.statistics.alignment_batch`,
:mod:`wearcast.statistics.processing_batch`) runs each step once over a chunk of profiles
instead of once per profile: the profiles' points become the rows of an (M, L) array, padded
on the right, with a mask of the valid entries.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray


def pack(arrays: Sequence[NDArray], fill: float) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """(M, L) float array of the rows ``arrays`` (L the longest), padded with ``fill``, and the
    mask of the valid entries (each row's first ``len(arrays[i])`` columns)."""
    lengths = np.fromiter((a.size for a in arrays), np.int64, len(arrays))
    width = int(lengths.max()) if lengths.size else 0
    out = np.full((len(arrays), width), fill, dtype=float)
    valid = np.arange(width) < lengths[:, None]
    if lengths.size:
        out[valid] = np.concatenate([np.asarray(a, dtype=float).ravel() for a in arrays])
    return out, valid


def compact(mask: NDArray[np.bool_], *columns: NDArray, fill: float = 0.0
            ) -> tuple[list[NDArray[np.float64]], NDArray[np.bool_]]:
    """The entries of each (M, L) array in ``columns`` where ``mask`` holds, moved to the
    left of their row (order kept) in (M, F) arrays (F the largest count), padded with
    ``fill``; and the mask of the valid entries of the result."""
    counts = mask.sum(axis=1)
    width = int(counts.max()) if counts.size else 0
    valid = np.arange(width) < counts[:, None]
    out = []
    for values in columns:
        packed = np.full((mask.shape[0], width), fill, dtype=float)
        packed[valid] = values[mask]
        out.append(packed)
    return out, valid


def rows_of(values: NDArray, valid: NDArray[np.bool_]) -> list[NDArray[np.float64]]:
    """The valid entries of each row of ``values`` as its own (copied) 1-D array; the valid
    entries of a row must be its first ones (as :func:`pack` and :func:`compact` make)."""
    lengths = valid.sum(axis=1)
    return [values[i, :n].copy() for i, n in enumerate(lengths.tolist())]


def upper_median(values: NDArray, valid: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Per row, the element a per-row ``np.partition(v, n // 2)[n // 2]`` picks from the
    row's valid entries v (n of them): the upper median. NaN for a row without entries."""
    counts = valid.sum(axis=1)
    ordered = np.sort(np.where(valid, values, np.inf), axis=1)
    out = np.full(values.shape[0], np.nan)
    has = counts > 0
    if ordered.shape[1]:
        picked = ordered[np.arange(values.shape[0]), np.minimum(counts // 2,
                                                                 ordered.shape[1] - 1)]
        out[has] = picked[has]
    return out
