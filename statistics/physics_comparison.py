"""A whole-vehicle wear simulation against measured, wheel-averaged parameter series.

Seed 003 Table 2 style data: per vehicle, mileages since reprofiling and FT (Sd), FH (Sh), qR
averaged over all the vehicle's wheels. The simulation
(:class:`wearcast.physics.vehicle_wear_simulation.VehicleWearSimulation`) is averaged the same
way; both are compared point by point at the measured mileages: the error per point
(simulated - measured) [mm], and per vehicle and quantity the mean error (bias) and the RMS
error [mm]; the loss rate per 1,000 km (least squares through the origin of the loss from the
new profile's value) of each.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import pandas as pd
from numpy.typing import NDArray

#: Measured column -> simulation quantity (``VehicleWearSimulation.mean``).
QUANTITIES = {"FT_mm": "sd_mm", "FH_mm": "sh_mm", "QR_mm": "qr_mm"}


def loss_rate_per_1000_km(km: np.ndarray, loss_mm: np.ndarray) -> float:
    """Least-squares slope through the origin [mm per 1,000 km]."""
    km = np.asarray(km, dtype=float)
    loss = np.asarray(loss_mm, dtype=float)
    if not np.any(km > 0):
        return float("nan")
    return float(np.sum(km * loss) / np.sum(km * km) * 1000.0)


@dataclass(frozen=True)
class MeasuredComparison:
    """points : one row per measurement (vehicle, distance_km, quantity, measured, simulated,
    error); per_vehicle : per vehicle and quantity n, bias_mm, rms_mm, measured and simulated
    loss rates [mm/1000 km]; overall : per quantity the same over all vehicles."""

    points: pd.DataFrame
    per_vehicle: pd.DataFrame
    overall: pd.DataFrame

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"points": self.points.to_dict(orient="records"),
                "per_vehicle": self.per_vehicle.to_dict(orient="records"),
                "overall": self.overall.to_dict(orient="records")}


def _summary(rows: pd.DataFrame, new_values: dict[str, float]) -> dict[str, float]:
    q = rows["quantity"].iloc[0]
    moving = rows["distance_km"] > 0
    km = rows["distance_km"][moving].to_numpy(float)
    meas_rate = loss_rate_per_1000_km(km, new_values[q] - rows["measured_mm"][moving].to_numpy())
    sim_rate = loss_rate_per_1000_km(km, new_values[q] - rows["simulated_mm"][moving].to_numpy())
    err = rows["error_mm"].to_numpy(float)
    return {"n": int(len(rows)), "bias_mm": float(err.mean()),
            "rms_mm": float(np.sqrt(np.mean(err ** 2))),
            "measured_loss_per_1000_km": meas_rate, "simulated_loss_per_1000_km": sim_rate,
            "loss_error_pct": 100.0 * (sim_rate / meas_rate - 1.0) if meas_rate else np.nan}


class VehicleMeans(Protocol):
    """What :func:`compare_with_measured` reads of a run: its mileages [km] and its vehicle
    averages per step and at mileages [mm] (``physics.vehicle_wheel_series.VehicleWheelSeries``,
    ``physics_model.ScaledVehicle``)."""

    @property
    def mileage_km(self) -> NDArray: ...

    def mean(self, quantity: str) -> NDArray: ...

    def mean_at(self, quantity: str, mileage_km: Any) -> NDArray: ...


def compare_with_measured(simulation: VehicleMeans, measured: pd.DataFrame,
                          new_values: dict[str, float] | None = None) -> MeasuredComparison:
    """Compare a vehicle simulation with measured series (columns ``vehicle``, ``distance_km``
    and any of ``FT_mm``, ``FH_mm``, ``QR_mm``). ``new_values``: the parameters of the new
    profile the losses are counted from (default: the simulation's at 0 km)."""
    if "vehicle" not in measured or "distance_km" not in measured:
        raise ValueError("measured needs the columns vehicle and distance_km")
    cols = [c for c in QUANTITIES if c in measured]
    if not cols:
        raise ValueError(f"measured needs at least one of {', '.join(QUANTITIES)}")
    km = measured["distance_km"].to_numpy(float)
    if np.any(km > simulation.mileage_km[-1] + 1e-6):
        raise ValueError(f"measured mileage {km.max():.0f} km beyond the simulated "
                         f"{simulation.mileage_km[-1]:.0f} km")
    new = new_values or {c: float(simulation.mean(QUANTITIES[c])[0]) for c in cols}
    rows = []
    for col in cols:
        sim = simulation.mean_at(QUANTITIES[col], km)
        rows.append(pd.DataFrame({"vehicle": measured["vehicle"].to_numpy(),
                                  "distance_km": km, "quantity": col,
                                  "measured_mm": measured[col].to_numpy(float),
                                  "simulated_mm": sim}))
    points = pd.concat(rows, ignore_index=True)
    points["error_mm"] = points["simulated_mm"] - points["measured_mm"]
    per_vehicle = pd.DataFrame([{"vehicle": v, "quantity": q, **_summary(g, new)}
                                for (v, q), g in points.groupby(["vehicle", "quantity"])])
    overall = pd.DataFrame([{"quantity": q, **_summary(g, new)}
                            for q, g in points.groupby("quantity")])
    return MeasuredComparison(points, per_vehicle, overall)
