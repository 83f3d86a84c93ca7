"""Rail fed back into the contact: the wheel-and-rail evolution of seed 003 §6.1 (item 2).

For each rail step j the wheel evolves from new over its n_sw wheel steps on the rail r_j
(:func:`wearcast.physics.wear_loop.simulate_wear` with the rail wear from all wheels; the
contact table rebuilt with r_j and the current wheel at every contact update); the mean rail's
depth per vehicle, averaged over those wheel steps (the seed's arithmetic mean of the virtual
rail profiles), is scaled to D_step^r (seed 003 eq. 4: N_step = D_step^r / max depth) and
removed along the rail's normal, giving r_{j+1}
(:class:`~wearcast.physics.rail_head_wear.WornRail`). km_tot^j (seed 003 Tables 5, 8) is the
mileage at the end of the wheel evolution on r_j.

Depths in mm, mileage in km, masses in t (Mt = 1e6 t).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.profiles.rails import RailShape
from wearcast.physics.rail_head_wear import RailHeadWear, WornRail, wear_rail
from wearcast.physics.rail_wear_per_vehicle import vehicle_mass_t
from wearcast.physics.vehicles import BogieVehicle, vehicle_preset
from wearcast.physics.wear_distribution import Smoothing
from wearcast.physics.wear_laws import WearLaw
from wearcast.physics.wear_loop import SEED_003_RAIL_D_STEP_MM, WearSteps, simulate_wear
from wearcast.physics.wear_simulation import WearSimulation


@dataclass(frozen=True)
class RailStepSimulation:
    """Result of :func:`simulate_rail_steps` (seed 003 §6.1, item 2; Tables 5 and 8).

    wheel_runs : one :class:`WearSimulation` per rail step j, the wheel from new on rail r_j
    rails : r_0 .. r_n (n + 1; r_0 the vehicle's rail), the mean rail fed into the contact
    high_rails, low_rails : the outer and inner rail of the curves, r_0 .. r_n, worn with the
        same vehicle numbers from their own depths (computed on the mean rail's contact; they
        are outputs, not fed back: the contact takes one rail for both wheels)
    km_tot : (n,) mileage at the end of each wheel evolution [km] (seed 003 km_tot^j)
    vehicles_per_step : (n,) N_step^j = D_step^r / max(mean rail depth per vehicle) (eq. 4)
    rail_y_mm : (n_rail,) the inclined rail frame's lateral grid [mm]
    rail_depth_per_vehicle_mm : (n, n_rail) mean rail depth per vehicle, averaged over the
        wheel steps of each rail step [mm]
    rail_step_depth_mm : D_step^r [mm]; vehicle_mass_t : mass per vehicle passage [t]
    elapsed_s : wall time [s]
    """

    wheel_runs: tuple[WearSimulation, ...]
    rails: tuple[Any, ...]
    high_rails: tuple[Any, ...]
    low_rails: tuple[Any, ...]
    km_tot: NDArray
    vehicles_per_step: NDArray
    rail_y_mm: NDArray
    rail_depth_per_vehicle_mm: NDArray
    rail_step_depth_mm: float
    vehicle_mass_t: float
    elapsed_s: float

    @property
    def tonnage_mt(self) -> NDArray:
        """Cumulative tonnage at the end of each rail step [Mt] (N_tot M_v)."""
        return np.cumsum(self.vehicles_per_step) * self.vehicle_mass_t / 1e6

    def head_wear(self, step: int, rail: str = "mean") -> RailHeadWear | None:
        """W1/W2/W3 of rail r_step (``mean``, ``high`` or ``low``) against its new head
        (``rail_head_wear``); None for a named (unworn) rail."""
        rails = {"mean": self.rails, "high": self.high_rails, "low": self.low_rails}[rail]
        r = rails[step]
        return r.head_wear() if isinstance(r, WornRail) else None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: per rail step km_tot, FT/FH/qR at its end, vehicles, tonnage and
        the head wear of the three rails it ends with."""
        rows = []
        for j, run in enumerate(self.wheel_runs):
            wear = {}
            for which in ("mean", "high", "low"):
                hw = self.head_wear(j + 1, which)
                wear[which] = None if hw is None else {
                    "w1_mm": hw.vertical.value_mm, "w2_mm": hw.lateral.value_mm,
                    "w3_mm": hw.corner_45.value_mm}
            rows.append({"rail_step": j, "km_tot": float(self.km_tot[j]),
                         "ft_mm": float(run.sd_mm[-1]), "fh_mm": float(run.sh_mm[-1]),
                         "qr_mm": float(run.qr_mm[-1]),
                         "vehicles": float(self.vehicles_per_step[j]),
                         "tonnage_mt": float(self.tonnage_mt[j]),
                         "rail_after": wear})
        return {"rail_steps": rows, "rail_step_depth_mm": self.rail_step_depth_mm,
                "elapsed_s": self.elapsed_s}


def simulate_rail_steps(vehicle: BogieVehicle | str, route_classes: Any, *,
                        n_rail_steps: int = 5,
                        rail_step_depth_mm: float = SEED_003_RAIL_D_STEP_MM,
                        steps: WearSteps | None = None, law: WearLaw | str = "usfd",
                        progress: Callable[[int, int, float], None] | None = None,
                        **kwargs: Any) -> RailStepSimulation:
    """Wheel and rail evolution with the worn rail fed back into the contact (seed 003 §6.1).

    For rail step j = 0 .. n_rail_steps - 1 the wheel evolves from new over ``steps`` (default
    20 adaptive steps of D_step^w = 0.2 mm, seed 003) on rail r_j (:func:`simulate_wear` with
    ``rail_from_all_wheels``: the contact table is rebuilt with r_j and the current wheel at
    every contact update); the mean rail depth per vehicle averaged over the wheel steps is
    smoothed like the wheel's (``smoothing``, default a 3 mm moving average), scaled so that
    its maximum is D_step^r (eq. 4) and removed along the rail's normal
    (``rail_head_wear.wear_rail``): r_{j+1}. The high and low rails are worn alongside with
    the same N_step from their own depths (outputs only).

    vehicle : BogieVehicle or preset name (its ``rail_profile`` is r_0: a name, or a
        ``WornRail`` to continue from); law : default seed 003's USFD; progress :
        callback(rail step done, n_rail_steps, km_tot); kwargs : passed to
        :func:`simulate_wear` (axle, side, application, smoothing, ...).
    """
    start = time.perf_counter()
    if n_rail_steps < 1 or not rail_step_depth_mm > 0:
        raise ValueError("n_rail_steps must be >= 1 and rail_step_depth_mm positive")
    if "rail_from_all_wheels" in kwargs:
        raise ValueError("simulate_rail_steps always takes the rail wear from all wheels")
    veh = vehicle_preset(vehicle) if isinstance(vehicle, str) else vehicle
    rail: Any = veh.rail_profile
    if not isinstance(rail, (str, WornRail)):
        raise ValueError("vehicle.rail_profile must be a rail name or a WornRail "
                         f"to wear it, got {rail!r}")
    given = kwargs.get("smoothing")
    smooth = Smoothing() if given is None else given
    rails, highs, lows = [rail], [rail], [rail]
    runs, km_tot, n_step, depths = [], [], [], []
    rail_y = None
    for j in range(n_rail_steps):
        run = simulate_wear(_with_rail(veh, rails[-1]), route_classes, law=law, steps=steps,
                            rail_from_all_wheels=True, **kwargs)
        runs.append(run)
        km_tot.append(float(run.mileage_km[-1]))
        rail_y = run.rail_y_mm
        assert run.rail_high_depth_per_vehicle_mm is not None
        assert run.rail_low_depth_per_vehicle_mm is not None
        # Smoothed as the wheel's depth (seed 003 §4.3: both distributions are smoothed).
        mean, high, low = (smooth.apply(d, rail_y) for d in (
            run.rail_depth_per_vehicle_mm, run.rail_high_depth_per_vehicle_mm,
            run.rail_low_depth_per_vehicle_mm))
        peak = float(np.max(mean))
        if not peak > 0:
            raise ValueError("the rail does not wear on this route (no loaded patch)")
        n = rail_step_depth_mm / peak
        n_step.append(n)
        depths.append(mean)
        incl = float(veh.rail_inclination)
        rails.append(wear_rail(rails[-1], rail_y, n * mean, incl, name=f"r{j + 1}"))
        highs.append(wear_rail(highs[-1], rail_y, n * high, incl, name=f"high r{j + 1}"))
        lows.append(wear_rail(lows[-1], rail_y, n * low, incl, name=f"low r{j + 1}"))
        if progress is not None:
            progress(j + 1, n_rail_steps, km_tot[-1])
    assert rail_y is not None
    mass_t = vehicle_mass_t(veh)
    return RailStepSimulation(
        wheel_runs=tuple(runs), rails=tuple(rails), high_rails=tuple(highs),
        low_rails=tuple(lows), km_tot=np.array(km_tot), vehicles_per_step=np.array(n_step),
        rail_y_mm=rail_y, rail_depth_per_vehicle_mm=np.array(depths),
        rail_step_depth_mm=float(rail_step_depth_mm), vehicle_mass_t=mass_t,
        elapsed_s=time.perf_counter() - start)


def _with_rail(vehicle: BogieVehicle, rail: str | RailShape) -> BogieVehicle:
    """The vehicle on another rail (a name or a rail shape)."""
    return replace(vehicle, rail_profile=rail)
