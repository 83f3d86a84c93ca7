"""What the lathe plan needs of each wheel, from the fleet state and its latest profile.

* **Wear rates** [mm/km] of Sd, Sh, qR and the diameter: the wheel's own (history since
  turning) where it wears towards the limit, else the fleet's median of the wheels that
  have one.
* **Wear behind the latest profile**: kilometres of wear since the profile was new,
  s_eq = (32.5 - Sd) / r_Sd (its flange-thickness loss from a new S1002 at its own Sd rate);
  without an Sd rate, the kilometres since the first measurement after its last turning.
  The profile at its turning is the latest one with its wear against S1002 scaled by
  (s_eq + km run until then) / s_eq (:func:`turning.projected_profile`).
* **Deadline**: the first limit's P10 remaining kilometres; P50 for the costs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from wearcast.physics.profiles.references import S1002_FLANGE_THICKNESS_MM
from wearcast.statistics.maintenance.fleet_state import FleetState, WheelState
from wearcast.statistics.maintenance.lathe_plan import DiameterGroup, PlanWheel
from wearcast.statistics.maintenance.limits import FLANGE_LIMITS
from wearcast.statistics.maintenance.turning import (
    TargetProfile,
    projected_profile,
    turning_options,
)

#: A wheel's latest measured profile: y [mm], z [mm] and its mileage [km].
LatestProfile = tuple[np.ndarray, np.ndarray, float]


def fleet_rates(state: FleetState) -> dict[str, float]:
    """Fleet median wear rates [mm/km] of the wheels with a history (0 without any)."""
    out = {}
    for name in (*FLANGE_LIMITS, "diameter"):
        values = [float(rate) for w in state.wheels
                  if w.remaining[name].source == "history"
                  and (rate := w.remaining[name].rate_mm_per_1000km) is not None]
        out[name] = max(float(np.median(values)), 0.0) / 1000.0 if values else 0.0
    return out


def wheel_rates(wheel: WheelState, fleet: Mapping[str, float]) -> dict[str, float]:
    """The wheel's own wear rates [mm/km] where positive, the fleet's otherwise."""
    out = {}
    for name in (*FLANGE_LIMITS, "diameter"):
        rem = wheel.remaining[name]
        own = rem.rate_mm_per_1000km if rem.source == "history" else None
        out[name] = own / 1000.0 if own is not None and own > 0 else float(fleet[name])
    return out


def wear_km(wheel: WheelState, rates: Mapping[str, float], profile_mileage_km: float) -> float:
    """Kilometres of wear behind the profile measured at ``profile_mileage_km`` (module
    docstring), at least 1 km."""
    gone = wheel.mileage_km - profile_mileage_km
    if wheel.sd_mm is not None and rates["sd"] > 0 and wheel.sd_mm < S1002_FLANGE_THICKNESS_MM:
        return max((S1002_FLANGE_THICKNESS_MM - wheel.sd_mm) / rates["sd"] - gone, 1.0)
    start = wheel.turned_at_km if wheel.turned_at_km is not None else 0.0
    return max(profile_mileage_km - start, 1.0)


def plan_wheels(state: FleetState, profiles: Mapping[str, LatestProfile],
                targets: Sequence[TargetProfile]
                ) -> tuple[list[PlanWheel], list[dict[str, Any]]]:
    """The plan's wheels, and the wheels it cannot plan with the reason."""
    fleet = fleet_rates(state)
    wheels: list[PlanWheel] = []
    unplanned: list[dict[str, Any]] = []
    for w in state.wheels:
        p10, _ = w.first("p10")
        p50, _ = w.first("p50")
        why = None
        if p10 is None or p50 is None:
            why = ("no remaining-km forecast (fewer than 2 measurements since turning and "
                   "no model)")
        elif w.measured_on is None or not w.km_per_day:
            why = "no date or mileage per day"
        elif w.wheel_id not in profiles:
            why = "no measured profile to cut from"
        if why is not None:
            unplanned.append({"wheel_id": w.wheel_id, "reason": why})
            continue
        assert p10 is not None and p50 is not None
        assert w.measured_on is not None and w.km_per_day is not None
        y, z, mileage = profiles[w.wheel_id]
        rates = wheel_rates(w, fleet)
        behind = wear_km(w, rates, mileage)
        since_latest = behind + (w.mileage_km - mileage)

        @lru_cache(maxsize=8)  # the plan asks again at the same km for its costs
        def options_at(km_since: float, y=y, z=z, behind=behind, rates=rates):
            zz = projected_profile(y, z, km_since / behind)
            return tuple(turning_options(y, zz, targets, state.limits, rates,
                                         rates["diameter"]))

        wheels.append(PlanWheel(w.wheel_id, wheelset_key(w),
                                w.measured_on, w.km_per_day, since_latest,
                                float(p10) if math.isfinite(p10) else math.inf,
                                float(p50) if math.isfinite(p50) else math.inf,
                                w.diameter_mm, options_at, rates["diameter"]))
    return wheels, unplanned


def wheelset_key(wheel: WheelState) -> str:
    """The plan's name of a wheel's wheelset: ``vehicle/bogie type/axle``."""
    return f"{wheel.vehicle_id}/{wheel.bogie_type}/{wheel.axle}"


def diameter_groups(state: FleetState) -> list[DiameterGroup]:
    """The bogies and vehicles of the fleet whose wheelsets' diameters must stay within the
    fleet's bogie and vehicle diameter-difference limits (groups of two wheelsets or more)."""
    bogies: dict[str, set[str]] = {}
    vehicles: dict[str, set[str]] = {}
    for w in state.wheels:
        bogies.setdefault(f"{w.vehicle_id}/{w.bogie_type}", set()).add(wheelset_key(w))
        vehicles.setdefault(w.vehicle_id, set()).add(wheelset_key(w))
    limits = state.limits
    return [DiameterGroup(scope, key, tuple(sorted(sets)), limit)
            for scope, table, limit in (("bogie", bogies, limits.bogie_diameter_difference_mm),
                                        ("vehicle", vehicles,
                                         limits.vehicle_diameter_difference_mm))
            for key, sets in sorted(table.items()) if len(sets) >= 2]
