"""The rigid alignment of :func:`.alignment.align_to_reference`, for many profiles at once.

Seed 000 §IV.A eq. (2) solved by Gauss–Newton with Huber reweighting, exactly as
:func:`wearcast.statistics.alignment.align_to_reference` does it for one profile (same fit
windows, same point selection, same weights, same 3x3 solve, same stopping rule), but each
step runs once over a chunk of profiles held as padded rows (:mod:`.ragged`): numpy's
per-call cost is paid once per chunk instead of once per profile. Each profile keeps its own
iteration count (a converged row is frozen while the others go on). The results equal the
per-profile ones to floating-point round-off (sums are taken in another order); a profile
the batch cannot fit (too few points, a singular system) gets ``None``, and the caller runs
the per-profile function on it (which raises its ``ValueError``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import (
    _MAX_SLOPE,
    FIT_WINDOWS_MM,
    HUBER_C,
    MAD_TO_SIGMA,
    MIN_SCALE_MM,
    MIN_WINDOW_POINTS,
    AlignedProfile,
    ReferenceHeight,
    reference_table,
)
from wearcast.statistics.ragged import compact, pack, upper_median
from wearcast.statistics.table_interp import reference_even_table


def _solve3_rows(a00: NDArray, a01: NDArray, a02: NDArray, a11: NDArray, a12: NDArray,
                 a22: NDArray, b0: NDArray, b1: NDArray, b2: NDArray
                 ) -> tuple[NDArray, NDArray, NDArray, NDArray[np.bool_]]:
    """Cramer's rule of ``alignment._solve3`` for symmetric 3x3 systems, row by row;
    also the rows that are singular (by the same test)."""
    a10, a20, a21 = a01, a02, a12
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    scale = np.abs(a00 * a11 * a22) + 1e-300
    singular = ~np.isfinite(det) | (np.abs(det) < 1e-12 * scale)
    det = np.where(singular, 1.0, det)
    x0 = (b0 * c00 + a01 * (b2 * a12 - b1 * a22) + a02 * (b1 * a21 - b2 * a11)) / det
    x1 = (a00 * (b1 * a22 - b2 * a12) + b0 * c01 + a02 * (b2 * a10 - b1 * a20)) / det
    x2 = (a00 * (b2 * a11 - b1 * a21) + a01 * (b1 * a20 - b2 * a10) + b0 * c02) / det
    return x0, x1, x2, singular


def align_to_reference_batch(
    profiles: Sequence[tuple[NDArray, NDArray]],
    reference_height: ReferenceHeight = s1002_height_mm,
    *,
    windows_mm: tuple[tuple[float, float], ...] = FIT_WINDOWS_MM,
    max_iterations: int = 10,
    tolerance: float = 1e-3,
    robust: bool = True,
) -> list[AlignedProfile | None]:
    """:func:`wearcast.statistics.alignment.align_to_reference` of each cleaned profile.

    Parameters
    ----------
    profiles : (y_mm, z_mm) per profile [mm], ascending y, wheel frame
    reference_height, windows_mm, max_iterations, tolerance, robust : as for
        ``align_to_reference``

    Returns
    -------
    One AlignedProfile per profile, in order; ``None`` where the per-profile function must
    decide (it raises ``ValueError`` there: no overlap with the reference, singular fit).
    """
    m = len(profiles)
    if m == 0:
        return []
    if not windows_mm:
        return [None] * m
    table = reference_table(reference_height)
    ty = table.y_mm
    even = reference_even_table(reference_height)  # np.interp on the table, by index
    y_lo, y_hi = float(ty[0]), float(ty[-1])
    y_all, valid = pack([np.asarray(y, dtype=float) for y, _ in profiles], np.nan)
    z_all, _ = pack([np.asarray(z, dtype=float) for _, z in profiles], np.nan)

    # the fit points of alignment._fit_mask, moved to the left of each row
    inside = valid & (y_all >= y_lo) & (y_all <= y_hi)
    in_window = [valid & (y_all >= lo) & (y_all <= hi) for lo, hi in windows_mm]
    use_windows = np.logical_and.reduce([w.sum(axis=1) >= MIN_WINDOW_POINTS for w in in_window])
    fit = np.where(use_windows[:, None], np.logical_or.reduce(in_window) & inside, inside)
    (yf_all, zf_all), used = compact(fit, y_all, z_all)

    failed = used.sum(axis=1) < 3
    dy, dz, theta = np.zeros(m), np.zeros(m), np.zeros(m)
    active = ~failed
    check = np.ones(m, dtype=bool)
    for iteration in range(max_iterations):
        rows = np.flatnonzero(active)
        if rows.size == 0:
            break
        c = np.cos(theta[rows])[:, None]
        s = np.sin(theta[rows])[:, None]
        yf, zf, v = yf_all[rows], zf_all[rows], used[rows]
        yr = c * yf - s * zf
        zr = s * yf + c * zf
        yp = yr + dy[rows][:, None]
        need = (check[rows] | (np.where(v, yp, np.inf).min(axis=1) <= y_lo)
                | (np.where(v, yp, -np.inf).max(axis=1) >= y_hi))
        at = even.locate(yp)
        if need.any():
            # keep points inside the reference's range and off its near-vertical parts
            slope = even.interp(yp[need], at[need], 1)
            good = v[need] & (yp[need] > y_lo) & (yp[need] < y_hi) & (np.abs(slope) < _MAX_SLOPE)
            v[need] = good
            used[rows[need]] = good
            check[rows[need]] = False
            lost = np.zeros(rows.size, dtype=bool)
            lost[need] = good.sum(axis=1) < 3
            if lost.any():
                failed[rows[lost]] = True
                active[rows[lost]] = False
                keep = ~lost
                rows, c, s, yr, zr, yp, v, at = (rows[keep], c[keep], s[keep], yr[keep],
                                                 zr[keep], yp[keep], v[keep], at[keep])
                if rows.size == 0:
                    break
        z_ref = even.interp(yp, at, 0)
        slope = even.interp(yp, at, 1)
        norm = 1.0 / np.sqrt(1.0 + slope * slope)
        residual = (zr + dz[rows][:, None] - z_ref) * norm
        j0, j1, j2 = -slope * norm, norm, (yr + slope * zr) * norm
        if robust and iteration >= 1:
            abs_r = np.abs(residual)
            cutoff = HUBER_C * np.maximum(MAD_TO_SIGMA * upper_median(abs_r, v), MIN_SCALE_MM)
            w = np.where(v, np.minimum(1.0, cutoff[:, None] / np.maximum(abs_r, 1e-300)), 0.0)
        else:
            w = v.astype(float)
        w0, w1, w2 = j0 * w, j1 * w, j2 * w
        x0, x1, x2, singular = _solve3_rows(
            (w0 * j0).sum(axis=1), (w0 * j1).sum(axis=1), (w0 * j2).sum(axis=1),
            (w1 * j1).sum(axis=1), (w1 * j2).sum(axis=1), (w2 * j2).sum(axis=1),
            -(w0 * residual).sum(axis=1), -(w1 * residual).sum(axis=1),
            -(w2 * residual).sum(axis=1))
        if singular.any():
            failed[rows[singular]] = True
            active[rows[singular]] = False
        ok = ~singular
        dy[rows[ok]] += x0[ok]
        dz[rows[ok]] += x1[ok]
        theta[rows[ok]] += x2[ok]
        if iteration >= 2:
            done = ok & (np.abs(x0) + np.abs(x1) + 100.0 * np.abs(x2) < tolerance)
            active[rows[done]] = False

    c_all = np.cos(theta)[:, None]
    s_all = np.sin(theta)[:, None]
    y_al = c_all * y_all - s_all * z_all + dy[:, None]
    z_al = s_all * y_all + c_all * z_all + dz[:, None]
    # final residual at the solution, over the points the fit kept
    yp = c_all * yf_all - s_all * zf_all + dy[:, None]
    at = even.locate(yp)
    z_ref = even.interp(yp, at, 0, left=np.nan, right=np.nan)
    slope = even.interp(yp, at, 1)
    good = used & np.isfinite(z_ref) & (np.abs(slope) < _MAX_SLOPE)
    r = (s_all * yf_all + c_all * zf_all + dz[:, None] - z_ref) / np.sqrt(1.0 + slope ** 2)
    n_good = good.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.where(good, r * r, 0.0).sum(axis=1) / n_good)
    lengths = valid.sum(axis=1).tolist()
    out: list[AlignedProfile | None] = []
    for i, n in enumerate(lengths):
        if failed[i]:
            out.append(None)
            continue
        yi, zi = y_al[i, :n].copy(), z_al[i, :n].copy()
        if theta[i] != 0.0 and np.any(np.diff(yi) <= 0.0):
            order = np.argsort(yi, kind="stable")
            yi, zi = yi[order], zi[order]
        out.append(AlignedProfile(
            y_mm=yi, z_mm=zi, lateral_shift_mm=float(dy[i]), vertical_shift_mm=float(dz[i]),
            rotation_rad=float(theta[i]),
            rms_residual_mm=float(rms[i]) if n_good[i] else float("nan"),
            n_used=int(n_good[i]), used_windows=bool(use_windows[i])))
    return out
