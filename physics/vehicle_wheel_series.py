"""Per-wheel flange parameters of a whole vehicle along a run, and their vehicle average.

A whole-vehicle wear run (``vehicle_wear_simulation``) gives, at each evaluation mileage, the
flange thickness Sd (FT), flange height Sh (FH) and flange steepness qR of every wheel of every
bogie (EN 15313 §6.3, the parameters seed 003 Table 2 reports). The measurements it is compared
with average all wheels of a unit; the vehicle average here is the bogie-number-weighted mean
over the wheels (``weights`` sum to 1), seed 003 §4-5.

Units: mm, km.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class VehicleWheelSeries:
    """mileage_km (n,); wheels: labels ``"<bogie>-<axle><L|R>"`` (w,); weights (w,) summing
    to 1 (bogie number / wheels); sd_mm, sh_mm, qr_mm (n, w) per wheel [mm]."""

    mileage_km: NDArray
    wheels: tuple[str, ...]
    weights: NDArray
    sd_mm: NDArray
    sh_mm: NDArray
    qr_mm: NDArray

    def mean(self, quantity: str) -> NDArray:
        """Vehicle average of ``sd_mm`` | ``sh_mm`` | ``qr_mm`` per step (as measured) [mm]."""
        return np.asarray(getattr(self, quantity)) @ self.weights

    def mean_at(self, quantity: str, mileage_km: Any) -> NDArray:
        """Vehicle average of a quantity at mileages (linear between steps) [mm]; a mileage
        outside the run raises ``ValueError``."""
        km = np.asarray(mileage_km, dtype=float)
        if np.any(km > self.mileage_km[-1] + 1e-6) or np.any(km < 0):
            raise ValueError(f"mileage outside the simulated 0..{self.mileage_km[-1]:.0f} km")
        return np.interp(km, self.mileage_km, self.mean(quantity))
