"""Flange parameters of a wheel profile in the wheel frame: Sh (FH), Sd (FT), qR.

EN 15313 / MiniProf definitions as in DESIGN.md (seed 003 §4.3 calls them FH, FT, qR):
Sh = flange-tip height above the tape circle (max z); Sd = distance from the back face
(y = -70 mm) to the flange face at z = 10 mm; qR = Sd minus the flange-face position 2 mm below
the tip, i.e. the lateral distance between the flange-face points at z = 10 mm and
z = Sh - 2 mm. S1002 new: Sh 28.0, Sd 32.5, qR 10.8 mm.

Physics must not import ``wearcast.statistics`` (dependencies point service -> statistics ->
physics), so the wear loop computes these here; the statistics package has its own,
richer version for measured profiles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

#: Wheel frame: the back face is 70 mm from the tape circle [mm].
BACK_FACE_Y_MM = -70.0
#: Height of the Sd measuring point above the tape circle [mm].
SD_HEIGHT_MM = 10.0
#: The qR point lies this far below the flange tip [mm].
QR_DROP_MM = 2.0
#: Flange face searched between the tip and this lateral position [mm].
FLANGE_FACE_END_Y_MM = -25.0


@dataclass(frozen=True)
class FlangeParameters:
    """sh_mm (FH) flange height, sd_mm (FT) flange thickness, qr_mm flange-face steepness [mm]."""

    sh_mm: float
    sd_mm: float
    qr_mm: float

    def to_dict(self) -> dict[str, float]:
        return {"sh_mm": self.sh_mm, "sd_mm": self.sd_mm, "qr_mm": self.qr_mm}


def _face_position(y: np.ndarray, z: np.ndarray, height_mm: float) -> float:
    """First y (from the tip towards the tread) where the flange face descends to height."""
    below = np.nonzero(z <= height_mm)[0]
    if below.size == 0 or below[0] == 0:
        return float("nan")
    i = below[0]
    y0, y1, z0, z1 = y[i - 1], y[i], z[i - 1], z[i]
    return float(y0 + (height_mm - z0) * (y1 - y0) / (z1 - z0))


def flange_parameters(y_mm: ArrayLike, z_mm: ArrayLike) -> FlangeParameters:
    """Sh, Sd and qR [mm] of a wheel profile z(y) (wheel frame, y ascending).

    The flange tip is the highest point left of ``FLANGE_FACE_END_Y_MM``; the flange face is the
    descending stretch from the tip towards the tread. NaN where the face does not reach the
    measuring height.
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    if y.ndim != 1 or y.shape != z.shape or y.size < 3:
        raise ValueError("y_mm and z_mm must be 1-D arrays of the same length (>= 3)")
    if np.any(np.diff(y) <= 0):
        raise ValueError("y_mm must be strictly ascending")
    flange = y < FLANGE_FACE_END_Y_MM
    if not np.any(flange):
        raise ValueError("the profile has no flange region (y < -25 mm)")
    tip = int(np.argmax(np.where(flange, z, -np.inf)))
    sh = float(z[tip])
    yf, zf = y[tip:], z[tip:]
    y_sd = _face_position(yf, zf, SD_HEIGHT_MM)
    y_qr = _face_position(yf, zf, sh - QR_DROP_MM)
    return FlangeParameters(sh_mm=sh, sd_mm=y_sd - BACK_FACE_Y_MM, qr_mm=y_sd - y_qr)
