"""A rail worn by a line's own traffic to a stated tonnage, by the rail-step model.

The rail-step evolution of seed 003 §6.1 (:func:`wearcast.physics.rail_feedback
.simulate_rail_steps`) wears the rail in steps of D_step^r (its largest normal depth, eq. 4):
step j removes N_step^j vehicle passages' mean rail depth, N_step^j = D_step^r / max(depth per
vehicle), i.e. N_step^j M_v of tonnage (M_v the mass of one vehicle passage). A stated tonnage T
[Mt] generally ends inside a step: the steps run whole while their cumulative tonnage stays
below T, and the step that crosses T removes only the remaining passages,
(T - T_done) / M_v times that step's depth per vehicle (the depth per vehicle is constant
within a step: eq. 4 scales one mean depth). Several tonnages come from ONE chain of steps
(the smaller ones are waypoints of the larger), so the cost is that of the largest.

Mt = 1e6 t (million gross tonnes, MGT); depths mm.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from wearcast.physics.rail_feedback import simulate_rail_steps
from wearcast.physics.rail_head_wear import wear_rail
from wearcast.physics.rail_wear_per_vehicle import vehicle_mass_t
from wearcast.physics.vehicles import BogieVehicle, vehicle_preset
from wearcast.physics.wear_loop import SEED_003_RAIL_D_STEP_MM, WearSteps

#: Wheel steps of each rail step here: 4 adaptive steps of 0.5 mm (the wheel's evolution on a
#: rail, whose mean rail depth the step removes; seed 003 runs 20 of 0.2 mm, about 5x the cost
#: for the same 2 mm of wheel wear).
DEFAULT_WHEEL_STEPS = WearSteps(n_steps=4, depth_per_step_mm=0.5)
#: Most rail steps one call runs (a tonnage that needs more is refused) [-].
MAX_RAIL_STEPS = 12


@dataclass(frozen=True)
class RailsByTonnage:
    """Result of :func:`rails_worn_to_tonnages`.

    rails : {tonnage [Mt]: the rail worn to it} (a tonnage of 0: the vehicle's own rail)
    rail_steps : rail steps run; tonnage_per_step_mt : (rail_steps,) N_step^j M_v [Mt]
    vehicle_mass_t : M_v [t]; elapsed_s : wall time [s]
    """

    rails: dict[float, Any]
    rail_steps: int
    tonnage_per_step_mt: tuple[float, ...]
    vehicle_mass_t: float
    elapsed_s: float


def rails_worn_to_tonnages(vehicle: BogieVehicle | str, route_classes: Any,
                           tonnages_mt: Sequence[float], *, law: Any = "usfd",
                           rail_step_depth_mm: float = SEED_003_RAIL_D_STEP_MM,
                           steps: WearSteps = DEFAULT_WHEEL_STEPS,
                           max_rail_steps: int = MAX_RAIL_STEPS,
                           **kwargs: Any) -> RailsByTonnage:
    """The vehicle's rail worn by its own passages on the route to each stated tonnage.

    vehicle : BogieVehicle or preset name (its ``rail_profile``, a name or a ``WornRail``,
        is the rail at 0 Mt); route_classes : the route's curve classes; tonnages_mt : [Mt],
        each >= 0; law, steps, rail_step_depth_mm : of :func:`simulate_rail_steps` (default
        D_step^r = 0.8 mm, seed 003 §6); kwargs : passed on to it (and to ``simulate_wear``).

    The mean rail (the one rail the contact takes for both wheels) of seed 003 §6.1's rail
    steps, cut inside the step that crosses each tonnage (module docstring). Raises ValueError
    for a negative tonnage or one that needs more than ``max_rail_steps`` steps.
    """
    start = time.perf_counter()
    veh = vehicle_preset(vehicle) if isinstance(vehicle, str) else vehicle
    wanted = sorted({float(t) for t in tonnages_mt})
    if any(not (np.isfinite(t) and t >= 0.0) for t in wanted):
        raise ValueError(f"tonnages_mt must be finite and >= 0, got {list(tonnages_mt)}")
    mass_t = vehicle_mass_t(veh)
    rail: Any = veh.rail_profile
    rails: dict[float, Any] = {t: rail for t in wanted if t == 0.0}
    done_mt = 0.0
    per_step: list[float] = []
    pending = [t for t in wanted if t > 0.0]
    while pending:
        if len(per_step) >= max_rail_steps:
            raise ValueError(f"a rail worn to {pending[-1]:g} Mt needs more than "
                             f"{max_rail_steps} rail steps of {rail_step_depth_mm} mm "
                             f"({done_mt:.2f} Mt after them)")
        step = simulate_rail_steps(replace(veh, rail_profile=rail), route_classes,
                                   n_rail_steps=1, rail_step_depth_mm=rail_step_depth_mm,
                                   steps=steps, law=law, feedback="mean", **kwargs)
        step_mt = float(step.vehicles_per_step[0]) * mass_t / 1e6
        per_step.append(step_mt)
        depth = step.rail_depth_per_vehicle_mm[0]
        while pending and pending[0] <= done_mt + step_mt:
            t = pending.pop(0)
            if t == done_mt + step_mt:
                # the end of the step: the step's own rail (seed 003 eq. 4), not its depth
                # scaled back from the tonnage (t -> passages rounds in the last bit)
                rails[t] = replace(step.rails[1], name=f"worn {t:g} Mt")
                continue
            passages = (t - done_mt) * 1e6 / mass_t
            rails[t] = wear_rail(rail, step.rail_y_mm, passages * depth,
                                 float(veh.rail_inclination), name=f"worn {t:g} Mt")
        rail = step.rails[1]
        done_mt += step_mt
    return RailsByTonnage(rails, len(per_step), tuple(per_step), mass_t,
                          time.perf_counter() - start)
