"""Synthetic measurements for a wear-coefficient fit: the wear loop run with known coefficients
(seed 000's lines: fit at 50,000 km, predict at 80,000 km), with Gaussian noise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vehicles import BogieVehicle
from wearcast.physics.wear_loop import WearSteps, simulate_wear
from wearcast.physics.wear_simulation import WearSimulation
from wearcast.statistics.coefficient_fit import fit_law


@dataclass(frozen=True)
class TwinData:
    """Synthetic measurements made by the loop with known coefficients.

    true_coefficients ((4,) KTH zones or (1,) c_tau), y_mm, wear_fit_mm at ``mileage_fit_km``,
    wear_predict_mm at ``mileage_predict_km`` (noise added to both), noise_mm, simulation
    (noise-free truth)
    """

    true_coefficients: NDArray
    y_mm: NDArray
    mileage_fit_km: float
    wear_fit_mm: NDArray
    mileage_predict_km: float
    wear_predict_mm: NDArray
    noise_mm: float
    simulation: WearSimulation


def make_twin(vehicle: BogieVehicle | str, classes: Any, true_coefficients: Sequence[float],
              mileage_fit_km: float = 50_000.0, mileage_predict_km: float = 80_000.0,
              step_km: float = 5000.0, noise_mm: float = 0.0, seed: int = 0,
              y_mm: ArrayLike | None = None, law: str = "archard_kth",
              tau_threshold_mpa: float = 0.0, **loop: Any) -> TwinData:
    """Twin measurements (seed 000's lines: fit at 50,000 km, predict at 80,000 km).

    The truth runs with fixed steps of ``step_km`` to ``mileage_predict_km``; the wear at
    ``mileage_fit_km`` must be a step boundary. Gaussian noise of ``noise_mm`` is added.
    ``law`` and ``tau_threshold_mpa`` as in :class:`CalibrationProblem` (for ``tau_max``,
    ``true_coefficients`` is (c_tau,) [mm/(m MPa)]).
    """
    k = np.asarray(true_coefficients, dtype=float)
    n = int(round(mileage_predict_km / step_km))
    if not np.isclose(n * step_km, mileage_predict_km) or not np.isclose(
            round(mileage_fit_km / step_km) * step_km, mileage_fit_km):
        raise ValueError("both mileages must be multiples of step_km")
    sim = simulate_wear(vehicle, classes, law=fit_law(law, k, tau_threshold_mpa),
                        steps=WearSteps(mode="fixed", n_steps=n, step_km=step_km,
                                        contact_update_depth_mm=loop.pop(
                                            "contact_update_depth_mm", 0.0)), **loop)
    y = sim.y_mm if y_mm is None else np.asarray(y_mm, dtype=float)
    rng = np.random.default_rng(seed)
    i_fit = int(round(mileage_fit_km / step_km))
    fit = np.interp(y, sim.y_mm, sim.wear_mm[i_fit]) + rng.normal(0.0, noise_mm, y.size)
    pred = np.interp(y, sim.y_mm, sim.wear_mm[-1]) + rng.normal(0.0, noise_mm, y.size)
    return TwinData(true_coefficients=k, y_mm=y, mileage_fit_km=mileage_fit_km,
                    wear_fit_mm=fit, mileage_predict_km=mileage_predict_km,
                    wear_predict_mm=pred, noise_mm=noise_mm, simulation=sim)
