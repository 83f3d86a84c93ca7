"""Contact patches of one wheel from its interpenetration region, merged or split as CONTACT does.

Given the contact locus of a wheel (``geometry.wheel_locus``: for every wheel sample the
vertical gap g over the rail, the locus point, the contact angle delta and the rolling
curvature A) and a rigid vertical approach d [mm], the rigid interpenetration is
pen(x, y) = d - g(y) - A(y) (x - x_locus(y))^2 (positive inside the bodies).  Following
CONTACT's wheel-rail contact search (Vollebregt, CONTACT user guide, "contact search" and
"A_SEP, D_SEP, D_COMB"; open-source CONTACT, module ``m_wr_locatecp``):

1. interpenetration regions: the maximal runs of consecutive locus samples with pen > 0;
2. per region, the "interpenetration centre of gravity": position and contact angle averaged
   with the weight w = integral over x of pen^2 dx = (16/15) pen0^(5/2) / sqrt(A) per unit
   lateral track width (pen0 = d - g at the locus point), i.e. w_k |dy_k| per sample;
3. regions, sorted from the field side to the track centre, are combined into one patch when
   the distance between their facing ends (track y and rail z) is at most ``dist_sep_mm``
   (CONTACT's D_SEP, 8 mm in the Manchester cases) and their mean contact angles differ by at
   most ``angle_sep_rad`` (A_SEP, 90 deg); the combined patch takes the union of the samples
   and the weighted mean of the centres.  Otherwise they stay separate patches.

So a tread and a flange-root region a few mm apart (the undeformed interpenetration region
connected or nearly so) form one patch, with its reference near the deeper of the two; a
tread and a flange contact 10+ mm apart are two patches.  The patch reference (position,
angle) is what CONTACT reports as the "contact reference location".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.contact.locus import WheelLocus

_FloatArray = NDArray[np.float64]

#: CONTACT's defaults in the Manchester A-2.2 cases (``mbench_a22_*.inp``, DISCNS line).
ANGLE_SEP_RAD = 0.5 * np.pi
DIST_SEP_MM = 8.0


@dataclass(frozen=True)
class PatchRegion:
    """One contact patch of one wheel at one pose: locus samples and reference location.

    samples : indices of the locus samples in the patch (ascending; may have gaps where
        combined regions were apart)
    weight : total interpenetration weight (module docstring) [mm^(7/2)]
    x_track_mm, y_track_mm, z_rail_mm : weighted reference point (track frame) [mm]
    z_track_mm : height of the wheel's locus point there at first touch [mm] (``WheelLocus``)
    contact_angle_rad : weighted contact angle delta [rad]
    y_wheel_mm : wheel-frame lateral position of the reference [mm]
    rolling_radius_mm : wheel radius at the reference [mm]
    max_penetration_mm : largest rigid interpenetration d - g in the patch [mm]
    n_regions : number of interpenetration regions combined into this patch
    """

    samples: NDArray[np.intp]
    weight: float
    x_track_mm: float
    y_track_mm: float
    z_rail_mm: float
    z_track_mm: float
    contact_angle_rad: float
    y_wheel_mm: float
    rolling_radius_mm: float
    max_penetration_mm: float
    n_regions: int


def _runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """(start, stop) of the runs of True in a 1-D mask (stop exclusive)."""
    padded = np.concatenate([[False], mask, [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def sample_weights(locus: WheelLocus, row: int, approach_mm: float) -> _FloatArray:
    """Interpenetration weight per locus sample (M,) at vertical approach d [mm] (module
    docstring, step 2): (16/15) pen^(5/2) / sqrt(A) |dy_track|, 0 where pen <= 0."""
    pen = approach_mm - locus.gap_mm[row]
    inside = np.flatnonzero(locus.valid[row] & (pen > 0.0))
    out = np.zeros(pen.shape)
    out[inside] = ((16.0 / 15.0) * pen[inside]**2.5 / locus.sqrt_curvature_a[inside]
                   * locus.track_width_mm[row, inside])
    return out


def _region(locus: WheelLocus, row: int, samples: NDArray[np.intp], weights: _FloatArray,
            approach_mm: float, n_regions: int) -> PatchRegion:
    # a run of consecutive samples (every region before merging) is gathered by a slice:
    # the same numbers as the index array, without its copies
    pick: slice | NDArray[np.intp] = (
        slice(int(samples[0]), int(samples[-1]) + 1)
        if samples.size and int(samples[-1]) - int(samples[0]) + 1 == samples.size
        else samples)
    w = weights[pick]
    total = float(w.sum())
    gaps = locus.gap_mm[row, pick]
    if total <= 0:  # pen barely positive: use the deepest sample
        w = np.zeros_like(w)
        w[np.argmin(gaps)] = 1.0
        total_w = 1.0
    else:
        total_w = total

    def mean(values: _FloatArray) -> float:
        return float(np.sum(values[pick] * w) / total_w)

    y_track = locus.y_track_mm[row]
    y_ref = mean(y_track)
    # the wheel position and radius at the reference: interpolated along the locus
    ys = y_track[pick]
    order = np.argsort(ys)
    y_wheel = float(np.interp(y_ref, ys[order], locus.y_wheel_mm[pick][order]))
    radius = float(np.interp(y_ref, ys[order], locus.rolling_radius_mm[pick][order]))
    return PatchRegion(
        samples=samples, weight=total, x_track_mm=mean(locus.x_track_mm[row]),
        y_track_mm=y_ref, z_rail_mm=mean(locus.z_rail_mm[row]),
        z_track_mm=mean(locus.z_track_mm[row]),
        contact_angle_rad=mean(locus.contact_angle_rad[row]), y_wheel_mm=y_wheel,
        rolling_radius_mm=radius,
        max_penetration_mm=float(approach_mm - np.min(gaps)),
        n_regions=n_regions,
    )


def patch_regions(locus: WheelLocus, row: int, approach_mm: float,
                  angle_sep_rad: float = ANGLE_SEP_RAD, dist_sep_mm: float = DIST_SEP_MM
                  ) -> list[PatchRegion]:
    """Contact patches of pose ``row`` of the locus at vertical approach d [mm].

    Returns the patches sorted from the wheel's field side to the track centre (CONTACT's
    order); an empty list when d is below the smallest gap.  Module docstring for the rules.
    """
    valid = locus.valid[row]
    pen_mask = valid & (locus.gap_mm[row] < approach_mm)
    runs = _runs(pen_mask)
    if not runs:
        return []
    weights = sample_weights(locus, row, approach_mm)
    sign = locus.sign
    regions = [_region(locus, row, np.arange(a, b), weights, approach_mm, 1) for a, b in runs]
    # field side first: descending sign * y_track
    regions.sort(key=lambda r: -sign * r.y_track_mm)

    def ends(r: PatchRegion) -> tuple[tuple[float, float], tuple[float, float]]:
        """(inner end, outer end) as (y, z): towards the track centre / the field side."""
        ys = locus.y_track_mm[row, r.samples]
        zs = locus.z_rail_mm[row, r.samples]
        inner = int(np.argmin(sign * ys))
        outer = int(np.argmax(sign * ys))
        return (float(ys[inner]), float(zs[inner])), (float(ys[outer]), float(zs[outer]))

    merged = [regions[0]]
    for nxt in regions[1:]:
        cur = merged[-1]
        (y_in, z_in), _ = ends(cur)
        _, (y_out, z_out) = ends(nxt)
        dist = float(np.hypot(y_in - y_out, z_in - z_out))
        angle = abs(cur.contact_angle_rad - nxt.contact_angle_rad)
        if dist <= dist_sep_mm and angle <= angle_sep_rad:
            samples = np.union1d(cur.samples, nxt.samples)
            merged[-1] = _region(locus, row, samples, weights, approach_mm,
                                 cur.n_regions + nxt.n_regions)
        else:
            merged.append(nxt)
    return merged
