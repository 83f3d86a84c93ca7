"""The wheel wear loop: curve classes -> quasi-static contact -> wear law -> profile update.

One step (seeds 000, 002, 003, 004):

1. Contact per curve class with the CURRENT wheel profile
   (:mod:`wearcast.physics.class_contacts`: quasi-static bogie curving with the contact table
   rebuilt from the worn profile at each contact update; fallbacks counted in
   ``WearSimulation.contact_fallbacks``).
2. Wear of the tracked wheel (``axle``, ``side``) per class (:mod:`wearcast.physics.patch_wear`:
   the law's worn volume per metre rolled, spread semi-elliptically (global) or per element of
   the FASTSIM grid (local), the wheel's share of the law's volume).
3. Route average: depth per km = sum_k p_k depth_k (seed 003 §4.3, shares normalised to 1).
4. Smoothing of the depth (moving average or smoothing spline).
5. Step length: adaptive (the maximum depth of the step equals D_step, seed 003 eq. 2) or a
   fixed mileage (seed 000: 5,000 km).
6. Profile update along the normal (seed 004 eq. 9), flange parameters Sh (FH), Sd (FT), qR.

Alongside, the rail wear per vehicle passage of every contact update is averaged over the
steps, with the rail steps of seed 003 eq. 4 (:mod:`wearcast.physics.rail_wear_per_vehicle`);
the result is a :class:`~wearcast.physics.wear_simulation.WearSimulation`. The rail fed back
into the contact, rail step by rail step, is :mod:`wearcast.physics.rail_feedback`.

All depths in mm, mileage km, tonnage t (Mt = 1e6 t), speeds m/s inside.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal, cast, get_args

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.adaptive_step import (
    adaptive_step,
    deepest_normal_depth,
    deepest_vertical_change,
)
from wearcast.physics.class_contacts import (
    BOGIE_WHEELS,
    ClassContacts,
    class_contacts,
    class_contacts_all_wheels,
)
from wearcast.physics.patch_wear import contact_volume_basis, law_coefficients, wheel_depth_basis
from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.rail_wear_per_vehicle import (
    rail_depth_per_vehicle,
    rail_depth_per_vehicle_all_wheels,
    rail_step_rows,
)
from wearcast.physics.vehicles import BogieVehicle, vehicle_preset
from wearcast.physics.vocabulary import CurveClass, Direction
from wearcast.physics.wear_distribution import (
    Smoothing,
    apply_normal_wear,
    check_application,
    depth_below_mm,
    worn_volume_mm3,
)
from wearcast.physics.wear_laws import WearLaw
from wearcast.physics.wear_simulation import WearSimulation

#: Default lateral grid of the wheel profile [mm] (what the contact table searches, +-1 mm).
WHEEL_GRID_MM = (-70.0, 60.0, 0.2)
#: Default rail grid, rail frame [mm].
RAIL_GRID_MM = (-40.0, 40.0, 0.2)
#: Seed 003 §6: wheel threshold D_step^w = 0.2 mm; seed 000: fixed steps of 5,000 km.
SEED_003_D_STEP_MM = 0.2
SEED_000_STEP_KM = 5000.0
#: Seed 003 §6: rail threshold D_step^r = 0.8 mm.
SEED_003_RAIL_D_STEP_MM = 0.8
#: Largest wear depth a wheel can lose before the loop is declared diverged [mm]: the radial
#: wear allowance of a wheel rim (e.g. 920 -> 840 mm diameter is 40 mm of radius). ASSUMED as
#: a physical bound; a run that passes it has left any meaningful regime (typically a fixed
#: step too long for a seizure-zone rate, whose worn profile feeds back into ever faster wear).
MAX_WHEEL_WEAR_MM = 40.0


class WearLoopDivergedError(RuntimeError):
    """The wear loop produced a non-finite profile or more wear than a wheel rim allows."""


#: Progress callback: (wheel steps done, wheel steps, mileage [km]).
Progress = Callable[[int, int, float], None]


def as_loop_classes(route_classes: Any) -> list[CurveClass]:
    """Curve classes from ``vocabulary.CurveClass`` objects, objects that build one with a
    ``curve_class()`` method (``statistics.routes.RouteClass``), mappings or objects with the
    same attributes, or a route with ``classes``."""
    items = getattr(route_classes, "classes", route_classes)
    out = []
    for item in items:
        if isinstance(item, CurveClass):  # type: ignore[misc]  # mypy sees wearcast.* as Any
            out.append(item)
            continue
        if callable(getattr(item, "curve_class", None)):
            out.append(item.curve_class())
            continue
        get = item.get if isinstance(item, Mapping) else (lambda k, d=None, i=item:
                                                          getattr(i, k, d))
        radius = get("radius_m")
        if radius is not None and not np.isfinite(float(radius)):
            radius = None
        speed = get("speed_kmh")
        out.append(CurveClass(radius_m=None if radius is None else float(radius),
                              cant_mm=float(get("cant_mm", 0.0) or 0.0),
                              speed_kmh=None if speed is None else float(speed),
                              direction=cast(Direction, str(get("direction", "left") or "left")),
                              share=float(get("share", 1.0))))
    if not out:
        raise ValueError("route_classes is empty")
    total = sum(c.share for c in out)
    if not total > 0:
        raise ValueError("the class shares must sum to a positive number")
    return out


#: How the wheel steps of :class:`WearSteps` are sized: by the largest depth per step
#: (``adaptive``) or by a fixed distance (``fixed``).
StepMode = Literal["adaptive", "fixed"]
STEP_MODES: tuple[StepMode, ...] = get_args(StepMode)


@dataclass(frozen=True)
class WearSteps:
    """Step control.

    mode : ``adaptive`` (max depth per step = ``depth_per_step_mm``, seed 003) or ``fixed``
    n_steps : number of wheel steps
    depth_per_step_mm : D_step^w [mm] (adaptive)
    step_km : mileage per step [km] (fixed; seed 000: 5,000 km)
    max_step_km : cap on an adaptive step [km]
    contact_update_depth_mm : re-solve the contact only once the profile has lost this much
        (max depth) since the last update; 0 = every step (seeds 000, 003)
    max_depth_per_step_mm : fixed mode only: a step that would remove more is cut into
        sub-steps of at most this depth, each with its own contact (the step-depth limit that
        keeps sharp peaks from growing in one jump, seed 004 §4), but never more than
        ``max_substeps`` sub-steps per step (beyond that the depth limit is exceeded)
    """

    mode: str = "adaptive"
    n_steps: int = 20
    depth_per_step_mm: float = SEED_003_D_STEP_MM
    step_km: float = SEED_000_STEP_KM
    max_step_km: float = 1e6
    contact_update_depth_mm: float = 0.0
    max_depth_per_step_mm: float = 0.5
    max_substeps: int = 20

    def __post_init__(self) -> None:
        if self.mode not in STEP_MODES:
            raise ValueError(f"steps mode must be 'adaptive' or 'fixed', got {self.mode!r}")
        if self.n_steps < 1:
            raise ValueError("n_steps must be >= 1")
        if not (self.depth_per_step_mm > 0 and self.step_km > 0 and self.max_step_km > 0
                and self.max_depth_per_step_mm > 0):
            raise ValueError("depth_per_step_mm, step_km, max_step_km and "
                             "max_depth_per_step_mm must be positive")
        if self.max_substeps < 1:
            raise ValueError("max_substeps must be >= 1")
        if self.contact_update_depth_mm < 0:
            raise ValueError("contact_update_depth_mm must be >= 0")


def _grid(spec: tuple[float, float, float]) -> NDArray[np.float64]:
    lo, hi, step = spec
    return np.linspace(lo, hi, int(round((hi - lo) / step)) + 1)


def contact_key(vehicle: BogieVehicle, classes: list[CurveClass], axle: int, side: str,
                unbalanced_acceleration_m_s2: float, tangent_speed_kmh: float,
                fastsim_grid: int, y_mm: NDArray, patch_width: str = "hertz") -> Any:
    """Everything a contact update depends on besides the profile heights (hashable)."""
    key: tuple[Any, ...] = (vehicle, tuple(classes), axle, side,
                            float(unbalanced_acceleration_m_s2), float(tangent_speed_kmh),
                            int(fastsim_grid), y_mm.tobytes(), patch_width)
    try:
        hash(key)
    except TypeError:  # a vehicle with unhashable fields: fall back to its full repr
        key = (repr(vehicle),) + key[1:]
    return key


def simulate_wear(vehicle: BogieVehicle | str, route_classes: Any, *,
                  law: WearLaw | str = "archard_kth", application: str = "global",
                  steps: WearSteps | None = None, axle: int = 1, side: str = "right",
                  smoothing: Smoothing | None = None,
                  initial_profile: tuple[NDArray, NDArray] | None = None,
                  unbalanced_acceleration_m_s2: float = 0.58, tangent_speed_kmh: float = 100.0,
                  fastsim_grid: int = 20, rail_step_depth_mm: float = SEED_003_RAIL_D_STEP_MM,
                  n_rail_steps: int = 5, progress: Progress | None = None,
                  contact_cache: dict | None = None,
                  patch_width: str = "hertz",
                  rail_from_all_wheels: bool = False,
                  mean_wheel: bool = False) -> WearSimulation:
    """Simulate the wear of one wheel over a route described by curve classes.

    Parameters
    ----------
    vehicle : BogieVehicle or preset name (``vehicles.vehicle_preset``, trailer bogie)
    route_classes : curve classes (:func:`as_loop_classes` accepts CurveClass / RouteClass
        objects, mappings or a Route)
    law : WearLaw or its name (``archard_kth``, ``krause_poll``, ``usfd``, ``tau_max``)
    application : ``global`` (semi-elliptic, seed 004) or ``local`` (FASTSIM grid, seed 002)
    steps : WearSteps (default: adaptive, 20 steps of D_step = 0.2 mm, seed 003)
    axle, side : the tracked wheel (axle 1 leads)
    smoothing : Smoothing of the step depth (default moving average over 3 mm)
    initial_profile : (y_mm, z_mm) of the starting wheel; default S1002 on the default grid
    unbalanced_acceleration_m_s2 : a_nc for classes without speed [m/s^2] (seed 001: 0.58,
        seed 003: 0.8)
    tangent_speed_kmh : speed of tangent classes without speed [km/h]
    fastsim_grid : FASTSIM grid n for the local application
    rail_step_depth_mm, n_rail_steps : rail thresholds D_step^r and number of rail steps
    progress : callback(done_steps, n_steps, mileage_km)
    patch_width : ``hertz`` (default) or ``kik_piotrowski`` (:func:`class_contacts`)
    contact_cache : optional dict shared by several runs (e.g. the iterations of a calibration)
        that stores each contact update's solution keyed by everything it depends on (vehicle,
        classes, tracked wheel, operating-point options and the exact bytes of the profile);
        an update whose profile is bit-identical to a stored one reuses it, so results are
        identical with and without the cache (only solutions without fallbacks are stored,
        the others depend on the previous update)
    rail_from_all_wheels : rail wear from all four wheels of the bogie, each with its own
        patches, split into high, low and mean rail
        (:func:`rail_depth_per_vehicle_all_wheels`, with the wheel's ``application``: the
        local one per FASTSIM element on the rail too, seed 003 §4.2;
        ``rail_depth_per_vehicle_mm`` is then the mean rail of seed 003); default: from the
        tracked wheel's rail only (:func:`rail_depth_per_vehicle`, always the global
        application). The rail itself is ``vehicle.rail_profile`` (a name,
        a measured or a :class:`~wearcast.physics.rail_head_wear.WornRail`), in the contact
        table of every contact update.
    mean_wheel : wear the profile by the mean of the four wheels' depths of the bogie (both
        axles, both sides: seed 003 §4.3 averages the wear over the wheel-rail pairs into one
        mean wheel profile, whose maximum depth sets the step, eq. 2-3) instead of the tracked
        wheel's (``axle``, ``side``); needs ``rail_from_all_wheels`` (the four wheels' contacts,
        all on the current profile). Fallbacks are still counted for the tracked wheel.

    Returns
    -------
    WearSimulation
    """
    start = time.perf_counter()
    veh = vehicle_preset(vehicle) if isinstance(vehicle, str) else vehicle
    wl = WearLaw(name=law) if isinstance(law, str) else law
    st = steps or WearSteps()
    sm = smoothing or Smoothing()
    classes = as_loop_classes(route_classes)
    shares = np.array([c.share for c in classes], dtype=float)
    shares = shares / shares.sum()
    if initial_profile is None:
        y = _grid(WHEEL_GRID_MM)
        z = s1002_height_mm(y)
    else:
        y = np.asarray(initial_profile[0], dtype=float)
        z = np.asarray(initial_profile[1], dtype=float)
    check_application(application)
    if mean_wheel and not rail_from_all_wheels:
        raise ValueError("mean_wheel needs rail_from_all_wheels (the contacts of all four "
                         "wheels)")
    coeffs = law_coefficients(wl)
    rail_y = _grid(RAIL_GRID_MM)
    profiles = [z.copy()]
    mileage = [0.0]
    step_km, step_depth, basis_steps = [], [], []
    contacts: ClassContacts | None = None
    basis_km = None
    fallbacks = updates = 0
    since_update = np.inf
    rail_rates = []
    rail_sides: list[dict[str, NDArray]] = []
    all_contacts: dict[tuple[int, str], ClassContacts] | None = None
    cache_key = None if contact_cache is None else contact_key(
        veh, classes, axle, side, unbalanced_acceleration_m_s2, tangent_speed_kmh, fastsim_grid,
        y, patch_width) + (rail_from_all_wheels, mean_wheel)
    linear = Smoothing(sm.method, sm.window_mm, sm.lam, clip_negative=False)
    eps = 1e-3
    for i in range(st.n_steps):
        remaining = st.step_km if st.mode == "fixed" else None
        step_normal = np.zeros_like(z)  # normal depth removed in this step [mm]
        step_basis = None
        taken = 0.0
        while True:
            if contacts is None or since_update >= st.contact_update_depth_mm:
                key = None if contact_cache is None else (cache_key, z.tobytes())
                hit = None if key is None or contact_cache is None else contact_cache.get(key)
                if hit is not None and rail_from_all_wheels:
                    all_contacts, fb = hit, 0
                    contacts = all_contacts[(axle, side)]
                elif hit is not None:
                    contacts, fb = hit, 0
                elif rail_from_all_wheels:
                    all_contacts, fb = class_contacts_all_wheels(
                        veh, classes, y, z, wheels=BOGIE_WHEELS,
                        unbalanced_acceleration_m_s2=unbalanced_acceleration_m_s2,
                        tangent_speed_kmh=tangent_speed_kmh, fastsim_grid=fastsim_grid,
                        previous=all_contacts, patch_width=patch_width)
                    # Fallbacks of the tracked wheel only, as without the option.
                    fb = fb // len(BOGIE_WHEELS)
                    contacts = all_contacts[(axle, side)]
                    if key is not None and contact_cache is not None and fb == 0:
                        contact_cache[key] = all_contacts
                else:
                    contacts, fb = class_contacts(
                        veh, classes, y, z, axle=axle, side=side,
                        unbalanced_acceleration_m_s2=unbalanced_acceleration_m_s2,
                        tangent_speed_kmh=tangent_speed_kmh, fastsim_grid=fastsim_grid,
                        previous=contacts, patch_width=patch_width)
                    if key is not None and contact_cache is not None and fb == 0:
                        contact_cache[key] = contacts
                fallbacks += fb
                updates += 1
                since_update = 0.0
                if mean_wheel:
                    assert all_contacts is not None
                    # seed 003 §4.3: the average over the wheel-rail pairs, one mean wheel
                    per_class = np.mean([wheel_depth_basis(all_contacts[w], wl, y, application,
                                                           fastsim_grid, veh.friction)
                                         for w in BOGIE_WHEELS], axis=0)  # mm per m rolled
                else:
                    per_class = wheel_depth_basis(contacts, wl, y, application, fastsim_grid,
                                                  veh.friction)            # mm per m rolled
                # Smooth each basis row linearly; clipping acts on the sum below.
                basis_km = linear.apply(np.einsum("c,cbn->bn", shares, per_class) * 1000.0, y)
                if all_contacts is not None:
                    sides = rail_depth_per_vehicle_all_wheels(
                        all_contacts, wl, classes, shares, rail_y, application=application,
                        fastsim_grid=fastsim_grid, friction=veh.friction)
                    rail_sides.append(sides)
                    rail_rates.append(sides["mean"])
                else:
                    rail_rates.append(rail_depth_per_vehicle(contacts, wl, shares, rail_y))
            assert basis_km is not None
            rate = basis_km.T @ coeffs                                     # mm/km, normal
            if sm.clip_negative:
                rate = np.maximum(rate, 0.0)
            if remaining is not None:
                # Fixed step, cut into sub-steps of at most max_depth_per_step_mm of vertical
                # change (a numerical limit on how far one contact solution is extrapolated)
                peak = deepest_vertical_change(rate, np.gradient(z, y))
                ds = remaining if peak <= 0 else min(remaining, max(
                    st.max_depth_per_step_mm / peak, st.step_km / st.max_substeps))
            else:
                # seed 003 eq. 2: the deepest point loses D_step^w normal to the profile (at
                # most MAX_VERTICAL_STEP_FACTOR D_step of vertical change, adaptive_step)
                ds = min(adaptive_step(rate, st.depth_per_step_mm, np.gradient(z, y)),
                         st.max_step_km)
            z_new = apply_normal_wear(y, z, rate * ds)
            step_normal += rate * ds
            # Vertical wear per unit coefficient, linearised (Jacobian of eq. 9).
            sub = np.stack([(z - apply_normal_wear(y, z, row * ds * eps)) / eps
                            for row in basis_km])
            step_basis = sub if step_basis is None else step_basis + sub
            since_update += deepest_normal_depth(rate * ds)
            _check_diverged(y, z_new, profiles[0], i, mileage[-1] + taken + ds)
            z = z_new
            taken += ds
            if remaining is None:
                break
            remaining -= ds
            if remaining <= 1e-9 * st.step_km:
                break
        basis_steps.append(step_basis)
        step_depth.append(deepest_normal_depth(step_normal))
        step_km.append(taken)
        profiles.append(z.copy())
        mileage.append(mileage[-1] + taken)
        if progress is not None:
            progress(i + 1, st.n_steps, mileage[-1])
    prof = np.array(profiles)
    params = [flange_parameters(y, p) for p in prof]  # EN 15313, from the worn tread
    r0_mm = veh.wheel_radius_m * 1000.0
    volumes = np.array([worn_volume_mm3(y, prof[0], p, r0_mm) for p in prof])
    rail_rate = np.mean(rail_rates, axis=0)
    rail_steps = rail_step_rows(rail_rate, rail_step_depth_mm, n_rail_steps, veh)
    return WearSimulation(
        y_mm=y, profiles_mm=prof, mileage_km=np.array(mileage),
        sh_mm=np.array([p.sh_mm for p in params]), sd_mm=np.array([p.sd_mm for p in params]),
        qr_mm=np.array([p.qr_mm for p in params]), step_km=np.array(step_km),
        step_max_depth_mm=np.array(step_depth), worn_volume_mm3=volumes,
        contact_fallbacks=fallbacks, contact_updates=updates,
        elapsed_s=time.perf_counter() - start, law=wl.name, application=application,
        n_classes=len(classes), rail_y_mm=rail_y, rail_depth_per_vehicle_mm=rail_rate,
        rail_steps=rail_steps, step_basis_mm=np.array(basis_steps), coefficients=coeffs,
        rail_high_depth_per_vehicle_mm=(np.mean([r["high"] for r in rail_sides], axis=0)
                                        if rail_sides else None),
        rail_low_depth_per_vehicle_mm=(np.mean([r["low"] for r in rail_sides], axis=0)
                                       if rail_sides else None),
        rail=veh.rail_profile, high_rail=veh.high_rail_profile, low_rail=veh.low_rail_profile,
        rail_update_depths_mm=(np.array([[r["mean"], r["high"], r["low"]] for r in rail_sides])
                               if rail_sides else None))


def _check_diverged(y_mm: NDArray, z_mm: NDArray, z_initial_mm: NDArray, step: int,
                    mileage_km: float) -> None:
    """Raise :class:`WearLoopDivergedError` on a non-finite profile or wear beyond
    :data:`MAX_WHEEL_WEAR_MM` normal to the new profile (``depth_below_mm``: a flange face worn
    sideways is not a rim worn through; a worn profile is never returned from a diverged
    run)."""
    if not np.all(np.isfinite(z_mm)):
        raise WearLoopDivergedError(
            f"wear loop diverged in step {step + 1} near {mileage_km:.0f} km: non-finite "
            "profile; use shorter steps (adaptive mode or a smaller step_km)")
    # the vertical difference bounds the depth normal to the new profile from above: the
    # (costlier) normal depth only where the vertical one exceeds the rim
    if float(np.max(z_initial_mm - z_mm)) <= MAX_WHEEL_WEAR_MM:
        return
    depth = float(np.max(depth_below_mm(y_mm, z_initial_mm, z_mm)))
    if depth > MAX_WHEEL_WEAR_MM:
        raise WearLoopDivergedError(
            f"wear loop diverged in step {step + 1} near {mileage_km:.0f} km: {depth:.3g} mm "
            f"of wear exceeds a wheel rim's {MAX_WHEEL_WEAR_MM:.0f} mm; use shorter steps "
            "(adaptive mode or a smaller step_km) or check the wear coefficients")


def class_wear_rates(vehicle: BogieVehicle | str, route_classes: Any,
                     law: WearLaw | str = "archard_kth", *, axle: int = 1, side: str = "right",
                     unbalanced_acceleration_m_s2: float = 0.58,
                     tangent_speed_kmh: float = 100.0) -> tuple[ClassContacts, NDArray]:
    """Worn volume per metre rolled of the tracked wheel per class and patch [mm^3/m] with the
    new S1002 profile (seed 004 Fig. 6: wear rate per curve), and the contacts behind it."""
    veh = vehicle_preset(vehicle) if isinstance(vehicle, str) else vehicle
    wl = WearLaw(name=law) if isinstance(law, str) else law
    y = _grid(WHEEL_GRID_MM)
    contacts, _ = class_contacts(veh, as_loop_classes(route_classes), y, s1002_height_mm(y),
                                 axle=axle, side=side,
                                 unbalanced_acceleration_m_s2=unbalanced_acceleration_m_s2,
                                 tangent_speed_kmh=tangent_speed_kmh)
    return contacts, contact_volume_basis(contacts, wl) @ law_coefficients(wl)
