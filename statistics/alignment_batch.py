"""The rigid alignment of :func:`.alignment.align_to_reference`, for many profiles at once.

Seed 000 §IV.A eq. (2) solved by Gauss–Newton with Huber reweighting. The fit's rules are
written once, in :mod:`.alignment`, as functions of one profile's points or of padded rows
(``fit_mask``, ``rotate``, ``on_reference``, ``residuals_and_jacobian``, ``huber_weights``,
``solve3``, ``converged``, ``normal_distances``); ``align_to_reference`` calls them on its
profile, this module once per step on a chunk of profiles held as padded rows
(:mod:`.ragged`), so numpy's per-call cost is paid once per chunk instead of once per
profile. What is this module's own is the bookkeeping: the rows' padding and compaction, the
reference looked up by index (:mod:`.table_interp`, the numbers of ``np.interp``), each
profile's own iteration count (a converged row is frozen while the others go on) and the
normal equations summed row by row. The results equal the per-profile ones to floating-point
round-off (the normal equations' sums are taken in another order); a profile the batch cannot
fit (too few points, a singular system) gets ``None``, and the caller runs the per-profile
function on it (which raises its ``ValueError``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import (
    FIT_WINDOWS_MM,
    AlignedProfile,
    ReferenceHeight,
    converged,
    fit_mask,
    huber_weights,
    normal_distances,
    on_reference,
    reference_table,
    residuals_and_jacobian,
    rotate,
    solve3,
)
from wearcast.statistics.ragged import compact, pack
from wearcast.statistics.table_interp import reference_even_table


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

    # the fit points (alignment.fit_mask), moved to the left of each row
    fit, use_windows = fit_mask(y_all, y_lo, y_hi, windows_mm, valid)
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
        yr, zr = rotate(yf, zf, c, s)
        yp = yr + dy[rows][:, None]
        need = (check[rows] | (np.where(v, yp, np.inf).min(axis=1) <= y_lo)
                | (np.where(v, yp, -np.inf).max(axis=1) >= y_hi))
        at = even.locate(yp)
        if need.any():
            # keep points inside the reference's range and off its near-vertical parts
            slope = even.interp(yp[need], at[need], 1)
            good = v[need] & on_reference(yp[need], slope, y_lo, y_hi)
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
        residual, j0, j1, j2 = residuals_and_jacobian(yr, zr, dz[rows][:, None],
                                                      even.interp(yp, at, 0),
                                                      even.interp(yp, at, 1))
        if robust and iteration >= 1:
            w = huber_weights(np.abs(residual), v)
        else:
            w = v.astype(float)
        w0, w1, w2 = j0 * w, j1 * w, j2 * w
        a01, a02, a12 = (w0 * j1).sum(axis=1), (w0 * j2).sum(axis=1), (w1 * j2).sum(axis=1)
        x0, x1, x2, regular = solve3(
            (w0 * j0).sum(axis=1), a01, a02, a01, (w1 * j1).sum(axis=1), a12, a02, a12,
            (w2 * j2).sum(axis=1), -(w0 * residual).sum(axis=1), -(w1 * residual).sum(axis=1),
            -(w2 * residual).sum(axis=1))
        singular = ~regular
        if singular.any():
            failed[rows[singular]] = True
            active[rows[singular]] = False
        ok = ~singular
        dy[rows[ok]] += x0[ok]
        dz[rows[ok]] += x1[ok]
        theta[rows[ok]] += x2[ok]
        if iteration >= 2:
            done = ok & converged(x0, x1, x2, tolerance)
            active[rows[done]] = False

    c_all = np.cos(theta)[:, None]
    s_all = np.sin(theta)[:, None]
    y_al, z_al = rotate(y_all, z_all, c_all, s_all)
    y_al, z_al = y_al + dy[:, None], z_al + dz[:, None]
    # final residual at the solution, over the points the fit kept
    yr, zr = rotate(yf_all, zf_all, c_all, s_all)
    yp = yr + dy[:, None]
    at = even.locate(yp)
    r, good = normal_distances(zr, dz[:, None], even.interp(yp, at, 0, left=np.nan, right=np.nan),
                               even.interp(yp, at, 1))
    good &= used
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
