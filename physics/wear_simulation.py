"""The result of a wheel wear simulation: the wheel profile after each step of the wear loop.

:class:`WearSimulation` is what :func:`wearcast.physics.wear_loop.simulate_wear` returns: the
profiles z(y) over mileage, the flange parameters (EN 15313 Sh/Sd/qR, i.e. FH/FT/qR), the worn
volume (seed 002 eq. 8), the rail wear per vehicle and the rail steps of seed 003 eq. 4, and the
per-step depth basis the coefficient fit uses; with the wear at a mileage and the mileage to a
depth read off linearly between steps.

Depths and lateral positions in mm, mileage in km, volumes in mm^3.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class WearSimulation:
    """Result of :func:`wearcast.physics.wear_loop.simulate_wear`.

    y_mm (n,), profiles_mm (n_steps+1, n) wheel profile z after each step (row 0: initial),
    mileage_km (n_steps+1,), sh_mm / sd_mm / qr_mm (n_steps+1,) flange parameters (FH, FT, qR),
    step_km (n_steps,), step_max_depth_mm (n_steps,) (the deepest normal depth each step
    removed, ``adaptive_step``: D_step^w in the adaptive mode), worn_volume_mm3 (n_steps+1,)
    (seed 002 eq. 8 against the initial profile), contact_fallbacks, contact_updates,
    elapsed_s, law, application, rail_y_mm, rail_depth_per_vehicle_mm (n_rail,), rail_steps
    (rail step -> vehicles, tonnage [Mt], max depth [mm]; ``rail_wear_per_vehicle.rail_step_rows``),
    rail_high/low_depth_per_vehicle_mm (n_rail,) with ``rail_from_all_wheels`` (else None),
    rail (the rail the wheel ran on: a name or a rail shape; with a high and a low rail of
    their own, the rail of tangent track), high_rail / low_rail (the curves' outer and inner
    rails when they are profiles of their own, ``BogieVehicle.high_rail_profile``, else
    None), rail_update_depths_mm (n_updates, 3, n_rail) with ``rail_from_all_wheels`` (else
    None): the mean, high and low rail depth per vehicle of each contact update (the
    simulations (w_i, r) whose virtual rails seed 003 §6.1 averages), step_basis_mm (n_steps,
    n_basis,
    n): vertical-equivalent depth of each step per unit basis coefficient (the zone
    coefficients for Archard/KTH), used by the exact calibration; coefficients (n_basis,).
    """

    y_mm: NDArray
    profiles_mm: NDArray
    mileage_km: NDArray
    sh_mm: NDArray
    sd_mm: NDArray
    qr_mm: NDArray
    step_km: NDArray
    step_max_depth_mm: NDArray
    worn_volume_mm3: NDArray
    contact_fallbacks: int
    contact_updates: int
    elapsed_s: float
    law: str
    application: str
    n_classes: int
    rail_y_mm: NDArray
    rail_depth_per_vehicle_mm: NDArray
    rail_steps: tuple
    step_basis_mm: NDArray
    coefficients: NDArray
    rail_high_depth_per_vehicle_mm: NDArray | None = None
    rail_low_depth_per_vehicle_mm: NDArray | None = None
    rail: Any = "60E1"
    high_rail: Any = None
    low_rail: Any = None
    rail_update_depths_mm: NDArray | None = None

    @property
    def wear_mm(self) -> NDArray:
        """Vertical wear w(y) = z_initial - z after each step [mm], (n_steps+1, n)."""
        return self.profiles_mm[0] - self.profiles_mm

    def wear_at(self, mileage_km: float) -> NDArray:
        """Vertical wear at a mileage, linear between steps [mm], (n,)."""
        m = self.mileage_km
        if not m[0] <= mileage_km <= m[-1] + 1e-9:
            raise ValueError(f"mileage {mileage_km} km outside the simulated 0..{m[-1]:.0f} km")
        i = int(np.clip(np.searchsorted(m, mileage_km, side="right") - 1, 0, m.size - 2))
        t = (mileage_km - m[i]) / (m[i + 1] - m[i])
        w = self.wear_mm
        return (1 - t) * w[i] + t * w[i + 1]

    def mileage_to_depth(self, depth_mm: float) -> float:
        """First mileage at which the maximum wear depth reaches depth_mm [km] (linear between
        steps; NaN if never)."""
        dmax = self.wear_mm.max(axis=1)
        hit = np.nonzero(dmax >= depth_mm)[0]
        if hit.size == 0:
            return float("nan")
        i = hit[0]
        if i == 0:
            return 0.0
        t = (depth_mm - dmax[i - 1]) / (dmax[i] - dmax[i - 1])
        return float(self.mileage_km[i - 1] + t * (self.mileage_km[i] - self.mileage_km[i - 1]))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (lists of floats)."""
        return {
            "law": self.law, "application": self.application, "n_classes": self.n_classes,
            "y_mm": self.y_mm.tolist(), "profiles_mm": self.profiles_mm.tolist(),
            "mileage_km": self.mileage_km.tolist(), "sh_mm": self.sh_mm.tolist(),
            "sd_mm": self.sd_mm.tolist(), "qr_mm": self.qr_mm.tolist(),
            "step_km": self.step_km.tolist(), "step_max_depth_mm": self.step_max_depth_mm.tolist(),
            "worn_volume_mm3": self.worn_volume_mm3.tolist(),
            "contact_fallbacks": self.contact_fallbacks, "contact_updates": self.contact_updates,
            "elapsed_s": self.elapsed_s, "rail_y_mm": self.rail_y_mm.tolist(),
            "rail_depth_per_vehicle_mm": self.rail_depth_per_vehicle_mm.tolist(),
            "rail_steps": [dict(s) for s in self.rail_steps],
        }
