"""A synthetic fleet with known wear and turning history, for tests and benchmarks.

Every wheel of ``n_vehicles`` vehicles (motor and trailer bogie, axles 1 and 2, both sides)
was last turned to S1002 at a known mileage and wears since then in a known way: its flange
face and root retreat laterally towards the back face by r = a_f s (the flange back stays,
the tip is trimmed where it meets the unworn S1002, the step to the tread is bridged straight
from the flange root at ``S1002_ROOT_Y_MM``), and its tread loses a layer
a_t s exp(-((y - y_t) / b_t)²) (s [km] since turning; a_f, a_t [mm/km] drawn per wheel),
so its true profile, Sd, Sh, qR and the mileage at which each limit is crossed are known.
Measured profiles are the true ones in the instrument's frame (heights from the worn tape
circle) with Gaussian noise; each wheel is also measured once before its last turning. The
running diameter falls by ``2 a_t`` per km at the tape circle and is measured with noise.
Mileages are cumulative; each vehicle runs ``km_per_day`` (drawn), so every measurement has
a date. The diameters after turning of a vehicle's axles lie within ±1.5 mm of each other.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from wearcast.physics.profiles.parameters import flange_parameters, tape_circle_height_mm
from wearcast.physics.profiles.references import S1002_ROOT_Y_MM
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.maintenance.limits import FleetLimits

Y_TREAD_MM, B_TREAD_MM = 4.0, 14.0


@dataclass(frozen=True)
class SyntheticWheel:
    """One generated wheel and its truth (rates [mm/km], mileages [km], diameters [mm])."""

    wheel_id: str
    vehicle_id: str
    bogie_type: str
    axle: int
    side: str
    km_per_day: float
    flange_rate: float
    tread_rate: float
    turned_at_km: float
    diameter_after_turning_mm: float
    measured_km: tuple[float, ...]
    first_date: dt.date

    def profile(self, y: np.ndarray, km_since: float) -> np.ndarray:
        """True heights [mm] over the worn tape circle."""
        r = self.flange_rate * km_since
        y_a = S1002_ROOT_Y_MM
        ref = s1002_height_mm(y)
        face = np.fmin(ref, s1002_height_mm(np.minimum(y + r, 60.0)))
        z_a = float(s1002_height_mm(np.array([y_a]))[0])
        z = np.where(y >= y_a, ref, np.where(y <= y_a - r, face, z_a))
        z = z - km_since * self.tread_rate * np.exp(-((y - Y_TREAD_MM) / B_TREAD_MM) ** 2)
        return z - tape_circle_height_mm(y, z)

    def date_at(self, mileage_km: float) -> dt.date:
        return self.first_date + dt.timedelta(
            days=(mileage_km - self.measured_km[0]) / self.km_per_day)

    def true_crossing_km(self, limits: FleetLimits, y: np.ndarray) -> float:
        """Cumulative mileage at which the first flange limit is crossed (bisection)."""
        def crossed(km_since: float) -> bool:
            p = flange_parameters(y, self.profile(y, km_since))
            return (p.sd_mm < limits.sd_min_mm or p.sh_mm > limits.sh_max_mm
                    or p.qr_mm < limits.qr_min_mm)

        lo, hi = 0.0, 50_000.0
        while not crossed(hi):
            lo, hi = hi, 2 * hi
            if hi > 1e8:
                return math.inf
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if crossed(mid) else (mid, hi)
        return self.turned_at_km + hi


@dataclass
class SyntheticFleet:
    wheels: list[SyntheticWheel]
    measurements: pd.DataFrame
    profiles: dict[tuple[str, float], tuple[np.ndarray, np.ndarray]] = field(repr=False,
                                                                            default_factory=dict)

    def long_csv(self) -> str:
        """The profiles as a long CSV (one row per point, with ``diameter_mm``)."""
        lines = ["wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,measured_on,"
                 "diameter_mm,y_mm,z_mm"]
        for r in self.measurements.to_dict("records"):
            y, z = self.profiles[(str(r["wheel_id"]), float(r["mileage_km"]))]
            head = (f"{r['wheel_id']},{r['vehicle_id']},{r['bogie_type']},{r['axle']},"
                    f"{r['side']},{r['mileage_km']:.1f},{r['measured_on'].isoformat()},"
                    f"{r['diameter_mm']:.3f}")
            lines.extend(f"{head},{a:.4f},{b:.4f}" for a, b in zip(y, z, strict=True))
        return "\n".join(lines) + "\n"


def generate_fleet(n_vehicles: int = 4, *, seed: int = 0, noise_mm: float = 0.01,
                   diameter_noise_mm: float = 0.05, step_km: float = 12_000.0,
                   n_since_turning: int = 4, y_step_mm: float = 0.4,
                   today: dt.date = dt.date(2026, 6, 1),
                   flange_rate_mm_per_km: float = 4.0e-5,
                   tread_rate_mm_per_km: float = 3.0e-6) -> SyntheticFleet:
    """A fleet whose latest measurements were taken in the weeks before ``today``."""
    rng = np.random.default_rng(seed)
    y = np.round(np.arange(-68.0, 58.0 + 1e-9, y_step_mm), 4)
    wheels, rows, profiles = [], [], {}
    for v in range(n_vehicles):
        vehicle = f"V{v + 1:03d}"
        kpd = float(rng.uniform(300.0, 700.0))
        age_km = float(rng.uniform(400_000.0, 900_000.0))
        vehicle_diameter = float(rng.uniform(862.0, 913.0))
        for bogie in ("motor", "trailer"):
            for axle in (1, 2):
                flange_rate = float(rng.lognormal(math.log(flange_rate_mm_per_km), 0.3))
                tread_rate = float(rng.lognormal(math.log(tread_rate_mm_per_km), 0.3))
                diameter = vehicle_diameter + float(rng.uniform(-1.5, 1.5))
                probe = SyntheticWheel("", "", "", 1, "", kpd, flange_rate, tread_rate, 0.0,
                                       diameter, (0.0,), today)
                life = probe.true_crossing_km(FleetLimits(), y)
                since = float(rng.uniform(0.3, 0.95)) * life
                since = max(since, step_km * n_since_turning)
                turned = age_km - since
                for side in ("left", "right"):
                    wid = f"{vehicle}-{bogie[0].upper()}{axle}{side[0].upper()}"
                    fr = flange_rate * float(rng.uniform(0.9, 1.1))
                    seen = [turned - step_km] + [
                        age_km - step_km * (n_since_turning - 1 - k) - float(rng.uniform(0, 900))
                        for k in range(n_since_turning)]
                    last_date = today - dt.timedelta(days=int(rng.integers(1, 28)))
                    first_date = last_date - dt.timedelta(days=(seen[-1] - seen[0]) / kpd)
                    w = SyntheticWheel(wid, vehicle, bogie, axle, side, kpd, fr, tread_rate,
                                       turned, diameter, tuple(seen), first_date)
                    wheels.append(w)
                    for k, s in enumerate(seen):
                        if k == 0:  # before the turning: worn from an earlier life
                            z = w.profile(y, 0.9 * since) if since > 0 else w.profile(y, 0.0)
                            d_true = diameter + 4.0 + 2 * tread_rate * 0.9 * since
                        else:
                            z = w.profile(y, s - turned)
                            d_true = diameter - 2 * tread_rate * (s - turned)
                        zn = z + rng.normal(0.0, noise_mm, y.size)
                        p = flange_parameters(y, zn)
                        rows.append({"wheel_id": wid, "vehicle_id": vehicle,
                                     "bogie_type": bogie, "axle": axle, "side": side,
                                     "mileage_km": round(s, 1), "measured_on": w.date_at(s),
                                     "sd_mm": p.sd_mm, "sh_mm": p.sh_mm, "qr_mm": p.qr_mm,
                                     "diameter_mm": d_true
                                     + float(rng.normal(0.0, diameter_noise_mm)),
                                     "kind": "profile"})
                        profiles[(wid, round(s, 1))] = (y, zn)
    frame = pd.DataFrame(rows)
    frame["measurement_id"] = np.arange(len(frame))
    return SyntheticFleet(wheels, frame, profiles)
