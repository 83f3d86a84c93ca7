""":func:`.cleaning.clean_profile` for many raw profiles of the same length at once.

An import's profiles mostly come from one instrument setting: the same number of points, in
lateral order one way or the other, without NaN, duplicates or spikes. For those the cleaning
rules of :mod:`.cleaning` reduce to: order the points (reverse a profile given field side
first), detect the orientation (flip z or mirror y), trim the near-vertical ends, check the
coverage -- done here once over the chunk, the profiles as rows of one (M, n) array. The
values are the raw ones (reversed, negated, trimmed), so they equal ``clean_profile``'s
exactly. Any other profile (a NaN point, points stepping back, points merged or spikes
removed, a profile that fails a check) gets ``None``: the caller runs ``clean_profile`` on it,
which applies the full rules (and raises the same ``ValueError`` for an unusable profile).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.cleaning import (
    _END_BAND_MM,
    MIN_FLANGE_HEIGHT_MM,
    MIN_POINTS,
    MIN_TREAD_REACH_MM,
    CleanedProfile,
)

_Z_FLIP_NOTE = "z was given downward (flange tip as minimum): flipped z -> -z"
_Y_MIRROR_NOTE = "y was mirrored (flange on the positive side): flipped y -> -y"


def _upper_median(values: NDArray, mask: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Per row, ``np.partition(v, n // 2)[n // 2]`` of the row's masked entries v (n >= 1)."""
    counts = mask.sum(axis=1)
    kth = counts // 2
    filled = np.where(mask, values, np.inf)
    part = np.partition(filled, np.unique(kth), axis=1)
    return part[np.arange(values.shape[0]), kth]


def clean_profiles_batch(
    profiles: Sequence[tuple[NDArray, NDArray]],
    *,
    min_spacing_mm: float = 0.05,
    max_end_slope: float = 20.0,
    spike_mm: float = 1.0,
) -> list[CleanedProfile | None]:
    """``clean_profile`` of each raw (y_mm, z_mm) profile [mm] that needs no more than
    ordering, orientation and end trimming; ``None`` for the others (module docstring).

    Profiles of different lengths are handled in groups of one length.
    """
    out: list[CleanedProfile | None] = [None] * len(profiles)
    by_length: dict[int, list[int]] = {}
    for i, (y, z) in enumerate(profiles):
        ya, za = np.asarray(y), np.asarray(z)
        if ya.ndim == 1 and ya.shape == za.shape and ya.size >= MIN_POINTS:
            by_length.setdefault(ya.size, []).append(i)
    for indices in by_length.values():
        y = np.array([profiles[i][0] for i in indices], dtype=float)
        z = np.array([profiles[i][1] for i in indices], dtype=float)
        with np.errstate(invalid="ignore", over="ignore"):
            rows = _clean_rows(y, z, min_spacing_mm, max_end_slope, spike_mm)
        for i, cleaned in zip(indices, rows, strict=True):
            out[i] = cleaned
    return out


def _clean_rows(y: NDArray, z: NDArray, min_spacing_mm: float, max_end_slope: float,
                spike_mm: float) -> list[CleanedProfile | None]:
    m, n = y.shape
    ok = np.isfinite(y).all(axis=1) & np.isfinite(z).all(axis=1)
    ok &= (y.max(axis=1) - y.min(axis=1)) >= 1.0
    # strictly monotonic raw order: nothing steps back, the sort is the identity or reversal
    dy = np.diff(y, axis=1)
    forward: NDArray[np.bool_] = np.all(dy > 0.0, axis=1)
    backward: NDArray[np.bool_] = np.all(dy < 0.0, axis=1)
    ok &= forward | backward
    y = np.where(backward[:, None], y[:, ::-1], y)
    z = np.where(backward[:, None], z[:, ::-1], z)
    # no two points in one lateral bin (nothing merged)
    bins = np.floor((y - y[:, :1]) / min_spacing_mm)
    ok &= (bins[:, 1:] != bins[:, :-1]).all(axis=1)
    # no single-point spikes
    chord_dy = y[:, 2:] - y[:, :-2]
    chord_dz = z[:, 2:] - z[:, :-2]
    off = np.abs((y[:, 1:-1] - y[:, :-2]) * chord_dz - (z[:, 1:-1] - z[:, :-2]) * chord_dy)
    ok &= ~(off > spike_mm * np.hypot(chord_dy, chord_dz)).any(axis=1)
    # orientation: the largest deviation from the tread level away from the ends
    inner = (y > y[:, :1] + _END_BAND_MM) & (y < y[:, -1:] - _END_BAND_MM)
    ok &= inner.sum(axis=1) >= MIN_POINTS // 2
    inner[~ok] = True  # rows already refused: any values, never used
    level = _upper_median(z, inner)
    deviation = np.where(inner, np.abs(z - level[:, None]), -np.inf)
    k = np.argmax(deviation, axis=1)
    rows = np.arange(m)
    flip_z = z[rows, k] < level
    mirror_y = y[rows, k] > 0.5 * (y[:, 0] + y[:, -1])
    z = np.where(flip_z[:, None], -z, z)
    y = np.where(mirror_y[:, None], -y[:, ::-1], y)
    z = np.where(mirror_y[:, None], z[:, ::-1], z)
    # near-vertical ends (back face)
    steep = np.abs(np.diff(z, axis=1)) > max_end_slope * np.diff(y, axis=1)
    all_steep = steep.all(axis=1)
    first = np.where(all_steep, n - 1, np.argmin(steep, axis=1))
    last = np.where(all_steep, 0, n - 1 - np.argmin(steep[:, ::-1], axis=1))
    trimmed = steep[:, 0] | steep[:, -1]
    first = np.where(trimmed, first, 0)
    last = np.where(trimmed, last, n - 1)
    size = last - first + 1
    ok &= size >= MIN_POINTS
    # coverage: a flange tip standing above the tread, data reaching over the tread
    cols = np.arange(n)
    kept = (cols >= first[:, None]) & (cols <= last[:, None])
    tip = np.argmax(np.where(kept, z, -np.inf), axis=1)
    y_tip, z_tip = y[rows, tip], z[rows, tip]
    field = kept & (cols > tip[:, None])
    has_field = field.any(axis=1)
    tread_level = np.where(has_field, _upper_median(z, field | ~has_field[:, None]), z_tip)
    ok &= z_tip - tread_level >= MIN_FLANGE_HEIGHT_MM
    ok &= y[rows, last] - y_tip >= MIN_TREAD_REACH_MM
    out: list[CleanedProfile | None] = []
    for i in range(m):
        if not ok[i]:
            out.append(None)
            continue
        a, b = int(first[i]), int(last[i]) + 1
        notes = []
        if flip_z[i]:
            notes.append(_Z_FLIP_NOTE)
        if mirror_y[i]:
            notes.append(_Y_MIRROR_NOTE)
        if trimmed[i]:
            notes.append(f"trimmed {n - (b - a)} points of near-vertical end runs (back face)")
        out.append(CleanedProfile(y_mm=y[i, a:b].copy(), z_mm=z[i, a:b].copy(),
                                  n_removed=n - (b - a), notes=tuple(notes)))
    return out
