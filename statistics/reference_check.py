"""Does a measured wheel fit the reference profile it was declared against?

Wear only removes material: from a new profile a wheel can reach a thinner flange, a higher
flange over a worn tread (larger Sh) and a steeper flank (smaller qR), with material gone
(positive wear) everywhere. EN 15313 measures Sd 10 mm above the *worn* tape circle, so tread
wear w0 at the tape circle moves the Sd point up the flank and makes Sd larger; the check
compares with the reference's flange thickness and height taken from the same worn level
(reference tape circle lowered by w0). A measured profile whose flange is much *thicker*
than that, whose flange is much *lower*, or that has material well above the reference over
a region (a clearly negative wear area, or a stretch of material well above it), or whose
unworn parts (the flange back the
alignment is fitted on) do not lie on the reference, was not worn from that reference:
another profile was turned (an EN 13715 thinner- or thicker-flange variant, another family)
or the datum is another one. Such a measurement is flagged; its wear areas must not enter
statistics until a reference that fits is given (never silently negative wear).

Thresholds: measurement scatter of a profile gauge is ~0.05 mm per point, so a region of
~100 mm has a wear-area noise of a few mm²; Sd/Sh agree with the instrument to 0.2 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from wearcast.physics.profiles.parameters import FlangeParameters, flange_parameters
from wearcast.statistics.alignment import ReferenceHeight, reference_table
from wearcast.statistics.wear_curves import WearAreas

#: A flange thicker than the reference's by more than this [mm] was not worn from it.
SD_EXCESS_MM = 1.0
#: A flange lower than the reference's by more than this [mm] was not worn from it.
SH_DEFICIT_MM = 1.0
#: A wear area below minus this [mm²] is material the reference does not have.
NEGATIVE_AREA_MM2 = 5.0
#: Material this far above the reference [mm] (wear below minus this) ...
NEGATIVE_WEAR_MM = 0.35
#: ... over a contiguous lateral stretch at least this wide [mm] was not worn from it
#: (measurement noise ~0.05 mm; the vertical alignment on the steep flange back ~0.1-0.2 mm).
NEGATIVE_SPAN_MM = 10.0
#: RMS distance [mm] of the unworn alignment windows from the reference beyond which the
#: shape is another profile (measured noise ~0.05 mm; real S1002 wheels: 0.2-0.3 mm).
UNWORN_RMS_MM = 0.5


@dataclass(frozen=True)
class ReferenceCheck:
    """Outcome of :func:`check_reference`.

    Attributes
    ----------
    fits : True when nothing contradicts wear from the reference
    reference_parameters : Sd, Sh, qR [mm] of the reference itself
    reasons : one sentence per contradiction (empty when ``fits``)
    """

    fits: bool
    reference_parameters: FlangeParameters
    reasons: tuple[str, ...]


@lru_cache(maxsize=64)
def reference_parameters(reference_height: ReferenceHeight) -> FlangeParameters:
    """Sd, Sh, qR [mm] of a reference profile (from its cached table)."""
    table = reference_table(reference_height)
    return flange_parameters(table.y_mm[::5], table.z_mm[::5])


@lru_cache(maxsize=256)
def _reference_at_level(reference_height: ReferenceHeight, tape_wear_mm: float
                        ) -> FlangeParameters:
    table = reference_table(reference_height)
    z0 = float(table.height_mm(0.0)) - tape_wear_mm
    return flange_parameters(table.y_mm[::5], table.z_mm[::5], tape_circle_z_mm=z0)


def _negative_stretch(grid_y_mm: np.ndarray, wear_mm: np.ndarray
                      ) -> tuple[float, float, float] | None:
    """Widest stretch (from, to [mm], deepest [mm]) where w < -NEGATIVE_WEAR_MM, if it is at
    least NEGATIVE_SPAN_MM wide."""
    below = np.isfinite(wear_mm) & (wear_mm < -NEGATIVE_WEAR_MM)
    best: tuple[float, float, float] | None = None
    edges = np.flatnonzero(np.diff(np.concatenate(([0], below.astype(int), [0]))))
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        lo, hi = float(grid_y_mm[start]), float(grid_y_mm[stop - 1])
        if hi - lo >= NEGATIVE_SPAN_MM and (best is None or hi - lo > best[1] - best[0]):
            best = (lo, hi, float(np.min(wear_mm[start:stop])))
    return best


def check_reference(parameters: FlangeParameters, areas: WearAreas,
                    reference_height: ReferenceHeight, tape_circle_wear_mm: float = 0.0,
                    unworn_rms_mm: float = 0.0, grid_y_mm: np.ndarray | None = None,
                    wear_mm: np.ndarray | None = None) -> ReferenceCheck:
    """Check a measured profile's Sd/Sh [mm] and wear areas [mm²] against its reference.

    Parameters
    ----------
    parameters : Sd, Sh, qR of the measured profile [mm]
    areas : its flange/tread wear areas against the reference [mm²]
    reference_height : the reference z(y) [mm]
    tape_circle_wear_mm : wear at the tape circle w(0) [mm] (from the wear curve; NaN or 0
        when unknown): the reference's Sd and Sh are taken from the worn level
    unworn_rms_mm : RMS distance [mm] of the unworn windows from the reference after the
        alignment (``AlignedProfile.rms_residual_mm``)
    grid_y_mm, wear_mm : the wear curve [mm] (optional): a stretch of material above the
        reference (``NEGATIVE_WEAR_MM`` over ``NEGATIVE_SPAN_MM``) contradicts wear too

    Returns
    -------
    ReferenceCheck (module docstring for the rules and thresholds).
    """
    ref = reference_parameters(reference_height)
    w0 = float(tape_circle_wear_mm) if math.isfinite(tape_circle_wear_mm) else 0.0
    at_level = _reference_at_level(reference_height, round(w0, 2))  # 0.01 mm: Sd +-0.004
    reasons = []
    if math.isfinite(parameters.sd_mm) and parameters.sd_mm > at_level.sd_mm + SD_EXCESS_MM:
        reasons.append(f"flange thickness Sd {parameters.sd_mm:.2f} mm exceeds the "
                       f"reference's {at_level.sd_mm:.2f} mm (at this tape-circle wear "
                       f"{w0:+.2f} mm) by {parameters.sd_mm - at_level.sd_mm:.2f} mm (wear "
                       "only thins a flange)")
    if math.isfinite(parameters.sh_mm) and parameters.sh_mm < at_level.sh_mm - SH_DEFICIT_MM:
        below = at_level.sh_mm - parameters.sh_mm
        reasons.append(f"flange height Sh {parameters.sh_mm:.2f} mm is {below:.2f} mm below "
                       f"the reference's {at_level.sh_mm:.2f} mm (at this tape-circle wear "
                       f"{w0:+.2f} mm)")
    if math.isfinite(unworn_rms_mm) and unworn_rms_mm > UNWORN_RMS_MM:
        reasons.append(f"the unworn flange back lies {unworn_rms_mm:.2f} mm RMS off the "
                       f"reference after alignment (beyond {UNWORN_RMS_MM:g} mm)")
    if grid_y_mm is not None and wear_mm is not None:
        stretch = _negative_stretch(np.asarray(grid_y_mm, float), np.asarray(wear_mm, float))
        if stretch is not None:
            lo, hi, deepest = stretch
            reasons.append(f"material up to {-deepest:.2f} mm above the reference over y = "
                           f"{lo:g} … {hi:g} mm (beyond {NEGATIVE_WEAR_MM:g} mm over "
                           f"{NEGATIVE_SPAN_MM:g} mm)")
    for region, value in (("flange", areas.flange_mm2), ("tread", areas.tread_mm2)):
        if np.isfinite(value) and value < -NEGATIVE_AREA_MM2:
            reasons.append(f"{region} wear area {value:.1f} mm² is negative (material above "
                           f"the reference beyond -{NEGATIVE_AREA_MM2:g} mm²)")
    return ReferenceCheck(fits=not reasons, reference_parameters=ref, reasons=tuple(reasons))
