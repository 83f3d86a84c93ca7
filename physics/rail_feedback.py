"""Rail fed back into the contact: the wheel-and-rail evolution of seed 003 §6.1 (item 2).

For each rail step j the wheel evolves from new over its n_sw wheel steps on the rails of step
j (:func:`wearcast.physics.wear_loop.simulate_wear` with the rail wear from all wheels; the
contact table rebuilt with those rails and the current wheel at every contact update). Each
wheel step's simulation (w_i, r_j) gives a virtual rail: its rail depths per vehicle scaled to
D_step^r (seed 003 eq. 4-5: N_i = D_step^r / max depth); the rails of step j + 1 are the
arithmetic mean of the virtual rails (seed 003 §6.1), removed along the rail's normal
(:class:`~wearcast.physics.rail_head_wear.WornRail`), after N_step = mean N_i vehicles
(``_virtual_rail_average``). km_tot^j (seed 003 Tables 5, 8) is the mileage at the end of the
wheel evolution on the rails of step j: 20 steps whose largest depth is D_step^w = 0.2 mm
(eq. 2), of seed 003's mean wheel with ``mean_wheel=True`` (passed to ``simulate_wear``: the
mean of the bogie's four wheels, §4.3), else of the tracked wheel.

Rail wear per tonne against seed 003: §4.3 averages the rail's wear, like the wheel's, over the
wheel-rail pairs, so the depth per vehicle of its eq. (4)-(5) is that of one (mean) wheel
passage, while its tonnage counts N_tot whole vehicles (104.7 t, eight axles over each rail;
§6.2.1). Here a vehicle is two bogies of the preset, each rail under its four axle passages
(``rail_wear_per_vehicle``). Per wheel passage the two agree to within the ratio of the wheels'
wear rates (``benchmarks/reproduce_seed003.py --rail-steps`` prints both).

Two feedbacks (``FEEDBACKS``):

* ``high_low``: the high rail (outer rail of every curve) and the low rail (inner)
  are profiles of their own, each worn by its own depth and fed back under its own wheels
  (``BogieVehicle.high_rail_profile`` / ``low_rail_profile``: the curving's contact table per
  side); N_step scales the deeper of the two to D_step^r. Tangent track runs on the mean rail
  r_j, worn by the mean of the two depths (the tangent wear is shared by both rails,
  ``rail_wear_per_vehicle``).
* ``mean`` (default): seed 003 §4.3's one mean rail profile, (high + low) / 2, under both
  wheels everywhere; N_step scales its depth to D_step^r. It stays the default because of the
  known limit below: ``high_low`` is the physically finer model but breaks on seed 003's route
  at its fifth step with Hertz patches, and a default must not give a meaningless answer.

Known limit: with Hertz patches (``patch_width="hertz"``) the high rail's gauge-corner wear
lands on the same narrow band every step (the wheel restarts from new); on seed 003's route
the fifth ``high_low`` step's curving solves then fail and the loop's fallback contacts make
that step meaningless (``contact_fallbacks``; ``benchmarks/reproduce_seed003.py
--rail-steps``).

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

#: Rail feedbacks of :func:`simulate_rail_steps` (module docstring).
FEEDBACKS = ("high_low", "mean")


@dataclass(frozen=True)
class RailStepSimulation:
    """Result of :func:`simulate_rail_steps` (seed 003 §6.1, item 2; Tables 5 and 8).

    wheel_runs : one :class:`WearSimulation` per rail step j, the wheel from new on rail r_j
    rails : r_0 .. r_n (n + 1; r_0 the vehicle's rail), the mean rail (``mean``: the rail of
        both wheels everywhere; ``high_low``: the rail of tangent track)
    high_rails, low_rails : the outer and inner rail of the curves, r_0 .. r_n, worn with the
        same vehicle numbers from their own depths (``high_low``: fed back, each under its
        own wheels in every curve; ``mean``: outputs only, the contact takes the mean rail)
    feedback : ``high_low`` or ``mean`` (module docstring)
    km_tot : (n,) mileage at the end of each wheel evolution [km] (seed 003 km_tot^j)
    vehicles_per_step : (n,) N_step^j, the mean over the wheel steps of N_i = D_step^r /
        max(rail depth per vehicle of simulation i) (eq. 4-5, §6.1)
    rail_y_mm : (n_rail,) the inclined rail frame's lateral grid [mm]
    rail_depth_per_vehicle_mm : (n, n_rail) mean rail depth per vehicle of each rail step:
        N_step^j times it is the mean of the virtual rails' depths, which the step removes
        (peak <= D_step^r) [mm]
    high_depth_per_vehicle_mm, low_depth_per_vehicle_mm : (n, n_rail) the same of the high
        and the low rail [mm]
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
    high_depth_per_vehicle_mm: NDArray
    low_depth_per_vehicle_mm: NDArray
    feedback: str = "mean"

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
        """JSON-ready summary: per rail step km_tot, FT/FH/qR at its end, the wheel run's contact
        fallbacks and updates (a step whose curving solves fell back is not to be trusted:
        module docstring), vehicles, tonnage and the head wear of the three rails it ends
        with."""
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
                         "contact_fallbacks": int(run.contact_fallbacks),
                         "contact_updates": int(run.contact_updates),
                         "vehicles": float(self.vehicles_per_step[j]),
                         "tonnage_mt": float(self.tonnage_mt[j]),
                         "rail_after": wear})
        return {"rail_steps": rows, "rail_step_depth_mm": self.rail_step_depth_mm,
                "feedback": self.feedback, "elapsed_s": self.elapsed_s}


