""":func:`.cleaning.clean_profile` for many raw profiles of the same length at once.

The rules of :mod:`.cleaning` (steps 2-8: point order and zig-zags, one mean point per lateral
bin, single-point spikes, orientation, near-vertical ends, coverage) run once over a chunk,
the profiles as rows of one (M, n) array; where a step drops or merges points the rows are
compacted again (:func:`.ragged.compact`). Every value is computed by the same operations in
the same order as ``clean_profile`` does (the bin means by the same ``np.add.reduceat``), so
the cleaned points, the counts and the notes equal ``clean_profile``'s exactly
(tests/statistics/test_processing_batch.py). A profile with a NaN point, one whose raw order
is not lateral, and one that fails a check get ``None``: the caller runs ``clean_profile`` on
it (which raises the same ``ValueError`` for an unusable profile).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.cleaning import (
    _END_BAND_MM,
    _MIN_KEPT_FRACTION,
    MIN_FLANGE_HEIGHT_MM,
    MIN_POINTS,
    MIN_TREAD_REACH_MM,
    CleanedProfile,
)
from wearcast.statistics.ragged import compact

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
    """``clean_profile`` of each raw (y_mm, z_mm) profile [mm]; ``None`` where the caller
    must run ``clean_profile`` itself (module docstring).

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


def _packed(flat: NDArray, counts: NDArray, width: int, fill: float) -> NDArray:
    """(M, width) rows of ``counts[i]`` consecutive values of ``flat`` each, padded."""
    out = np.full((counts.size, width), fill)
    out[np.arange(width) < counts[:, None]] = flat
    return out


