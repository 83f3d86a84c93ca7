"""Whole-vehicle wear: every wheel of every bogie, both running directions, averaged as measured.

Seed 003 measures FT, FH and qR on every wheel of each Minuetto unit and averages them (§5.2,
Table 2), and simulates "one mean profile for all the wheels of the vehicle" (§4). The
single-wheel loop (:func:`wearcast.physics.wear_loop.simulate_wear`) tracks one wheel (by
default the right wheel of the leading axle), which is not what was measured. Here:

* The vehicle is a list of bogie types with their number (the Minuetto: two motor end bogies
  and two trailer Jacobs bogies, seed 003 §3). Each bogie type is solved by the quasi-static
  curving model once per step and operating point; the contacts of its four wheels come from
  that one solution (:func:`class_contacts.class_contacts_all_wheels`).
* Running directions: a vehicle that reverses at the termini runs a share ``forward_share`` of
  its mileage with axle 1 leading and the rest with axle 2 leading. The bogie is symmetric
  fore and aft, so running backwards is the same bogie with the other axle leading: the
  physical axle a wears at s r_lead(a) + (1 - s) r_lead(3 - a) with s = ``forward_share``. A
  wheel stays on its rail, so its side (outer in a curve of its hand) does not change.
* Wheel profiles: one per physical wheel position (bogie type, axle, side), each worn by its
  own rate. The curving model takes one wheel profile for all four wheels of a bogie; it is
  given the mean of the bogie's four profiles (seed 003's mean-profile simplification). With
  ``forward_share`` = 0.5 and a route whose left and right curves have equal shares, the four
  wheels wear alike and the mean profile is every wheel's own profile.
* Steps: adaptive, the largest normal depth of any wheel in a step equals D_step (seed 003
  eq. 2), the last step cut to land on the end mileage (``cut_last_step=False``: kept whole,
  the run ends at the first step at or beyond it, a prefix of every longer run); the contact
  is re-solved every step, each operating point warm-started from its last equilibrium.
* Averaged as measured: Sd (FT), Sh (FH), qR of every wheel, averaged over all wheels of the
  vehicle (bogie types weighted by their number).
* ``wear_scale`` multiplies the wheel's worn volume (a calibrated wear-coefficient scale);
  ``flange_wear_factor`` multiplies the wear of patches whose contact angle exceeds
  ``FLANGE_ANGLE_RAD`` (flange lubrication: < 1).

Depths mm, mileage km.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.adaptive_step import adaptive_step
from wearcast.physics.patch_wear import wheel_depth_basis_by_slot
from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.step_convergence import DEFAULT_TOLERANCE, StepConvergence, converge_steps
from wearcast.physics.vehicle_wheel_series import VehicleWheelSeries
from wearcast.physics.vehicles import BogieVehicle, vehicle_preset
from wearcast.physics.wear_distribution import Smoothing, apply_normal_wear, depth_below_mm
from wearcast.physics.wear_laws import WearLaw
from wearcast.physics.wear_loop import (
    BOGIE_WHEELS,
    MAX_WHEEL_WEAR_MM,
    WHEEL_GRID_MM,
    ClassContacts,
    WearLoopDivergedError,
    as_loop_classes,
    class_contacts_all_wheels,
    contact_key,
    law_coefficients,
    wheel_depth_basis,
)

#: Contact angle above which a patch counts as a flange patch for ``flange_wear_factor`` [rad]
#: (about 20 degrees: the S1002 tread and flange root stay below, the flange flank above).
FLANGE_ANGLE_RAD = 0.35
#: Bogies of the presets' whole vehicles: (bogie type, number). Seed 003 §3: the Minuetto has
#: four bogies, the two end ones motor, the two intermediate (Jacobs) ones trailer.
VEHICLE_BOGIES: dict[str, tuple[tuple[str, int], ...]] = {
    "minuetto": (("motor", 2), ("trailer", 2)),
}
#: Default bogies of a preset not listed above: one motor, one trailer bogie.
DEFAULT_BOGIES: tuple[tuple[str, int], ...] = (("motor", 1), ("trailer", 1))


@dataclass(frozen=True)
class VehicleWearOptions:
    """The physical options of a whole-vehicle run (the diagnosis varies them).

    forward_share : share of the mileage run with axle 1 leading [-] (0.5: reverses at termini)
    wear_scale : factor on the wheel's worn volume (calibrated coefficient scale) [-]
    flange_wear_factor : factor on the wear of flange patches (lubrication < 1) [-]
    friction : coefficient of friction replacing the preset's (None: the preset's) [-]
    patch_width : ``hertz`` | ``kik_piotrowski`` (``wear_loop.class_contacts``)
    application : ``global`` | ``local``
    rail : the rail under every wheel, replacing the preset's: a name (``60E1``, ``60E2``),
        a measured rail or a rail worn by the loop (``rail_head_wear.WornRail``, e.g. a rail
        step of ``rail_feedback.simulate_rail_steps``); None: the preset's
    high_rail, low_rail : the outer and the inner rail of every curve when they are profiles
        of their own (``BogieVehicle.high_rail_profile`` / ``low_rail_profile``: the curving's
        contact table per side; e.g. ``RailStepSimulation.high_rails[j]`` / ``low_rails[j]``);
        tangent track keeps ``rail``; None: ``rail`` in the curves too
    traction_torque_nm : driving (+) or braking (-) torque on every axle of every motor bogie
        [N m], held over the whole route (the mean tractive effort the line demands, seed 001
        §2.2's traction on motor wheels); trailer bogies roll free; None: the preset's
    """

    forward_share: float = 0.5
    wear_scale: float = 1.0
    flange_wear_factor: float = 1.0
    friction: float | None = None
    patch_width: str = "hertz"
    application: str = "global"
    rail: Any = None
    traction_torque_nm: float | None = None
    high_rail: Any = None
    low_rail: Any = None

    def __post_init__(self) -> None:
        if not 0.0 <= self.forward_share <= 1.0:
            raise ValueError("forward_share must lie in [0, 1]")
        if not (self.wear_scale > 0 and self.flange_wear_factor >= 0):
            raise ValueError("wear_scale must be > 0 and flange_wear_factor >= 0")
        if self.friction is not None and not 0 < self.friction < 1.5:
            raise ValueError("friction must lie in (0, 1.5)")
        if self.traction_torque_nm is not None and not np.isfinite(self.traction_torque_nm):
            raise ValueError("traction_torque_nm must be finite")


@dataclass(frozen=True)
class VehicleWearSimulation(VehicleWheelSeries):
    """Result of :func:`simulate_vehicle_wear`: the per-wheel series of
    :class:`VehicleWheelSeries` with y_mm (n,), profiles_mm (n_wheels, n) at the end;
    contact_updates, contact_fallbacks, elapsed_s, depth_per_step_mm (D_step), options.
    """

    y_mm: NDArray
    initial_profile_mm: NDArray
    profiles_mm: NDArray
    contact_updates: int
    contact_fallbacks: int
    elapsed_s: float
    depth_per_step_mm: float
    options: VehicleWearOptions
    law: str
    convergence: StepConvergence | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (vehicle means per step)."""
        return {"mileage_km": self.mileage_km.tolist(), "wheels": list(self.wheels),
                "ft_mm": self.mean("sd_mm").tolist(), "fh_mm": self.mean("sh_mm").tolist(),
                "qr_mm": self.mean("qr_mm").tolist(), "contact_updates": self.contact_updates,
                "contact_fallbacks": self.contact_fallbacks, "elapsed_s": self.elapsed_s,
                "depth_per_step_mm": self.depth_per_step_mm, "law": self.law,
                "step_convergence": None if self.convergence is None
                else self.convergence.to_dict()}


def vehicle_bogies(vehicle: str | Sequence[tuple[BogieVehicle, int]],
                   friction: float | None = None) -> list[tuple[BogieVehicle, int]]:
    """Bogie types of a whole vehicle with their number: a preset name
    (:data:`VEHICLE_BOGIES`, else one motor and one trailer bogie) or explicit pairs."""
    if isinstance(vehicle, str):
        spec = VEHICLE_BOGIES.get(vehicle, DEFAULT_BOGIES)
        out = [(vehicle_preset(vehicle, bogie), n) for bogie, n in spec]
    else:
        out = [(b, int(n)) for b, n in vehicle]
    if not out or any(n < 1 for _, n in out):
        raise ValueError("a vehicle needs at least one bogie, each with a number >= 1")
    if friction is not None:
        out = [(replace(b, friction=friction), n) for b, n in out]
    return out


def _wheel_rates(contacts: dict[tuple[int, str], ClassContacts], law: WearLaw, y: NDArray,
                 shares: NDArray, options: VehicleWearOptions, friction: float,
                 smoothing: Smoothing, fastsim_grid: int) -> dict[tuple[int, str], NDArray]:
    """Normal depth per km of each curving wheel (axle 1 leading) [mm/km], smoothed."""
    coeffs = law_coefficients(law)
    out = {}
    for wheel, c in contacts.items():
        if options.flange_wear_factor != 1.0:
            # Scale the flange patches' normal force share of wear via a per-patch factor.
            factor = np.where(c.contact_angle_rad > FLANGE_ANGLE_RAD,
                              options.flange_wear_factor, 1.0)
            per_class = _scaled_basis(c, law, y, options.application, fastsim_grid, friction,
                                      factor)
        else:
            per_class = wheel_depth_basis(c, law, y, options.application, fastsim_grid,
                                          friction)
        rate = np.einsum("c,cbn->bn", shares, per_class).T @ coeffs * 1000.0
        out[wheel] = options.wear_scale * smoothing.apply(rate, y)
    return out


def _scaled_basis(c: ClassContacts, law: WearLaw, y: NDArray, application: str,
                  fastsim_grid: int, friction: float, factor: NDArray) -> NDArray:
    """wheel_depth_basis with each patch's contribution multiplied by ``factor`` (n_class,
    n_slot): the patches are split into per-slot contacts (the basis is additive in patches);
    global application: all slots' parts from one spread (``wheel_depth_basis_by_slot``, the
    same numbers)."""
    by_slot = (wheel_depth_basis_by_slot(c, law, y) if application == "global" else None)
    total = None
    for slot in range(c.normal_force_n.shape[1]):
        if by_slot is not None:
            part = by_slot[slot]
        else:
            only = np.zeros_like(c.in_contact)
            only[:, slot] = c.in_contact[:, slot]
            part = wheel_depth_basis(replace(c, in_contact=only), law, y, application,
                                     fastsim_grid, friction)
        part = part * factor[:, slot][:, None, None]
        total = part if total is None else total + part
    assert total is not None
    return total


def simulate_vehicle_wear(vehicle: str | Sequence[tuple[BogieVehicle, int]], route_classes: Any,
                          *, law: WearLaw | str = "usfd", mileage_km: float = 3600.0,
                          depth_per_step_mm: float = 0.2,
                          options: VehicleWearOptions | None = None,
                          smoothing: Smoothing | None = None,
                          initial_profile: tuple[NDArray, NDArray] | None = None,
                          unbalanced_acceleration_m_s2: float = 0.58,
                          tangent_speed_kmh: float = 100.0, fastsim_grid: int = 20,
                          max_steps: int = 400,
                          progress: Callable[[float], None] | None = None,
                          continue_from: VehicleWearSimulation | None = None,
                          contact_cache: dict | None = None,
                          cut_last_step: bool = True
                          ) -> VehicleWearSimulation:
    """Wear of every wheel of a vehicle over a route of curve classes to ``mileage_km``.

    vehicle : preset name (whole vehicle per :data:`VEHICLE_BOGIES`) or (BogieVehicle, number)
        pairs; route_classes : as ``wear_loop.simulate_wear``; law : WearLaw or name (default
        seed 003's USFD); depth_per_step_mm : D_step [mm] (seed 003: 0.2); options :
        :class:`VehicleWearOptions`; progress : callback(mileage_km).
    continue_from : an earlier run of the same vehicle, route, law and options to go on from
        (its wheel profiles at its end, its series kept; the first contact solve starts cold):
        a longer run without redoing the first part; ``max_steps`` counts the new steps. The
        wheels, grid, law and options are checked; vehicle and route are the caller's.
    contact_cache : optional dict shared by several runs (the parameter sets of a diagnosis)
        that stores each bogie's FIRST contact update (solved from centred wheelsets, no
        previous contact: a function of the bogie, classes, operating-point options and the
        exact profile bytes alone) and reuses it in a run whose first update has the same
        key: runs that differ only in the wear (scale, flange factor, running direction,
        law) solve the new profile's contact once. Results are identical with and without it
        (only updates without fallbacks are stored).
    cut_last_step : True: the last step is cut to end at ``mileage_km``; False: it is a whole
        step like the others, so the run ends at or beyond ``mileage_km`` and is step for step
        the first part of the same run to any longer mileage (the physics diagnosis reads its
        runs up to a mileage and needs them to be the longer runs' there).
    """
    start = time.perf_counter()
    opts = options or VehicleWearOptions()
    wl = WearLaw(name=law) if isinstance(law, str) else law
    sm = smoothing or Smoothing()
    if not (mileage_km > 0 and depth_per_step_mm > 0):
        raise ValueError("mileage_km and depth_per_step_mm must be positive")
    bogies = vehicle_bogies(vehicle, opts.friction)
    if opts.rail is not None:
        bogies = [(replace(b, rail_profile=opts.rail), n) for b, n in bogies]
    if opts.high_rail is not None or opts.low_rail is not None:
        bogies = [(replace(b, high_rail_profile=opts.high_rail, low_rail_profile=opts.low_rail),
                   n) for b, n in bogies]
    if opts.traction_torque_nm is not None:
        bogies = [(replace(b, traction_torque_nm=float(opts.traction_torque_nm))
                   if b.bogie_type == "motor" else b, n) for b, n in bogies]
    classes = as_loop_classes(route_classes)
    shares = np.array([c.share for c in classes], dtype=float)
    shares = shares / shares.sum()
    if initial_profile is None:
        lo, hi, h = WHEEL_GRID_MM
        y = np.linspace(lo, hi, int(round((hi - lo) / h)) + 1)
        z0 = s1002_height_mm(y)
    else:
        y = np.asarray(initial_profile[0], dtype=float)
        z0 = np.asarray(initial_profile[1], dtype=float)
    n_b = len(bogies)
    profiles = np.repeat(z0[None, None, :], n_b * 4, axis=0).reshape(n_b, 4, -1).copy()
    labels = tuple(f"{b.bogie_type}{i}-{a}{s[0].upper()}" for i, (b, _) in enumerate(bogies)
                   for a, s in BOGIE_WHEELS)
    weights = np.array([n for _, n in bogies for _ in BOGIE_WHEELS], dtype=float)
    weights /= weights.sum()
    previous: list[dict | None] = [None] * n_b
    mileage = [0.0]
    params = [_parameters(y, profiles)]
    updates = fallbacks = 0
    if continue_from is not None:
        if (continue_from.wheels != labels or continue_from.y_mm.shape != y.shape
                or continue_from.law != wl.name or continue_from.options != opts):
            raise ValueError("continue_from: a run of other wheels, wheel grid, law or "
                             "options")
        z0 = continue_from.initial_profile_mm
        profiles = continue_from.profiles_mm.reshape(n_b, 4, -1).copy()
        mileage = [float(m) for m in continue_from.mileage_km]
        params = [np.stack([continue_from.sd_mm[i], continue_from.sh_mm[i],
                            continue_from.qr_mm[i]]) for i in range(len(mileage))]
        updates, fallbacks = continue_from.contact_updates, continue_from.contact_fallbacks
    fwd = opts.forward_share
    lead_index = {w: i for i, w in enumerate(BOGIE_WHEELS)}
    for _ in range(max_steps):
        if mileage[-1] >= mileage_km - 1e-9:
            break
        rates = np.zeros_like(profiles)
        for bi, (bogie, _) in enumerate(bogies):
            mean_z = profiles[bi].mean(axis=0)
            key = None
            if contact_cache is not None and previous[bi] is None:
                key = (contact_key(bogie, classes, 0, "all", unbalanced_acceleration_m_s2,
                                   tangent_speed_kmh, fastsim_grid, y, opts.patch_width),
                       mean_z.tobytes())
            hit = None if key is None or contact_cache is None else contact_cache.get(key)
            if hit is not None:
                contacts, fb = hit, 0
            else:
                contacts, fb = class_contacts_all_wheels(
                    bogie, classes, y, mean_z,
                    unbalanced_acceleration_m_s2=unbalanced_acceleration_m_s2,
                    tangent_speed_kmh=tangent_speed_kmh, fastsim_grid=fastsim_grid,
                    previous=previous[bi], patch_width=opts.patch_width, warm_first=True)
                if key is not None and contact_cache is not None and fb == 0:
                    contact_cache[key] = contacts
            previous[bi] = contacts
            updates += 1
            fallbacks += fb
            lead_rates = _wheel_rates(contacts, wl, y, shares, opts, bogie.friction, sm,
                                      fastsim_grid)
            for axle, side in BOGIE_WHEELS:
                other = (3 - axle, side)
                rates[bi, lead_index[(axle, side)]] = (fwd * lead_rates[(axle, side)]
                                                       + (1.0 - fwd) * lead_rates[other])
        _check_finite_rates(rates, labels, mileage[-1])
        remaining = mileage_km - mileage[-1]
        # seed 003 eq. 2: the deepest point of any wheel loses D_step normal to its profile
        # (at most MAX_VERTICAL_STEP_FACTOR D_step of vertical change, adaptive_step)
        ds = adaptive_step(rates, depth_per_step_mm, np.gradient(profiles, y, axis=-1))
        if not math.isfinite(ds):
            ds = remaining
        elif cut_last_step:
            ds = min(ds, remaining)
        for bi in range(n_b):
            for wi in range(4):
                profiles[bi, wi] = apply_normal_wear(y, profiles[bi, wi], rates[bi, wi] * ds)
        _check_profiles(y, z0, profiles, labels, mileage[-1])
        mileage.append(mileage[-1] + ds)
        params.append(_parameters(y, profiles))
        if progress is not None:
            progress(mileage[-1])
    else:
        raise RuntimeError(f"max_steps={max_steps} reached at {mileage[-1]:.0f} km; "
                           "raise depth_per_step_mm or max_steps")
    p = np.array(params)                                       # (n_steps+1, 3, n_wheels)
    return VehicleWearSimulation(
        mileage_km=np.array(mileage), wheels=labels, weights=weights, sd_mm=p[:, 0],
        sh_mm=p[:, 1], qr_mm=p[:, 2], y_mm=y, initial_profile_mm=z0,
        profiles_mm=profiles.reshape(n_b * 4, -1), contact_updates=updates,
        contact_fallbacks=fallbacks, elapsed_s=time.perf_counter() - start,
        depth_per_step_mm=depth_per_step_mm, options=opts, law=wl.name)


def simulate_vehicle_wear_converged(vehicle: str | Sequence[tuple[BogieVehicle, int]],
                                    route_classes: Any, *, first_step_mm: float = 0.8,
                                    max_halvings: int = 2,
                                    tolerance: float = DEFAULT_TOLERANCE,
                                    **kwargs: Any) -> VehicleWearSimulation:
    """:func:`simulate_vehicle_wear` with D_step = ``first_step_mm`` halved until the vehicle
    mean FT and qR at the end change by less than ``tolerance`` of their loss
    (:mod:`wearcast.physics.step_convergence`); the finest run, with its ``convergence``."""
    if "depth_per_step_mm" in kwargs:
        raise ValueError("give first_step_mm, not depth_per_step_mm")

    def run(step: float) -> VehicleWearSimulation:
        return simulate_vehicle_wear(vehicle, route_classes, depth_per_step_mm=step, **kwargs)

    def ends(sim: VehicleWearSimulation) -> dict[str, float]:
        return {"FT": float(sim.mean("sd_mm")[-1]), "qR": float(sim.mean("qr_mm")[-1])}

    sim = run(first_step_mm)
    initial = {"FT": float(sim.mean("sd_mm")[0]), "qR": float(sim.mean("qr_mm")[0])}
    runs = iter([sim])

    def cached(step: float) -> VehicleWearSimulation:
        return next(runs, None) or run(step)

    result, conv = converge_steps(cached, ends, initial, first_step_mm,
                                  tolerance=tolerance, max_halvings=max_halvings)
    return replace(result, convergence=conv)


def _check_finite_rates(rates: NDArray, labels: Sequence[str], mileage_km: float) -> None:
    """Raise :class:`WearLoopDivergedError` naming the wheels whose wear rate of this step is
    not finite (a contact with a non-finite patch), before it reaches a profile."""
    flat = rates.reshape(len(labels), -1)
    bad = [w for w, r in zip(labels, flat, strict=True) if not np.all(np.isfinite(r))]
    if bad:
        raise WearLoopDivergedError(
            f"vehicle wear loop diverged near {mileage_km:.0f} km: non-finite wear rate of "
            f"{', '.join(bad)} (a contact patch of this step's contact update is not finite)")


def _check_profiles(y: NDArray, z0: NDArray, profiles: NDArray, labels: Sequence[str],
                    mileage_km: float) -> None:
    """Raise :class:`WearLoopDivergedError` on a non-finite profile or one worn deeper than
    ``MAX_WHEEL_WEAR_MM`` below the new profile, normal to it (``depth_below_mm``: a flange
    face worn sideways is not a rim worn through), naming the wheel and where."""
    flat = profiles.reshape(len(labels), -1)
    for label, z in zip(labels, flat, strict=True):
        if not np.all(np.isfinite(z)):
            raise WearLoopDivergedError(f"vehicle wear loop diverged near {mileage_km:.0f} km: "
                                        f"non-finite profile of {label}")
        # the vertical difference bounds the normal depth from above: the (costlier) normal
        # depth only where the vertical one exceeds the rim
        if float(np.max(z0 - z)) <= MAX_WHEEL_WEAR_MM:
            continue
        depth = depth_below_mm(y, z0, z)
        k = int(np.argmax(depth))
        if depth[k] > MAX_WHEEL_WEAR_MM:
            raise WearLoopDivergedError(
                f"vehicle wear loop diverged near {mileage_km:.0f} km: {label} worn "
                f"{depth[k]:.3g} mm below the new profile at y = {y[k]:.1f} mm, more than a "
                f"wheel rim's {MAX_WHEEL_WEAR_MM:.0f} mm")


def _parameters(y: NDArray, profiles: NDArray) -> NDArray:
    """Sd, Sh, qR of every wheel, shape (3, n_wheels) [mm] (the loop's convention)."""
    flat = profiles.reshape(-1, profiles.shape[-1])
    out = np.empty((3, flat.shape[0]))
    for i, z in enumerate(flat):
        fp = flange_parameters(y, z)  # EN 15313 on the worn profile, as the wear loop
        out[:, i] = (fp.sd_mm, fp.sh_mm, fp.qr_mm)
    return out