def simulate_rail_steps(vehicle: BogieVehicle | str, route_classes: Any, *,
                        n_rail_steps: int = 5,
                        rail_step_depth_mm: float = SEED_003_RAIL_D_STEP_MM,
                        steps: WearSteps | None = None, law: WearLaw | str = "usfd",
                        progress: Callable[[int, int, float], None] | None = None,
                        feedback: str = "mean", **kwargs: Any) -> RailStepSimulation:
    """Wheel and rail evolution with the worn rail fed back into the contact (seed 003 §6.1).

    For rail step j = 0 .. n_rail_steps - 1 the wheel evolves from new over ``steps`` (default
    20 adaptive steps of D_step^w = 0.2 mm, seed 003) on the rails of step j
    (:func:`simulate_wear` with ``rail_from_all_wheels``: the contact table is rebuilt with
    them and the current wheel at every contact update); the high, low and mean rail depths
    per vehicle of each wheel step are smoothed like the wheel's (``smoothing``, default a
    3 mm moving average) and scaled by N_i so that the fed-back depth of that virtual rail
    peaks at D_step^r (eq. 4-5: ``high_low`` the deeper of high and low, ``mean`` the mean);
    their mean (§6.1) is removed along the rail's normal (``rail_head_wear.wear_rail``): the
    rails of step j + 1. With
    ``high_low`` the high and low rails are fed back each under its own wheels (module
    docstring); with ``mean`` the mean rail under both and the other two are outputs.

    vehicle : BogieVehicle or preset name (its ``rail_profile`` is r_0: a name, or a
        ``WornRail`` to continue from; its ``high_rail_profile`` / ``low_rail_profile``, when
        given, start the high and low rails); law : default seed 003's USFD; progress :
        callback(rail step done, n_rail_steps, km_tot); feedback : ``mean`` (default) or
        ``high_low``;
        kwargs : passed to :func:`simulate_wear` (axle, side, application, smoothing,
        ``mean_wheel`` for seed 003's km_tot of the mean wheel, ...).
    """
    start = time.perf_counter()
    if n_rail_steps < 1 or not rail_step_depth_mm > 0:
        raise ValueError("n_rail_steps must be >= 1 and rail_step_depth_mm positive")
    if "rail_from_all_wheels" in kwargs:
        raise ValueError("simulate_rail_steps always takes the rail wear from all wheels")
    if feedback not in FEEDBACKS:
        raise ValueError(f"feedback must be one of {', '.join(FEEDBACKS)}, got {feedback!r}")
    veh = vehicle_preset(vehicle) if isinstance(vehicle, str) else vehicle
    rail: Any = veh.rail_profile
    high0: Any = rail if veh.high_rail_profile is None else veh.high_rail_profile
    low0: Any = rail if veh.low_rail_profile is None else veh.low_rail_profile
    for name, r in (("rail_profile", rail), ("high_rail_profile", high0),
                    ("low_rail_profile", low0)):
        if not isinstance(r, (str, WornRail)):
            raise ValueError(f"vehicle.{name} must be a rail name or a WornRail "
                             f"to wear it, got {r!r}")
    if feedback == "mean" and (veh.high_rail_profile is not None
                               or veh.low_rail_profile is not None):
        raise ValueError("feedback 'mean' puts one rail under both wheels: the vehicle must "
                         "not carry a high or low rail of its own")
    given = kwargs.get("smoothing")
    smooth = Smoothing() if given is None else given
    rails, highs, lows = [rail], [high0], [low0]
    high_depths, low_depths = [], []
    runs, km_tot, n_step, depths = [], [], [], []
    rail_y = None
    for j in range(n_rail_steps):
        on = (_with_rail(veh, rails[-1]) if feedback == "mean"
              else _with_rails(veh, rails[-1], highs[-1], lows[-1]))
        run = simulate_wear(on, route_classes, law=law, steps=steps,
                            rail_from_all_wheels=True, **kwargs)
        runs.append(run)
        km_tot.append(float(run.mileage_km[-1]))
        rail_y = run.rail_y_mm
        assert run.rail_update_depths_mm is not None
        n, mean, high, low = _virtual_rail_average(run.rail_update_depths_mm, rail_y, smooth,
                                                   rail_step_depth_mm, feedback)
        n_step.append(n)
        depths.append(mean)
        high_depths.append(high)
        low_depths.append(low)
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
        elapsed_s=time.perf_counter() - start,
        high_depth_per_vehicle_mm=np.array(high_depths),
        low_depth_per_vehicle_mm=np.array(low_depths), feedback=feedback)


