"""In-service limits of the flange parameters Sd, Sh, qR and the parameters of a wear curve.

The parameters and their definitions (EN 15313 / MiniProf; docs/conventions.md "Profile
parameters and limits") are the physics core's (:mod:`wearcast.physics.profiles.parameters`,
also used by the wear loop), re-exported here; this module adds the in-service limits
(:class:`WheelLimits`) and the parameters of a profile given as a wear curve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wearcast.physics.profiles.parameters import (
    BACK_FACE_Y_MM,
    QR_DEPTH_MM,
    SD_HEIGHT_MM,
    FlangeParameterArrays,
    FlangeParameters,
    flange_parameters,
    flange_parameters_batch,
    tape_circle_height_mm,
)
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import ReferenceHeight
from wearcast.statistics.wear_curves import reference_on_grid

__all__ = [
    "BACK_FACE_Y_MM", "DEFAULT_LIMITS", "QR_DEPTH_MM", "SD_HEIGHT_MM",
    "FlangeParameterArrays", "FlangeParameters", "WheelLimits", "flange_parameters",
    "flange_parameters_batch", "parameters_from_wear_curve", "tape_circle_height_mm",
]


@dataclass(frozen=True)
class WheelLimits:
    """In-service limits of the flange parameters [mm]; override any of them.

    Defaults: German EBO Anlage 6 (also Austrian EisbBBV Anlage 2; EN 15313 governs) as
    summarised in docs/conventions.md "Profile parameters and limits": flange thickness
    Sd >= 22 mm for international traffic (20 mm domestic), flange height Sh <= 36 mm,
    qR >= 6.5 mm.
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
