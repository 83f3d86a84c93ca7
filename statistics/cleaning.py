"""Cleaning and resampling of measured wheel profiles.

A measured profile arrives as raw points ``(y_mm, z_mm)`` in the instrument's order. Before it
can be aligned to its reference (``wearcast.statistics.alignment``) and turned into a wear
curve (seed 001 §3.1) it must be a single-valued, ascending function z(y) in the wheel frame
of docs/conventions.md: y [mm] lateral from the tape circle, negative towards the flange;
z [mm] radius increase over the tape circle, positive towards the flange tip.

``clean_profile`` does, in this order:

1. rejects infinite coordinates, drops points with a NaN coordinate;
2. rejects profiles in metres (lateral extent < 1) and profiles with too few points;
3. orders the points: if the raw order runs mostly one way along y, points lying behind the
   farthest point reached so far (zig-zags near the flange tip, the overhanging field-side
   face, jitter on the back face) are dropped -- or, if that would drop over 20 % of the
   points (a far-forward outlier), only points stepping back from their predecessor; then
   the points are sorted by y (a raw order that is not lateral at all is just sorted);
4. merges points closer than ``min_spacing_mm`` laterally (mean of each lateral bin);
5. removes single-point spikes (normal distance > ``spike_mm`` from their neighbours' chord);
6. detects the orientation: the flange tip is the largest deviation from the tread level away
   from the lateral ends (the ends may carry the back face and the field-side chamfer). A tip
   below the tread means z was given downward (z -> -z); a tip on the positive-y side means
   y was mirrored (y -> -y);
7. trims near-vertical runs at both ends (the back face, |dz/dy| > ``max_end_slope``);
8. rejects a profile whose range misses the flange or the tread.

Every correction is reported in ``CleanedProfile.notes``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Fewest points a usable profile may have after cleaning.
MIN_POINTS = 20
#: Smallest flange height over the tread level [mm] for the flange to count as present
#: (S1002 new: 28 mm; EBO limit Sh >= 26 mm, so 15 mm leaves room for measurement offsets).
MIN_FLANGE_HEIGHT_MM = 15.0
#: Smallest lateral distance [mm] the data must extend from the flange tip towards the field
#: side so that the tread (tape circle at 55 mm from the S1002 tip) is covered.
MIN_TREAD_REACH_MM = 58.0
#: Lateral band [mm] at each end excluded from the orientation detection (back face, chamfer).
_END_BAND_MM = 5.0
#: Back-and-forth removal keeps at least this share of the points (else a local rule is used).
_MIN_KEPT_FRACTION = 0.8


@dataclass(frozen=True)
class CleanedProfile:
    """A measured profile ready for alignment.

    Attributes
    ----------
    y_mm : lateral positions [mm], strictly ascending, wheel frame
    z_mm : heights [mm], positive towards the flange tip
    n_removed : number of raw points dropped or merged away
    notes : human-readable corrections applied (orientation, ordering, removals)
    """

    y_mm: NDArray[np.float64]
    z_mm: NDArray[np.float64]
    n_removed: int
    notes: tuple[str, ...]


def _as_profile_arrays(y_mm: ArrayLike, z_mm: ArrayLike) -> tuple[NDArray, NDArray]:
    y = np.asarray(y_mm, dtype=float).ravel()
    z = np.asarray(z_mm, dtype=float).ravel()
    if y.shape != z.shape:
        raise ValueError(f"y_mm and z_mm differ in length ({y.size} vs {z.size} points)")
    return y, z


def clean_profile(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    min_spacing_mm: float = 0.05,
    max_end_slope: float = 20.0,
    spike_mm: float = 1.0,
) -> CleanedProfile:
    """Clean one measured wheel profile into an ascending, single-valued z(y).

    Parameters
    ----------
    y_mm, z_mm : raw point coordinates [mm] in the instrument's point order, wheel frame
        (y from the tape circle; MiniProf X from the back face maps to y = X - 70)
    min_spacing_mm : points closer than this laterally [mm] are merged (bin means)
    max_end_slope : runs at either end steeper than this |dz/dy| are trimmed (back face);
        S1002's flange back is steeper than 20 only within 0.03 mm of y = -70
    spike_mm : a point whose normal distance from the chord of its two neighbours exceeds
        this [mm] is removed as a spike

    Returns
    -------
    CleanedProfile

    Raises
    ------
    ValueError : too few points, infinite values, a profile in metres, or a lateral range
        that misses the flange or the tread.
    """
    y, z = _as_profile_arrays(y_mm, z_mm)
    n_raw = y.size
    notes: list[str] = []

    finite = np.isfinite(y) & np.isfinite(z)
    if not finite.all():
        if np.isinf(y).any() or np.isinf(z).any():
            raise ValueError("profile has infinite coordinates; give finite values in mm")
        notes.append(f"removed {int(finite.size - finite.sum())} points with NaN coordinates")
        y, z = y[finite], z[finite]
    _require_points(y.size)
    y_min, y_max = float(y.min()), float(y.max())
    extent = y_max - y_min
    if extent < 1.0:
        raise ValueError(
            f"profile's lateral extent is {extent:.4g}: looks like metres; give y_mm and z_mm "
            "in millimetres"
        )

    # --- point order and zig-zags ---
    dy = np.diff(y)
    forward = np.count_nonzero(dy > 0.0) / dy.size
    if max(forward, 1.0 - forward) >= 0.8:
        y_run = y if forward >= 0.5 else -y
        # a point is part of a back-and-forth if it lies behind the farthest point reached so
        # far; if that drops too much (a far-forward outlier), judge each step on its own
        keep = np.empty(y.size, dtype=bool)
        keep[0] = True
        keep[1:] = y_run[1:] >= np.maximum.accumulate(y_run)[:-1]
        if keep.sum() < _MIN_KEPT_FRACTION * y.size:
            keep[1:] = np.diff(y_run) >= 0.0
        n_back = int(y.size - keep.sum())
        if n_back:
            notes.append(f"removed {n_back} points stepping back in the raw order (zig-zags)")
            y, z = y[keep], z[keep]
    else:
        notes.append("raw points were not in lateral order: sorted by y")
    order = np.argsort(y, kind="stable")
    y, z = y[order], z[order]

    # --- duplicates and too-close points: one mean point per lateral bin ---
    bins = np.floor((y - y[0]) / min_spacing_mm).astype(np.int64)
    new_bin = np.empty(bins.size, dtype=bool)  # (np.r_ costs more than the comparison)
    new_bin[0] = True
    np.not_equal(bins[1:], bins[:-1], out=new_bin[1:])
    starts = np.flatnonzero(new_bin)
    if starts.size < y.size:
        counts = np.diff(np.append(starts, y.size))
        y = np.add.reduceat(y, starts) / counts
        z = np.add.reduceat(z, starts) / counts
        notes.append(
            f"merged {int(counts.sum() - starts.size)} points closer than {min_spacing_mm} mm"
        )
    _require_points(y.size)

    # --- single-point spikes ---
    chord_dy = y[2:] - y[:-2]
    chord_dz = z[2:] - z[:-2]
    # normal distance of each point from the chord of its neighbours
    off = np.abs((y[1:-1] - y[:-2]) * chord_dz - (z[1:-1] - z[:-2]) * chord_dy)
    spikes = off > spike_mm * np.hypot(chord_dy, chord_dz)
    if spikes.any():
        keep = np.concatenate(([True], ~spikes, [True]))
        notes.append(f"removed {int(spikes.sum())} spikes (> {spike_mm} mm off their neighbours)")
        y, z = y[keep], z[keep]

    # --- orientation: the largest deviation from the tread level away from the ends ---
    inner = (y > y[0] + _END_BAND_MM) & (y < y[-1] - _END_BAND_MM)
    n_inner = int(inner.sum())
    if n_inner < MIN_POINTS // 2:
        raise ValueError(f"profile's lateral extent {extent:.1f} mm misses the flange or tread")
    yi, zi = y[inner], z[inner]
    level = float(np.partition(zi, n_inner // 2)[n_inner // 2])
    k = int(np.argmax(np.abs(zi - level)))
    if zi[k] < level:
        z = -z
        notes.append("z was given downward (flange tip as minimum): flipped z -> -z")
    if float(yi[k]) > 0.5 * (y[0] + y[-1]):
        y, z = -y[::-1], z[::-1]
        notes.append("y was mirrored (flange on the positive side): flipped y -> -y")

    # --- near-vertical ends (back face) ---
    steep = np.abs(np.diff(z)) > max_end_slope * np.diff(y)
    if steep[0] or steep[-1]:
        first = int(np.argmin(steep)) if not steep.all() else steep.size
        last = steep.size - int(np.argmin(steep[::-1])) if not steep.all() else 0
        n_before = y.size
        y, z = y[first : last + 1], z[first : last + 1]
        notes.append(f"trimmed {n_before - y.size} points of near-vertical end runs (back face)")
    _require_points(y.size)

    # --- coverage ---
    k = int(np.argmax(z))
    y_tip, z_tip = float(y[k]), float(z[k])
    n_field = y.size - k - 1
    tread_level = float(np.partition(z[k + 1 :], n_field // 2)[n_field // 2]) if n_field else z_tip
    if z_tip - tread_level < MIN_FLANGE_HEIGHT_MM:
        raise ValueError(
            "profile's range misses the flange: no flange tip stands "
            f"{MIN_FLANGE_HEIGHT_MM} mm above the tread"
        )
    if float(y[-1]) - y_tip < MIN_TREAD_REACH_MM:
        raise ValueError(
            f"profile's range misses the tread: data end {float(y[-1]) - y_tip:.1f} mm from the "
            f"flange tip, at least {MIN_TREAD_REACH_MM} mm needed"
        )
    return CleanedProfile(y_mm=y, z_mm=z, n_removed=int(n_raw - y.size), notes=tuple(notes))


def _require_points(n: int) -> None:
    if n < MIN_POINTS:
        raise ValueError(f"profile has {n} usable points; at least {MIN_POINTS} are needed")


def resample_profile(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    grid_y_mm: ArrayLike,
    *,
    max_gap_mm: float | None = None,
) -> NDArray[np.float64]:
    """Heights of a profile on a lateral grid by linear interpolation.

    Parameters
    ----------
    y_mm : ascending lateral positions [mm] (e.g. ``CleanedProfile.y_mm``)
    z_mm : heights [mm]
    grid_y_mm : lateral grid [mm]
    max_gap_mm : if given, grid points inside a gap between data points wider than this
        [mm] are NaN too

    Returns
    -------
    z on the grid [mm]; NaN outside the data's lateral range (and inside wide gaps).
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    grid = np.asarray(grid_y_mm, dtype=float)
    out = np.interp(grid, y, z)
    outside = (grid < y[0]) | (grid > y[-1])
    if max_gap_mm is not None and y.size > 1:
        right = np.clip(np.searchsorted(y, grid, side="left"), 1, y.size - 1)
        outside |= (y[right] - y[right - 1]) > max_gap_mm
    out[outside] = np.nan
    return out