def _virtual_rail_average(update_depths_mm: NDArray, rail_y_mm: NDArray, smooth: Smoothing,
                          rail_step_depth_mm: float, feedback: str
                          ) -> tuple[float, NDArray, NDArray, NDArray]:
    """One rail step from the wheel evolution's simulations (w_i, r_j) (seed 003 §6.1, p_{j,2}).

    update_depths_mm : (n_updates, 3, n_rail) mean, high and low rail depth per vehicle of
        each contact update (``WearSimulation.rail_update_depths_mm``) [mm]

    Each simulation i gives a virtual rail: its depths, smoothed as the wheel's (seed 003
    §4.3), scaled by eq. (4)-(5) to peak at D_step^r, N_i = D_step^r / peak_i vehicles
    (``mean``: the mean rail's peak; ``high_low``: the deeper of high and low). The rail of the
    next step is the arithmetic mean of the virtual rails, i.e. the mean of the scaled depths
    (removal along the normal of the same rail is linear in the depth to first order); its
    peak is at most D_step^r (the virtual rails' peaks need not coincide). The step's traffic
    is the mean N_step = mean_i N_i (ASSUMED: the seed averages the profiles with equal
    weights and states no N for the mean rail). Returns (N_step, mean, high, low depth per
    vehicle [mm]) with N_step x depth per vehicle = the depth the step removes, so the
    depth per vehicle is the 1/peak_i-weighted mean of the simulations' depths.
    """
    removed = []
    n_i = []
    for depths in update_depths_mm:
        mean, high, low = (smooth.apply(d, rail_y_mm) for d in depths)
        peak = float(np.max(mean) if feedback == "mean" else max(np.max(high), np.max(low)))
        if not peak > 0:
            raise ValueError("the rail does not wear on this route (no loaded patch)")
        n = rail_step_depth_mm / peak
        n_i.append(n)
        removed.append(n * np.stack([mean, high, low]))
    n_step = float(np.mean(n_i))
    per_vehicle = np.mean(removed, axis=0) / n_step
    return n_step, per_vehicle[0], per_vehicle[1], per_vehicle[2]


def _with_rail(vehicle: BogieVehicle, rail: str | RailShape) -> BogieVehicle:
    """The vehicle on another rail (a name or a rail shape)."""
    return replace(vehicle, rail_profile=rail)


def _with_rails(vehicle: BogieVehicle, rail: str | RailShape, high: str | RailShape,
                low: str | RailShape) -> BogieVehicle:
    """The vehicle on a line with tangent rail ``rail`` and curves' high and low rails."""
    return replace(vehicle, rail_profile=rail, high_rail_profile=high, low_rail_profile=low)
