"""Flange parameters Sd, Sh, qR of a wheel profile and their in-service limits.

Definitions (EN 15313 / MiniProf "wheel wear" defaults L1 = 2, L2 = 70, L3 = 10 mm;
docs/conventions.md
"Conventions"; ``reference/README.md`` "Wheel limits"), in the wheel frame y [mm] from the
tape circle (back face at y = -70), z [mm] up towards the flange tip:

* Sh, flange height: flange-tip height minus the tape-circle height z(0);
* Sd, flange thickness: distance from the back face (y = -70) to the flange face (the
  field-side flank of the flange) at 10 mm above the tape-circle height;
* qR, flange slope measure: horizontal distance between the flange-face point 2 mm below the
  tip and the Sd point.

For S1002 new (EN 13715) these are 32.50 / 28.00 / 10.80 mm.

The parameters themselves are computed in the physics core
(:mod:`wearcast.physics.profiles.parameters`, also used by the wear loop) and re-exported here;
this module adds the in-service limits and the parameters of a wear curve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wearcast.physics.profiles.parameters import (
    BACK_FACE_Y_MM,
    QR_DEPTH_MM,
    SD_HEIGHT_MM,
    BatchGrid,
    FlangeParameterArrays,
    FlangeParameters,
    flange_parameters,
    flange_parameters_batch,
)
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import ReferenceHeight
from wearcast.statistics.wear_curves import reference_on_grid

__all__ = [
    "BACK_FACE_Y_MM", "DEFAULT_LIMITS", "QR_DEPTH_MM", "SD_HEIGHT_MM", "BatchGrid",
    "FlangeParameterArrays", "FlangeParameters", "WheelLimits", "flange_parameters",
    "flange_parameters_batch", "parameters_from_wear_curve",
]


@dataclass(frozen=True)
class WheelLimits:
    """In-service limits of the flange parameters [mm]; override any of them.

    Defaults: German EBO Anlage 6 (also Austrian EisbBBV Anlage 2; EN 15313 governs) as
    summarised in ``reference/README.md`` "Wheel limits": flange thickness Sd >= 22 mm for
    international traffic (20 mm domestic), flange height Sh <= 36 mm, qR >= 6.5 mm.
    """

    sd_min_mm: float = 22.0
    sh_max_mm: float = 36.0
    qr_min_mm: float = 6.5

    def exceeded(self, parameters: FlangeParameters) -> tuple[str, ...]:
        """Names (``"sd"``, ``"sh"``, ``"qr"``) of the limits the parameters violate."""
        out = []
        if parameters.sd_mm < self.sd_min_mm:
            out.append("sd")
        if parameters.sh_mm > self.sh_max_mm:
            out.append("sh")
        if parameters.qr_mm < self.qr_min_mm:
            out.append("qr")
        return tuple(out)


#: Default limits (international traffic); ``WheelLimits(sd_min_mm=20.0)`` for domestic.
DEFAULT_LIMITS = WheelLimits()


def parameters_from_wear_curve(
    grid_y_mm: ArrayLike,
    wear_mm: ArrayLike,
    reference_height: ReferenceHeight = s1002_height_mm,
) -> FlangeParameters:
    """Sd, Sh, qR of the worn profile z_worn = z_ref - w given on a lateral grid.

    Parameters
    ----------
    grid_y_mm : ascending lateral grid [mm] (must include y = 0, the flange tip and flank)
    wear_mm : wear curve on the grid [mm]
    reference_height : reference profile z(y) [mm] (default S1002)

    Returns
    -------
    FlangeParameters of the worn profile (docs/conventions.md hybrid model step 6).
    """
    grid = np.asarray(grid_y_mm, dtype=float)
    z_worn = reference_on_grid(grid, reference_height) - np.asarray(wear_mm, dtype=float)
    return flange_parameters(grid, z_worn)