def _clean_rows(y: NDArray, z: NDArray, min_spacing_mm: float, max_end_slope: float,
                spike_mm: float) -> list[CleanedProfile | None]:
    m, n = y.shape
    rows = np.arange(m)
    ok = np.isfinite(y).all(axis=1) & np.isfinite(z).all(axis=1)
    ok &= (y.max(axis=1) - y.min(axis=1)) >= 1.0
    y = np.where(ok[:, None], y, np.arange(n, dtype=float))  # refused rows: any tame values
    z = np.where(ok[:, None], z, 0.0)
    # --- point order and zig-zags (the rule of clean_profile, row by row) ---
    dy = np.diff(y, axis=1)
    forward = np.count_nonzero(dy > 0.0, axis=1) / dy.shape[1]
    ok &= np.maximum(forward, 1.0 - forward) >= 0.8
    y_run = np.where((forward >= 0.5)[:, None], y, -y)
    keep = np.ones((m, n), dtype=bool)
    keep[:, 1:] = y_run[:, 1:] >= np.maximum.accumulate(y_run, axis=1)[:, :-1]
    local = keep.sum(axis=1) < _MIN_KEPT_FRACTION * n
    if local.any():
        keep[local, 1:] = np.diff(y_run[local], axis=1) >= 0.0
    n_back = n - keep.sum(axis=1)
    (y, z), valid = compact(keep, y, z, fill=np.inf)
    order = np.argsort(y, axis=1, kind="stable")  # the padding (inf) stays at the end
    y = np.take_along_axis(y, order, axis=1)
    z = np.take_along_axis(z, order, axis=1)
    # --- one mean point per lateral bin ---
    width = y.shape[1]
    with np.errstate(invalid="ignore"):
        bins = np.floor((y - y[:, :1]) / min_spacing_mm)
    new_bin = np.ones((m, width), dtype=bool)
    np.not_equal(bins[:, 1:], bins[:, :-1], out=new_bin[:, 1:])
    new_bin &= valid
    flat_new = new_bin[valid]
    starts = np.flatnonzero(flat_new)
    counts = np.diff(np.append(starts, flat_new.size))
    n_kept = valid.sum(axis=1)
    n_bins = new_bin.sum(axis=1)
    n_merged = n_kept - n_bins
    y = _packed(np.add.reduceat(y[valid], starts) / counts, n_bins, width, 0.0)
    z = _packed(np.add.reduceat(z[valid], starts) / counts, n_bins, width, 0.0)
    size = n_bins
    ok &= size >= MIN_POINTS
    # --- single-point spikes ---
    cols = np.arange(width)
    chord_dy = y[:, 2:] - y[:, :-2]
    chord_dz = z[:, 2:] - z[:, :-2]
    off = np.abs((y[:, 1:-1] - y[:, :-2]) * chord_dz - (z[:, 1:-1] - z[:, :-2]) * chord_dy)
    spikes = (off > spike_mm * np.hypot(chord_dy, chord_dz)) & (cols[1:-1] < size[:, None] - 1)
    n_spikes = spikes.sum(axis=1)
    if n_spikes.any():
        keep = cols < size[:, None]
        keep[:, 1:-1] &= ~spikes
        (y, z), _ = compact(keep, y, z)
        size = size - n_spikes
        width = y.shape[1]
        cols = np.arange(width)
    valid = cols < size[:, None]
    last_col = np.maximum(size - 1, 0)
    # --- orientation: the largest deviation from the tread level away from the ends ---
    inner = valid & (y > y[:, :1] + _END_BAND_MM) & (y < y[rows, last_col][:, None] - _END_BAND_MM)
    ok &= inner.sum(axis=1) >= MIN_POINTS // 2
    inner[~ok] = valid[~ok]  # refused rows: any values, never used
    inner[:, 0] |= ~inner.any(axis=1)
    level = _upper_median(z, inner)
    k = np.argmax(np.where(inner, np.abs(z - level[:, None]), -np.inf), axis=1)
    flip_z = z[rows, k] < level
    mirror_y = y[rows, k] > 0.5 * (y[:, 0] + y[rows, last_col])
    z = np.where(flip_z[:, None], -z, z)
    mirrored = np.where(valid, last_col[:, None] - cols, cols)
    y = np.where(mirror_y[:, None], -np.take_along_axis(y, mirrored, axis=1), y)
    z = np.where(mirror_y[:, None], np.take_along_axis(z, mirrored, axis=1), z)
    # --- near-vertical ends (back face) ---
    in_diff = cols[:-1] < last_col[:, None]
    steep = (np.abs(np.diff(z, axis=1)) > max_end_slope * np.diff(y, axis=1)) & in_diff
    trimmed = steep[:, 0] | steep[rows, np.maximum(last_col - 1, 0)]
    gentle = ~steep & in_diff
    has_gentle = gentle.any(axis=1)
    first = np.where(has_gentle, np.argmax(gentle, axis=1), last_col)
    last = np.where(has_gentle, np.where(gentle, cols[:-1], -1).max(axis=1) + 1, 0)
    first = np.where(trimmed, first, 0)
    last = np.where(trimmed, last, last_col)
    ok &= last - first + 1 >= MIN_POINTS
    # --- coverage: a flange tip standing above the tread, data reaching over the tread ---
    kept = (cols >= first[:, None]) & (cols <= last[:, None])
    kept[:, 0] |= ~kept.any(axis=1)
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
        if n_back[i]:
            notes.append(f"removed {int(n_back[i])} points stepping back in the raw order "
                         "(zig-zags)")
        if n_merged[i]:
            notes.append(f"merged {int(n_merged[i])} points closer than {min_spacing_mm} mm")
        if n_spikes[i]:
            notes.append(f"removed {int(n_spikes[i])} spikes (> {spike_mm} mm off their "
                         "neighbours)")
        if flip_z[i]:
            notes.append(_Z_FLIP_NOTE)
        if mirror_y[i]:
            notes.append(_Y_MIRROR_NOTE)
        if trimmed[i]:
            notes.append(f"trimmed {int(size[i]) - (b - a)} points of near-vertical end runs "
                         "(back face)")
        out.append(CleanedProfile(y_mm=y[i, a:b].copy(), z_mm=z[i, a:b].copy(),
                                  n_removed=n - (b - a), notes=tuple(notes)))
    return out
