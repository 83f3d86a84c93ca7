"""A fleet's maintenance limits: flange parameters, scrap diameter, diameter differences.

Sd, Sh and qR defaults are the in-service limits of EN 15313 as summarised by the German EBO
Anlage 6 (Austrian EisbBBV Anlage 2): Sd >= 22 mm (international traffic), Sh <= 36 mm,
qR >= 6.5 mm (:class:`wearcast.statistics.profile_parameters.WheelLimits`).

The diameter limits depend on the wheel and the operator's maintenance plan, which EN 15313
leaves to the operator; the defaults here are assumptions to be overridden per fleet: a
920 mm wheel class scrapped at 840 mm (UIC 510-2 class), and largest running-diameter
differences of 1 mm within an axle, 5 mm within a bogie and 10 mm within a vehicle.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any

from wearcast.statistics.profile_parameters import DEFAULT_LIMITS, WheelLimits

#: The flange-parameter limits in the order of :data:`LIMIT_DIRECTIONS`.
FLANGE_LIMITS = ("sd", "sh", "qr")
#: +1: the parameter wears downwards towards a minimum; -1: upwards towards a maximum.
LIMIT_DIRECTIONS = {"sd": 1.0, "sh": -1.0, "qr": 1.0, "diameter": 1.0}


@dataclass(frozen=True)
class FleetLimits:
    """Limits of one fleet [mm]; any field may be overridden. The flange-parameter defaults
    are :data:`wearcast.statistics.profile_parameters.DEFAULT_LIMITS`."""

    sd_min_mm: float = DEFAULT_LIMITS.sd_min_mm
    sh_max_mm: float = DEFAULT_LIMITS.sh_max_mm
    qr_min_mm: float = DEFAULT_LIMITS.qr_min_mm
    scrap_diameter_mm: float = 840.0
    new_diameter_mm: float = 920.0
    axle_diameter_difference_mm: float = 1.0
    bogie_diameter_difference_mm: float = 5.0
    vehicle_diameter_difference_mm: float = 10.0

    def limit_of(self, name: str) -> float:
        """The limit value [mm] of ``sd``, ``sh``, ``qr`` or ``diameter`` (scrap)."""
        return {"sd": self.sd_min_mm, "sh": self.sh_max_mm, "qr": self.qr_min_mm,
                "diameter": self.scrap_diameter_mm}[name]

    def margin(self, name: str, value: float) -> float:
        """Signed margin [mm] of a parameter value to its limit; negative = crossed."""
        return LIMIT_DIRECTIONS[name] * (value - self.limit_of(name))

    def wheel_limits(self) -> WheelLimits:
        return WheelLimits(self.sd_min_mm, self.sh_max_mm, self.qr_min_mm)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    @classmethod
    def from_overrides(cls, overrides: Mapping[str, Any] | None) -> FleetLimits:
        """Defaults with ``overrides`` applied; raises ValueError "limits.<name>: reason"."""
        allowed = {f.name for f in fields(cls)}
        values: dict[str, float] = {}
        for key, value in (overrides or {}).items():
            if key not in allowed:
                raise ValueError(f"limits.{key}: unknown limit (allowed: {sorted(allowed)})")
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"limits.{key}: must be a number") from None
            if not math.isfinite(number) or number <= 0:
                raise ValueError(f"limits.{key}: must be a finite number > 0")
            values[key] = number
        out = cls(**values)
        if out.scrap_diameter_mm >= out.new_diameter_mm:
            raise ValueError("limits.scrap_diameter_mm: must be below new_diameter_mm")
        return out


DEFAULT_FLEET_LIMITS = FleetLimits()
