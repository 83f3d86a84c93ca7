"""The curving model's contact table: the wheel-rail gap of one wheel over the wheelset's shift.

The gap is the vertical distance between the wheel and its rail at each wheel point, taken from
the rigid multi-point geometry (``contact.geometry``, roll solved) at each shift and smoothed at
the scale of a contact patch; contact candidates are its local minima (``ContactTable.candidates``,
compiled in ``contact_candidates_kernel``), with Hertz constants from the smoothed curvature.
Used by ``curving`` (the bogie's equilibrium) and the wear loop (a table per worn profile).
Frames and signs: docs/conventions.md and ``contact.geometry``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics import gap_smoothing as gs
from wearcast.physics.contact.geometry import (
    WheelsetTrack,
    rigid_wheel_gap,
    rigid_wheel_gap_beyond_rail,
)
from wearcast.physics.contact.hertz import hertz_contact
from wearcast.physics.contact.track_profiles import wheel_curve_from_height, wheelset_track
from wearcast.physics.contact_candidates_kernel import N_SLOTS, candidate_slots
from wearcast.physics.gap_smoothing import (
    check_gap_smoothing,
    smooth_gap,
    smooth_like_gap,
    smoothstep,
)
from wearcast.physics.profiles.measured_wheel import MeasuredWheel
from wearcast.physics.profiles.rails import RailShape, rail_profile
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicles import BogieVehicle
from wearcast.physics.vocabulary import DIRECTIONS

#: Track gauge measured 14 mm below the rail top [mm] (standard gauge).
GAUGE_MM = 1435.0
#: Lateral distance of the tape circles from the wheelset centre [mm] (flange back 1360 mm).
TAPE_CIRCLE_HALF_SPACING_MM = 750.0
#: Bounds of the lateral relative curvature B used for Hertz [1/mm] (relative radius 1 m
#: ... 5 mm).
MIN_CURVATURE_B_PER_MM = 5e-4
MAX_CURVATURE_B_PER_MM = 0.1
#: Rise of the gap between two minima above which they are separate patches [mm].
SEPARATION_MM = 0.1
#: Rise over which a newly formed gap minimum matures into a contact candidate [mm].
PROMINENCE_MM = 0.005
#: Gap scale of the soft minimum that shares a merged patch between two minima [mm].
SHARE_GAP_MM = 0.01
#: Gap assigned to a slot without a contact candidate [mm]; also the rank penalty of an
#: immature minimum when a gap row has more minima than slots (``contact_candidates_kernel``).
_NO_CONTACT_GAP_MM = 50.0
#: Key difference over which a kept minimum fades out as the best minimum left without a slot
#: approaches its rank [mm] (``contact_candidates_kernel``: the residual stays continuous when
#: a gap row has more minima than ``N_SLOTS``); the scale of the soft sharing, SHARE_GAP_MM.
SLOT_FADE_MM = 0.01

#: Wheel y [mm] below which the gap is smoothed at the flange scale, and above which at the
#: tread scale (``build_contact_table``), blended linearly between.
FLANK_SMOOTHING_Y_MM = (-25.0, -15.0)
#: Standard deviations of the gap's Gaussian smoothing on the tread and on the flange [mm]
#: (``build_contact_table``).
GAP_SMOOTHING_MM = (2.0, 2.0)


@dataclass(frozen=True)
class ContactTable:
    """Vertical gap between one wheel and its rail, tabulated over the wheelset's shift.

    ``shift_mm`` (n_s,) is the wheelset's lateral displacement towards THIS wheel's field side
    (the left wheel's +y, the right wheel's -y; both wheels alike by mirror symmetry).
    ``gap_mm`` (n_s, n_y) is the vertical distance between wheel and rail surfaces at the wheel
    points ``wheel_y_mm`` (n_y,) (wheel frame of docs/conventions.md), the wheelset at its nominal
    height
    and without roll, smoothed with a Gaussian of standard deviation ``smoothing_mm`` (n_y,)
    (the scale of a contact patch, ``GAP_SMOOTHING_MM``; S1002 on a rail crown
    is nearly conformal and the raw gap has shallow double minima);
    ``gap2_per_mm`` is its second derivative, the relative lateral curvature at the patch
    scale (Gaussian smoothing keeps the curvature of a parabola and raises its minimum by
    g'' sigma^2 / 2, which is subtracted again).

    Contact candidates are the local minima of the gap row interpolated linearly in shift
    (:meth:`candidates`). Keeping the whole gap function instead of contact points keeps the
    candidates continuous in the shift through the tread-flange transition and two-point
    contact; minima separated by less than ``SEPARATION_MM`` of rise share one patch.

    ``rigid_rise_mm`` (n_s,): how far the wheel rises at rigid contact relative to the centred
    wheelset [mm] (minimum of the unsmoothed gap), for the wheelset roll.
    Wheel columns on ``wheel_y_mm``: height z [mm], slope dz/dy, and ``contact_slope``
    (n_s, n_y) the slope averaged like the gap at each shift (the gap's Gaussians, with the
    masked smoothing's weights of the points with rail below,
    ``gap_smoothing.smooth_like_gap``), which gives each candidate its contact angle:
    with S = G*(m g) / G*(m) the smoothed gap (m the rail's coverage, 1 for the ``gaussian``
    method; g = z_rail(y + shift) - z_wheel(y) up to sign, m moving with the rail), at a
    minimum y_c of S (dS/dy = 0) the envelope theorem gives the rate at which the gap closes
    with the shift, d S(y_c) / d shift = dS/d shift - dS/dy = G*(m z_wheel') / G*(m): the
    wheel's slope averaged with the gap's own weights. A normal force along that angle is
    the gradient of a potential of the approach (d - S(y_c)), the residual's contact forces
    are conservative, and the candidate's force direction agrees with its gap (the slope at
    the point, or averaged with the plain Gaussian where the rail does not cover the kernel,
    at the gauge corner, does not; helper flange11). On the S1002 flange root the contact
    angle rises by 4-6 deg per mm, convexly, so the mean is steeper than the point value: the
    point slope put the loaded patch 0.3-0.9 mm up the flank of the one contact pipeline's
    pressure centre at the same force angle, the mean 0.02-0.50 mm (the Manchester trailer
    at 150-600 m, ``benchmarks/curving_flange_table_vs_rigid.py`` block 3). Near the gauge
    corner the mean depends on the shift (at wheel y -36 mm: 44-53 deg over shifts 5-10 mm,
    the point slope 49 deg); it stays below 66 deg where the point slope reaches 70 deg.
    ``rail_offset_mm`` maps
    wheel y to rail y (y_rail = y_wheel + offset + shift). Hertz constants under 1 N for
    log(B/A) = ``hertz_log_ratio`` and A = 1/mm: ``hertz_approach1``, ``hertz_a1``,
    ``hertz_b1`` [mm]. ``track``: the wheelset on its track the table was built from (the
    contact pipeline evaluates the curving's contacts on it, ``curving_contacts``).

    ``right``: the right wheel's table when the two rails differ (a high and a low rail of
    their own, ``build_contact_table(..., rail_right=...)``): the left-wheel table of the
    mirrored track (rails exchanged), so that its shift is also towards ITS wheel's field
    side; None when both rails are one profile (the right wheel is this table's mirror
    image). :meth:`side` gives each wheel's table.
    """

    shift_mm: NDArray[np.float64]
    wheel_y_mm: NDArray[np.float64]
    gap_mm: NDArray[np.float64]
    gap2_per_mm: NDArray[np.float64]
    wheel_z_mm: NDArray[np.float64]
    wheel_slope: NDArray[np.float64]
    contact_slope: NDArray[np.float64]
    rigid_rise_mm: NDArray[np.float64]
    rail_offset_mm: float
    nominal_radius_m: float
    smoothing_mm: NDArray[np.float64]
    hertz_log_ratio: NDArray[np.float64]
    hertz_approach1: NDArray[np.float64]
    hertz_a1: NDArray[np.float64]
    hertz_b1: NDArray[np.float64]
    track: WheelsetTrack
    right: ContactTable | None = None

    def side(self, index: int) -> ContactTable:
        """The table of wheel ``index`` (0 left, 1 right, ``vocabulary.SIDES`` order): this
        one for the left wheel, and for the right wheel ``right`` when the rails differ, else
        this one (mirror symmetry)."""
        if index not in (0, 1):
            raise ValueError(f"side index must be 0 (left) or 1 (right), got {index!r}")
        return self if index == 0 or self.right is None else self.right

    def mirrored(self) -> ContactTable:
        """The table of the mirrored track (left and right rails exchanged): the right
        wheel's table becomes the left one's; itself when both rails are one profile."""
        if self.right is None:
            return self
        return replace(self.right, right=replace(self, right=None))

    def rigid_rise(self, shift_mm: ArrayLike) -> NDArray[np.float64]:
        """Rise of the wheel at rigid contact for a shift towards its field side [mm]."""
        return np.interp(np.asarray(shift_mm, dtype=float), self.shift_mm, self.rigid_rise_mm)

    def candidates(self, shift_mm: ArrayLike, n_slots: int = N_SLOTS) -> dict[str, NDArray]:
        """Up to ``n_slots`` contact candidates per wheel at arbitrary shifts.

        Returns arrays of shape shift.shape + (n_slots,), slot 0 the field-most candidate:
        ``gap_mm`` above the deepest minimum (a missing candidate gets a large gap),
        ``weight`` in [0, 1] (1 for a separate patch, see ``_candidate_slots_numpy``),
        ``angle_rad`` contact angle (> 0 pushes the wheel towards the track centre),
        ``wheel_y_mm``, ``rail_y_mm``, ``lateral_mm`` (distance from the track centre line),
        ``radius_m`` rolling radius, ``curv_a``, ``curv_b`` [1/mm], ``approach1_mm``,
        ``a1_mm``, ``b1_mm`` Hertz constants under 1 N. The slots come from the compiled kernel
        (``contact_candidates_kernel``, whose docstring states which minima get a slot when
        there are more than ``n_slots``); ``_candidate_slots_numpy`` is its reference.
        """
        s = np.asarray(shift_mm, dtype=float)
        flat = np.ascontiguousarray(s.reshape(-1))
        slots = candidate_slots(self.gap_mm, self.gap2_per_mm, self.smoothing_mm,
                                float(self.shift_mm[0]),
                                float(self.shift_mm[1] - self.shift_mm[0]), self.wheel_y_mm,
                                flat, n_slots, PROMINENCE_MM, SEPARATION_MM, SHARE_GAP_MM,
                                _NO_CONTACT_GAP_MM, SLOT_FADE_MM)
        yc, gap, g2, weight = (v.reshape(s.shape + (n_slots,)) for v in slots)
        return self._candidate_columns(s, yc, gap, g2, weight)

    def _shift_rows(self, shift_mm: ArrayLike) -> tuple[NDArray, NDArray]:
        """The table row k below each shift and the weight w of row k + 1 (linear in the
        shift, clamped to the grid), shift.shape each."""
        s = np.asarray(shift_mm, dtype=float)
        grid = self.shift_mm
        pos = np.clip((s - grid[0]) / (grid[1] - grid[0]), 0.0, len(grid) - 1.000001)
        k = np.floor(pos).astype(int)
        return k, pos - k

    def contact_slope_at(self, shift_mm: ArrayLike, wheel_y_mm: ArrayLike) -> NDArray:
        """``contact_slope`` at wheel points ``wheel_y_mm`` (shift.shape + (k,)) of each shift:
        linear in y on the two table rows around the shift (clamped like the candidates'
        gap rows, :meth:`candidates`), then linear in the shift between them."""
        yc = np.asarray(wheel_y_mm, dtype=float)
        k, w = self._shift_rows(shift_mm)
        k, w = k[..., None], w[..., None]
        xp = self.wheel_y_mm
        j = np.clip(np.searchsorted(xp, yc, side="right") - 1, 0, xp.size - 2)

        def on_row(row: NDArray) -> NDArray:
            # np.interp's arithmetic (slope form from the left point, clamped ends)
            f0, f1 = self.contact_slope[row, j], self.contact_slope[row, j + 1]
            value = (f1 - f0) / (xp[j + 1] - xp[j]) * (yc - xp[j]) + f0
            value = np.where(yc >= xp[-1], self.contact_slope[row, -1], value)
            return np.where(yc < xp[0], self.contact_slope[row, 0], value)

        return (1.0 - w) * on_row(k) + w * on_row(k + 1)

    def _candidate_slots_numpy(self, shift_mm: ArrayLike, n_slots: int = N_SLOTS
                               ) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Reference implementation of the candidate slots (wheel y, gap, g'', weight), each
        shift.shape + (n_slots,): the numpy form of ``contact_candidates_kernel`` (its
        docstring states the selection rule)."""
        k, w = self._shift_rows(shift_mm)
        w = w[..., None]
        g = (1.0 - w) * self.gap_mm[k] + w * self.gap_mm[k + 1]  # (..., n_y)
        n_y = g.shape[-1]
        cols = np.arange(n_y)
        inner = g[..., 1:-1]
        is_min = (inner < g[..., :-2]) & (inner <= g[..., 2:])
        dy = self.wheel_y_mm[1] - self.wheel_y_mm[0]
        g2_rows = (1.0 - w) * self.gap2_per_mm[k] + w * self.gap2_per_mm[k + 1]

        # second differences of the row (the ends take their neighbour's)
        second = np.empty_like(g)
        second[..., 1:-1] = g[..., :-2] - 2.0 * inner + g[..., 2:]

        def refine(i: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
            """Parabola refinement at interior indices i: wheel y, g'', corrected gap, g
            (``contact_candidates_kernel._refine``: the curvature of the vertex's gap
            interpolated like g'', so the gap stays continuous where the grid minimum moves)."""
            gm = np.take_along_axis(g, i - 1, axis=-1)
            g0 = np.take_along_axis(g, i, axis=-1)
            gp = np.take_along_axis(g, i + 1, axis=-1)
            den = gm - 2.0 * g0 + gp
            frac = np.clip(np.where(den > 0, 0.5 * (gm - gp) / np.where(den > 0, den, 1.0),
                                    0.0), -0.5, 0.5)
            yc = self.wheel_y_mm[i] + frac * dy
            # second derivative at the refined position (linear in y between grid points)
            j = np.where(frac >= 0.0, i + 1, i - 1)
            f = np.abs(frac)
            g2 = ((1.0 - f) * np.take_along_axis(g2_rows, i, axis=-1)
                  + f * np.take_along_axis(g2_rows, j, axis=-1))
            den_j = np.where((j > 0) & (j < n_y - 1),
                             np.take_along_axis(second, np.clip(j, 1, n_y - 2), axis=-1), den)
            den_eff = (1.0 - f) * den + f * den_j
            gc = g0 - 0.5 * den_eff * frac * frac - 0.5 * g2 * self.smoothing_mm[i] ** 2
            return yc, g2, gc, g0

        # maturity of every point as a minimum: m = ramp(prominence / PROMINENCE_MM), its rise
        # above the lower of its two adjacent maxima of the gap (0 at birth and death)
        is_max = np.zeros(g.shape, dtype=bool)
        is_max[..., 1:-1] = (inner >= g[..., :-2]) & (inner > g[..., 2:])
        is_max[..., 0] = True
        is_max[..., -1] = True
        left_max = np.maximum.accumulate(np.where(is_max, cols, 0), axis=-1)
        right_max = np.flip(np.minimum.accumulate(np.flip(np.where(is_max, cols, n_y - 1),
                                                          axis=-1), axis=-1), axis=-1)
        rise = (np.minimum(np.take_along_axis(g, left_max, axis=-1),
                           np.take_along_axis(g, right_max, axis=-1)) - g)[..., 1:-1]
        maturity_all = smoothstep(rise / PROMINENCE_MM)
        # the gaps' origin: the deepest refined minimum of the whole row
        interior = np.broadcast_to(cols[1:-1], inner.shape)
        gc_all = refine(interior)[2]
        best = np.min(np.where(is_min, gc_all, np.inf), axis=-1, keepdims=True)
        # the n_slots + 1 lowest keys g + (1 - maturity) no-contact gap, ties to the lower
        # index (repeated argmin); the last is the best minimum left without a slot
        key_all = np.where(is_min, inner + (1.0 - maturity_all) * _NO_CONTACT_GAP_MM, np.inf)
        score = key_all.copy()
        picks, keys = [], []
        for _ in range(n_slots + 1):
            j = np.argmin(score, axis=-1)[..., None]
            picks.append(j)
            keys.append(np.take_along_axis(score, j, axis=-1))  # inf once the minima run out
            np.put_along_axis(score, j, np.inf, axis=-1)
        idx = np.concatenate(picks[:n_slots], axis=-1)
        key = np.concatenate(keys[:n_slots], axis=-1)
        key_excl = keys[n_slots]
        found = np.isfinite(key)
        # a missing candidate takes the first interior point's columns (finite, unused)
        i = np.where(found, idx + 1, 1)
        yc, g2, gc, g0 = refine(i)
        gap = np.where(found, gc - best, _NO_CONTACT_GAP_MM)
        # weights (continuity of the forces when minima are born, die or exchange their order on
        # a flat gap): each candidate k has a maturity m_k (above), faded by its rank
        # f_k = ramp((key_excl - key_k) / SLOT_FADE_MM) (1 when every minimum has a slot;
        # 0 where k and the best excluded minimum exchange their slot); candidates j whose gap
        # between them rises less than SEPARATION_MM above the shallower one belong to one
        # conformal patch (c_kj -> 1) and share it by a soft minimum of their gaps
        # (temperature SHARE_GAP_MM):
        #     w_k = m_k f_k / (eps + m_k f_k + sum_j c_kj m_j f_j exp(-(g_j - g_k) / SHARE_GAP_MM)).
        # An isolated mature candidate with its slot secure has weight 1.
        fade = np.where(np.isfinite(key_excl),
                        smoothstep((key_excl - np.where(found, key, 0.0)) / SLOT_FADE_MM), 1.0)
        maturity = np.where(found, np.take_along_axis(maturity_all, np.where(found, idx, 0),
                                                      axis=-1) * fade, 0.0)
        pairs = [(p, q) for p in range(n_slots) for q in range(p + 1, n_slots)]
        merged = np.zeros(g.shape[:-1] + (n_slots, n_slots))
        if pairs:
            ip = i[..., [p for p, _ in pairs]]
            iq = i[..., [q for _, q in pairs]]
            lo = np.minimum(ip, iq)
            hi = np.maximum(ip, iq)
            between = (cols >= lo[..., None]) & (cols <= hi[..., None])  # (..., pairs, n_y)
            barrier_pairs = np.max(np.where(between, g[..., None, :], -np.inf), axis=-1)
            g0p = g0[..., [p for p, _ in pairs]]
            g0q = g0[..., [q for _, q in pairs]]
            merged_pairs = 1.0 - smoothstep((barrier_pairs - np.maximum(g0p, g0q))
                                             / SEPARATION_MM)
            for m, (p, q) in enumerate(pairs):
                merged[..., p, q] = merged_pairs[..., m]
                merged[..., q, p] = merged_pairs[..., m]
        rel = np.exp(-np.clip(gap[..., None, :] - gap[..., :, None], -50 * SHARE_GAP_MM,
                              None) / SHARE_GAP_MM)  # [k, j]: exp(-(g_j - g_k)/tau)
        others = np.sum(merged * maturity[..., None, :] * rel, axis=-1)
        weight = np.where(found, maturity / (1e-9 + maturity + others), 0.0)
        # order slots field side first
        order = np.argsort(-np.where(found, yc, -np.inf), axis=-1, kind="stable")
        yc = np.take_along_axis(yc, order, axis=-1)
        gap = np.take_along_axis(gap, order, axis=-1)
        g2 = np.take_along_axis(g2, order, axis=-1)
        weight = np.take_along_axis(weight, order, axis=-1)
        return yc, gap, g2, weight

    def _candidate_columns(self, s: NDArray, yc: NDArray, gap: NDArray, g2: NDArray,
                           weight: NDArray) -> dict[str, NDArray]:
        """The candidate columns of ``candidates`` from the slots."""
        wz = np.interp(yc, self.wheel_y_mm, self.wheel_z_mm)
        slope = self.contact_slope_at(s, yc)
        rail_y = yc + self.rail_offset_mm + s[..., None]
        angle = np.arctan(-slope)
        cos = np.cos(angle)
        radius = self.nominal_radius_m + wz / 1000.0
        curv_a = cos / (2.0 * radius * 1000.0)
        # the smoothed gap's curvature, bounded below (nearly conformal patches cannot grow
        # beyond the profile features; Hertz would make them arbitrarily stiff) and above by
        # the sharpest real pair (S1002 flange tip R12 on a gauge corner R13: B = 0.08/mm)
        curv_b = np.clip(0.5 * g2 * cos**3, MIN_CURVATURE_B_PER_MM, MAX_CURVATURE_B_PER_MM)
        lr = np.clip(np.log(curv_b / curv_a), self.hertz_log_ratio[0], self.hertz_log_ratio[-1])
        scale = np.cbrt(curv_a)
        return {
            "gap_mm": gap, "weight": weight, "angle_rad": angle, "wheel_y_mm": yc,
            "rail_y_mm": rail_y,
            "lateral_mm": TAPE_CIRCLE_HALF_SPACING_MM + s[..., None] + yc, "radius_m": radius,
            "curv_a": curv_a, "curv_b": curv_b,
            "approach1_mm": np.interp(lr, self.hertz_log_ratio, self.hertz_approach1) * scale,
            "a1_mm": np.interp(lr, self.hertz_log_ratio, self.hertz_a1) / scale,
            "b1_mm": np.interp(lr, self.hertz_log_ratio, self.hertz_b1) / scale,
        }


def conical_wheel(conicity: float) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """A conical wheel z(y) = -conicity * y (wheel frame, no flange) for linear-theory tests.

    Parameters
    ----------
    conicity : cone slope lambda [-]
    """
    def height_mm(y_mm: NDArray[np.float64]) -> NDArray[np.float64]:
        return -conicity * np.asarray(y_mm, dtype=float)
    return height_mm


def rail_envelope(rail: str | RailShape, inclination: float) -> tuple[NDArray, NDArray, float]:
    """Upper envelope z(y) of the inclined rail (top at 0) and the distance of the rail-frame
    origin from the track centre [mm] that puts the gauge point (14 mm below the top, innermost)
    at GAUGE_MM / 2."""
    y, z = rail_profile(rail, step_mm=0.05, inclination=inclination)
    keep = np.concatenate([[True], y[1:] > np.maximum.accumulate(y)[:-1]])
    y, z = y[keep], z[keep]
    z = z - np.max(z)
    gauge_side = y < y[np.argmax(z)]
    yg, zg = y[gauge_side], z[gauge_side]
    order = np.argsort(zg)
    y_gauge = float(np.interp(-14.0, zg[order], yg[order]))
    return y, z, GAUGE_MM / 2.0 - y_gauge


def _interp_rows(x: NDArray, xp: NDArray, fp_rows: NDArray, outside: float) -> NDArray:
    """``np.stack([np.interp(x, xp, row, left=outside, right=outside) for row in fp_rows])``
    in one pass over the rows, with np.interp's arithmetic (the value at an exact grid point,
    slope (fp[j+1] - fp[j]) / (xp[j+1] - xp[j]) times (x - xp[j]) plus fp[j] between; finite
    fp_rows)."""
    n = xp.size
    j = np.searchsorted(xp, x, side="right") - 1  # xp[j] <= x < xp[j+1]
    below, above = j < 0, x > xp[-1]
    jc = np.clip(j, 0, n - 2)
    exact = (j >= 0) & (j <= n - 1) & (xp[np.clip(j, 0, n - 1)] == x)
    f0, f1 = fp_rows[:, jc], fp_rows[:, jc + 1]
    slope = (f1 - f0) / (xp[jc + 1] - xp[jc])
    out = slope * (x - xp[jc]) + f0
    out = np.where(exact, fp_rows[:, np.clip(j, 0, n - 1)], out)
    return np.where(below | above, outside, out)


@lru_cache(maxsize=1)
def _hertz_unit_table() -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Hertz approach and semi-axes under 1 N for A = 1/mm over log(B/A) (``contact.hertz``);
    other A follow by scaling (a ~ A^(-1/3), approach ~ A^(1/3))."""
    log_ratio = np.linspace(np.log(1e-4), np.log(1e4), 801)
    patch = hertz_contact(1.0, 1.0, np.exp(log_ratio))
    return log_ratio, patch.approach_mm, patch.a_mm, patch.b_mm


def build_contact_table(wheel_height_mm: Callable[[NDArray[np.float64]], NDArray[np.float64]]
                        | None = None, rail: str | RailShape = "60E1",
                        inclination: float = 1.0 / 40.0,
                        wheel_radius_m: float = 0.46, max_shift_mm: float = 15.0,
                        shift_step_mm: float = 0.1, wheel_step_mm: float = 0.2,
                        wheel_y_range_mm: tuple[float, float] = (-55.0, 45.0),
                        smoothing_mm: tuple[float, float] = GAP_SMOOTHING_MM,
                        rail_right: str | RailShape | None = None,
                        gap_smoothing: str | None = None) -> ContactTable:
    """Tabulate the wheel-rail gap function of one wheel over the wheelset's lateral shift.

    The gap comes from the rigid multi-point geometry (``contact.geometry``, the module checked
    against the Manchester benchmark): for each shift of the wheelset centre the roll that puts
    both wheels on their rails is solved, and the vertical gap of every wheel point over the
    rail is taken in that pose. The table's shift is the shift at rail level (contact frame),
    centre shift plus r0 times the rigid roll, on a uniform grid.

    Parameters
    ----------
    wheel_height_mm : wheel profile z(y) in the wheel frame [mm]; default S1002
        (``profiles.s1002``)
    rail : ``60E1`` or ``60E2`` (``profiles.rails``) or a measured rail shape: the left rail
        (and the right one unless ``rail_right`` is given)
    rail_right : the right rail when it is another profile (a high and a low rail of their
        own in a curve): the roll of the rigid geometry is then solved on the two rails, and
        the result carries the right wheel's own table (``ContactTable.right``, built the same
        way on the mirrored track). None, or a rail equal to ``rail``: one (mirrored) table,
        the same numbers as without it
    inclination : rail inclination slope (1/40, 1/20)
    wheel_radius_m : nominal rolling radius at the tape circle [m]
    max_shift_mm, shift_step_mm : table range +-max_shift and step of the shift [mm]
    wheel_step_mm : spacing of the wheel points [mm]
    wheel_y_range_mm : part of the wheel profile searched for contact [mm]
    smoothing_mm : standard deviations of the Gaussian smoothing of the gap along y on the
        tread (y > -15 mm) and on the flange (y < -25 mm), blended linearly between [mm]. The
        tread's 2 mm is the scale of a tread patch (S1002 on a rail crown is nearly conformal
        and the raw gap has shallow double minima). On the flange 2 mm spans the whole 70 deg
        flank (a few mm of wheel y) and the conformal root, which moves the flange contact
        1-3 mm down towards the root (contact angle 30-50 deg; the non-Hertzian pipeline,
        ``contact.wheel_rail``, at the same pose without yaw: 34-48 deg); 0.5 mm on the
        flange brings it within 0.8 mm of the pipeline
        (``benchmarks/curving_flange_vs_geometry.py --flange-smoothing 0.5``) but the root
        patches then become wide and soft and the worn-rail continuation, seed 000's fixed
        steps and seed 002's local wear no longer converge or hold, so it is not the default
        (README, known gaps). Below 0.5 mm the continuation fails at single radii.
    gap_smoothing : ``gaussian`` or ``masked`` (``gap_smoothing``: how the wheel points with no
        rail below take part in the smoothing); None: ``gap_smoothing.GAP_SMOOTHING``

    Returns
    -------
    ContactTable. Geometry: tape circles 1500 mm apart (flange back 1360 mm), rails inclined and
    placed with the gauge 1435 mm measured 14 mm below the top; gaps are vertical distances
    (valid while contact angles stay below ~75 deg; the S1002 flank is at 70 deg).
    """
    method = check_gap_smoothing(gs.GAP_SMOOTHING if gap_smoothing is None else gap_smoothing)
    args = (wheel_height_mm, inclination, wheel_radius_m, max_shift_mm, shift_step_mm,
            wheel_step_mm, wheel_y_range_mm, smoothing_mm, method)
    if rail_right is None or same_rail(rail, rail_right):
        return _side_table(rail, None, *args)
    return replace(_side_table(rail, rail_right, *args),
                   right=_side_table(rail_right, rail, *args))


def same_rail(a: str | RailShape, b: str | RailShape) -> bool:
    """Whether two rails are one profile (names equal, or shapes equal by content)."""
    return type(a) is type(b) and bool(a == b)


def _side_table(rail: str | RailShape, opposite: str | RailShape | None,
                wheel_height_mm: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None,
                inclination: float, wheel_radius_m: float, max_shift_mm: float,
                shift_step_mm: float, wheel_step_mm: float,
                wheel_y_range_mm: tuple[float, float], smoothing_mm: tuple[float, float],
                gap_smoothing: str) -> ContactTable:
    """The left wheel's table on ``rail`` with ``opposite`` as the right rail (None: the
    same rail, mirrored) (:func:`build_contact_table`)."""
    wheel = s1002_height_mm if wheel_height_mm is None else wheel_height_mm
    r0_mm = 1000.0 * wheel_radius_m
    y_w = np.arange(wheel_y_range_mm[0], wheel_y_range_mm[1] + 1e-9, wheel_step_mm)
    z_w = wheel(y_w)
    h = 0.2
    slope = (wheel(y_w + h) - wheel(y_w - h)) / (2 * h)
    # the rigid geometry on a curve through the wheel's points (0.05 mm) and the rail's
    track = wheelset_track(wheel_curve_from_height(wheel, wheel_y_range_mm), rail,
                           inclination, r0_mm, rail_right=opposite)
    # centre shifts wide enough to cover the contact-level grid (the roll adds r0 theta)
    centre = np.arange(-max_shift_mm - 1.0, max_shift_mm + 1.0 + 1e-9, shift_step_mm)
    inside_geo = None
    if gap_smoothing == "masked":
        # beyond the rail the rail's end faces continued, and each point's exact distance
        # inside the rail's envelope: both continuous in the shift (``gap_smoothing``)
        y_geo, raw_geo, roll, inside_geo = rigid_wheel_gap_beyond_rail(track, centre, "left")
    else:
        y_geo, raw_geo, roll = rigid_wheel_gap(track, centre, "left")
    contact_level = centre + r0_mm * roll
    shifts = np.arange(-max_shift_mm, max_shift_mm + 1e-9, shift_step_mm)
    order = np.argsort(y_geo)
    y_geo, raw_geo = y_geo[order], raw_geo[:, order]
    raw_geo = np.where(np.isfinite(raw_geo), raw_geo, gs.NO_RAIL_GAP_MM)
    # rows: linear in the contact-level shift; columns: onto the uniform wheel grid
    pos = np.interp(shifts, contact_level, np.arange(centre.size))
    k = np.clip(np.floor(pos).astype(int), 0, centre.size - 2)
    w = (pos - k)[:, None]
    rows = (1.0 - w) * raw_geo[k] + w * raw_geo[k + 1]
    raw = _interp_rows(y_w, y_geo, rows, gs.NO_RAIL_GAP_MM)
    inside = None
    if inside_geo is not None:
        inside_geo = inside_geo[:, order]
        inside = _interp_rows(y_w, y_geo, (1.0 - w) * inside_geo[k] + w * inside_geo[k + 1],
                              -gs.RAIL_EDGE_RAMP_MM)
    # the wheel's rigid rise so that the roll of the pair is (rise(y) - rise(-y)) / 1500 mm
    rigid_roll = np.interp(shifts, contact_level, roll)
    rigid_rise = TAPE_CIRCLE_HALF_SPACING_MM * rigid_roll
    _, _, rail_origin = rail_envelope(rail, inclination)
    offset = TAPE_CIRCLE_HALF_SPACING_MM - rail_origin  # rail y of wheel y = 0 at zero shift
    lo, hi = FLANK_SMOOTHING_Y_MM
    blend = np.clip((y_w - lo) / (hi - lo), 0.0, 1.0)  # 1 on the tread, 0 on the flank
    sigma = blend * smoothing_mm[0] + (1.0 - blend) * smoothing_mm[1]
    # one smoothing on tread and flange (the default): the blend of two equal filters is the
    # filter itself, computed once
    scales: tuple[tuple[NDArray | float, float], ...] = (
        ((1.0, smoothing_mm[0]),) if smoothing_mm[0] == smoothing_mm[1]
        else ((blend, smoothing_mm[0]), (1.0 - blend, smoothing_mm[1])))
    gap, gap2 = smooth_gap(raw, inside, scales, wheel_step_mm, gap_smoothing)
    # the candidates' contact angle: the wheel's slope averaged with the gap's own weights at
    # each shift (the masked smoothing's normalised kernel) (ContactTable docstring)
    contact_slope = smooth_like_gap(slope, shifts.size, inside, scales, wheel_step_mm,
                                    gap_smoothing)
    log_ratio, app1, a1, b1 = _hertz_unit_table()
    return ContactTable(shift_mm=shifts, wheel_y_mm=y_w, gap_mm=gap, gap2_per_mm=gap2,
                         wheel_z_mm=z_w, wheel_slope=slope, contact_slope=contact_slope,
                         rigid_rise_mm=rigid_rise,
                         rail_offset_mm=offset,
                         nominal_radius_m=wheel_radius_m, smoothing_mm=sigma,
                         hertz_log_ratio=log_ratio,
                         hertz_approach1=app1, hertz_a1=a1, hertz_b1=b1, track=track)


@lru_cache(maxsize=16)
def contact_table_for(wheel_profile: str, rail: str, inclination: float,
                      wheel_radius_m: float, rail_right: Any = None) -> ContactTable:
    """Cached :func:`build_contact_table` for a named wheel profile (``S1002``)."""
    if wheel_profile.upper() != "S1002":
        raise ValueError(f"unknown wheel profile {wheel_profile!r}; known: S1002")
    return build_contact_table(None, rail, inclination, wheel_radius_m, rail_right=rail_right)


@lru_cache(maxsize=16)
def measured_wheel_table_for(wheel: MeasuredWheel, rail: str, inclination: float,
                             wheel_radius_m: float, rail_right: Any = None) -> ContactTable:
    """Cached :func:`build_contact_table` for a measured wheel (over the part of the contact
    search range its points cover)."""
    return build_contact_table(wheel.height_mm, rail, inclination, wheel_radius_m,
                               wheel_y_range_mm=wheel.search_range_mm, rail_right=rail_right)


def track_rails(vehicle: BogieVehicle, direction: str | None = None
                ) -> tuple[str | RailShape, str | RailShape]:
    """The (left, right) rails under a vehicle in a curve to ``direction`` (``left`` or
    ``right``; None for tangent track).

    A vehicle with a high and a low rail of their own (``BogieVehicle.high_rail_profile`` /
    ``low_rail_profile``) runs in every curve with the high rail outside: in a left curve the
    right rail is the high one, in a right curve the left one. On tangent track, and without
    them, both rails are ``rail_profile``.
    """
    if direction is not None and direction not in DIRECTIONS:
        raise ValueError(f"direction must be 'left', 'right' or None, got {direction!r}")
    high = vehicle.high_rail_profile
    low = vehicle.low_rail_profile
    if direction is None or (high is None and low is None):
        return vehicle.rail_profile, vehicle.rail_profile
    high = vehicle.rail_profile if high is None else high
    low = vehicle.rail_profile if low is None else low
    return (low, high) if direction == "left" else (high, low)


def vehicle_contact_table(vehicle: BogieVehicle, direction: str | None = None) -> ContactTable:
    """The (cached) contact table of a vehicle's profile pair on the rails of a curve to
    ``direction`` (:func:`track_rails`; None: tangent track)."""
    left, right = track_rails(vehicle, direction)
    rail: Any = left  # a name or a hashable measured-rail shape
    other: Any = None if same_rail(left, right) else right
    if isinstance(vehicle.wheel_profile, MeasuredWheel):
        return measured_wheel_table_for(vehicle.wheel_profile, rail,
                                        float(vehicle.rail_inclination),
                                        float(vehicle.wheel_radius_m), other)
    return contact_table_for(vehicle.wheel_profile, rail,
                             float(vehicle.rail_inclination), float(vehicle.wheel_radius_m),
                             other)
