"""The wear loop: route classes -> quasi-static contact -> wear law -> profile update, repeated.

One step (seeds 000, 002, 003, 004):

1. Contact per curve class with the CURRENT wheel profile: the quasi-static bogie curving of
   :mod:`wearcast.physics.curving` (contact table rebuilt from the worn profile each time the
   contact is updated; classes of the same radius, cant and speed share one solution; a
   right-hand class is the mirror image of a left-hand one, so the tracked wheel of a right
   curve is the opposite wheel of the left-curve solution). If the batched solve does not
   converge for some class, that class is solved alone; if it still fails, the class keeps the
   contact of its previous contact update, or, on the first update, the contact of the
   converged operating point nearest in curvature (then cant) -- the stated simpler contact;
   both are counted in ``WearSimulation.contact_fallbacks``. If no class converges,
   :class:`~wearcast.physics.curving.CurvingConvergenceError` is raised.
2. Wear of the tracked wheel (``axle``, ``side``) per class: the law's worn volume per metre
   rolled (:mod:`wearcast.physics.wear_laws`) spread with the semi-elliptic distribution
   (global) or per element of the FASTSIM grid (local; every law)
   (:mod:`wearcast.physics.wear_distribution`); the wheel's share of the law's volume by the
   law's definition (``wear_laws.wheel_rail_split``: half for seed 004's wheel-and-rail KTH
   coefficients, all of it for USFD).
3. Route average: depth per km = sum_k p_k depth_k (seed 003 §4.3, shares normalised to 1).
4. Smoothing of the depth (moving average or smoothing spline).
5. Step length: adaptive (the maximum depth of the step equals D_step, seed 003 eq. 2) or a
   fixed mileage (seed 000: 5,000 km).
6. Profile update along the normal (seed 004 eq. 9), flange parameters Sh (FH), Sd (FT), qR.

Rail wear (seed 003 §4.3, item 2): rail wear does not grow with the vehicle's mileage but with
the number of vehicles N (tonnage N M_v). The rail of the tracked wheel's side in each class
is worn by both axles of the bogie and by two bogies per vehicle; per vehicle passage, the
cross-section area removed is the volume per metre rolled / 1000 mm, spread semi-elliptically on
the rail's own lateral coordinate, averaged over classes with p_k. Rail steps: N_step =
D_step^r / max(depth per vehicle) (seed 003 eq. 4). With ``rail_from_all_wheels`` the rail
wear comes from all four wheels of the bogie, each with its own patches (no scaling), and is
split into the high rail (the outer rail of each curve), the low rail and the mean rail of
seed 003 (one mean rail profile for all rails, §4.3).

Rail fed back into the contact (seed 003 §4.3 and §6.1, item 2, :func:`simulate_rail_steps`):
for each rail step j the wheel evolves from new over its n_sw wheel steps on the rail r_j (the
contact table rebuilt with r_j and the current wheel at every contact update); the mean rail's
depth per vehicle, averaged over those wheel steps (the seed's arithmetic mean of the virtual
rail profiles), is scaled to D_step^r (eq. 4: N_step = D_step^r / max depth) and removed
along the rail's normal, giving r_{j+1} (:class:`WornRail`). km_tot^j (seed 003 Tables 5, 8) is
the mileage at the end of the wheel evolution on r_j.

All depths in mm, mileage km, tonnage t (Mt = 1e6 t), speeds m/s inside.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeAlias, cast

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.contact.fastsim import fastsim
from wearcast.physics.curving import (
    SHEAR_MODULUS_MPA,
    CurvingConvergenceError,
    CurvingResult,
    build_contact_table,
    conformal_half_width_mm,
    curve_case,
    solve_curving_cases_or_none,
)
from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.physics.profiles.rails import RailShape
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.rail_head_wear import RailHeadWear, WornRail, wear_rail
from wearcast.physics.vehicles import GRAVITY_M_S2, BogieVehicle, vehicle_preset
from wearcast.physics.vocabulary import CurveClass, Direction
from wearcast.physics.wear_distribution import (
    Smoothing,
    apply_normal_wear,
    local_archard_depth,
    local_rate_depth,
    semi_elliptic_depth,
    worn_volume_mm3,
)
from wearcast.physics.wear_laws import (
    WearLaw,
    archard_basis,
    element_depth_rate_mm_per_m,
    krause_poll_rate,
    tau_max_rate,
    usfd_rate,
    wheel_rail_split,
)
from wearcast.physics.wear_measures import rigid_sliding_velocity_m_s

#: Default lateral grid of the wheel profile [mm] (what the contact table searches, +-1 mm).
WHEEL_GRID_MM = (-70.0, 60.0, 0.2)
#: Default rail grid, rail frame [mm].
RAIL_GRID_MM = (-40.0, 40.0, 0.2)
#: Seed 003 §6: wheel threshold D_step^w = 0.2 mm; seed 000: fixed steps of 5,000 km.
SEED_003_D_STEP_MM = 0.2
SEED_000_STEP_KM = 5000.0
#: Seed 003 §6: rail threshold D_step^r = 0.8 mm.
SEED_003_RAIL_D_STEP_MM = 0.8
#: Patch-width models of :func:`class_contacts`.
PATCH_WIDTHS = ("hertz", "kik_piotrowski")
#: Largest wear depth a wheel can lose before the loop is declared diverged [mm]: the radial
#: wear allowance of a wheel rim (e.g. 920 -> 840 mm diameter is 40 mm of radius). ASSUMED as
#: a physical bound; a run that passes it has left any meaningful regime (typically a fixed
#: step too long for a seizure-zone rate, whose worn profile feeds back into ever faster wear).
MAX_WHEEL_WEAR_MM = 40.0


class WearLoopDivergedError(RuntimeError):
    """The wear loop produced a non-finite profile or more wear than a wheel rim allows."""

Progress = Callable[[int, int, float], None]


#: A curve class of a route; the same class the curve-radius tables use.
LoopClass: TypeAlias = CurveClass


def as_loop_classes(route_classes: Any) -> list[LoopClass]:
    """Curve classes from LoopClass objects, mappings, objects with the same attributes
    (``vocabulary.CurveClass``, ``statistics.routes.RouteClass``) or a route with ``classes``."""
    items = getattr(route_classes, "classes", route_classes)
    out = []
    for item in items:
        if isinstance(item, CurveClass):  # type: ignore[misc]  # mypy sees wearcast.* as Any
            out.append(item)
            continue
        get = item.get if isinstance(item, Mapping) else (lambda k, d=None, i=item:
                                                          getattr(i, k, d))
        radius = get("radius_m")
        if radius is not None and not np.isfinite(float(radius)):
            radius = None
        speed = get("speed_kmh")
        out.append(LoopClass(radius_m=None if radius is None else float(radius),
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
        if self.mode not in ("adaptive", "fixed"):
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


@dataclass(frozen=True)
class ClassContacts:
    """Contacts of the tracked wheel per class, shape (n_class, n_slot) (patch slots of the
    curving model, field side first).

    normal_n [N], wheel_y_mm, rail_y_mm [mm], angle_rad, rolling_radius_mm, a_mm, b_mm, xi,
    eta [-], phi_per_mm, fx_n, fy_n, mz_nmm, tau_max_mpa, t_gamma_n, loaded (bool); speed_m_s
    (n_class,). Rail-side arrays of both axles of the bogie on the same rail: rail_* with shape
    (n_class, 2 axles, n_slot). ``states``: the last curving equilibrium per operating point
    (the warm start of the next update's failed points).
    """

    normal_n: NDArray
    wheel_y_mm: NDArray
    rail_y_mm: NDArray
    angle_rad: NDArray
    rolling_radius_mm: NDArray
    a_mm: NDArray
    b_mm: NDArray
    xi: NDArray
    eta: NDArray
    phi_per_mm: NDArray
    fx_n: NDArray
    fy_n: NDArray
    mz_nmm: NDArray
    tau_max_mpa: NDArray
    t_gamma_n: NDArray
    loaded: NDArray
    speed_m_s: NDArray
    rail_axles: dict = field(default_factory=dict)
    states: dict = field(default_factory=dict)


_CONTACT_FIELDS = ("normal_force_n", "wheel_y_mm", "rail_y_mm", "contact_angle_rad",
                   "rolling_radius_m", "a_mm", "b_mm", "xi", "eta", "phi_per_mm", "fx_n", "fy_n",
                   "mz_nmm", "tau_max_mpa", "t_gamma_n", "in_contact")


_RAIL_FIELDS = ("normal_force_n", "rail_y_mm", "contact_angle_rad", "b_mm", "rolling_radius_m",
                "in_contact")
_FIELD_NAMES = {"normal_force_n": "normal_n", "wheel_y_mm": "wheel_y_mm", "rail_y_mm": "rail_y_mm",
                "contact_angle_rad": "angle_rad", "a_mm": "a_mm", "b_mm": "b_mm", "xi": "xi",
                "eta": "eta", "phi_per_mm": "phi_per_mm", "fx_n": "fx_n", "fy_n": "fy_n",
                "mz_nmm": "mz_nmm", "tau_max_mpa": "tau_max_mpa", "t_gamma_n": "t_gamma_n",
                "in_contact": "loaded"}


def _operating_point(c: LoopClass, unbalanced_acceleration_m_s2: float,
                     tangent_speed_kmh: float) -> tuple:
    if c.is_tangent:
        v = (c.speed_kmh if c.speed_kmh is not None else tangent_speed_kmh) / 3.6
        return (None, 0.0, round(v, 9))
    speed_m_s = None if c.speed_kmh is None else c.speed_kmh / 3.6
    assert c.radius_m is not None  # not tangent here
    radius_m = float(c.radius_m)
    case = curve_case(radius_m, c.cant_mm, speed_m_s, "left", unbalanced_acceleration_m_s2)
    return (radius_m, float(c.cant_mm), round(case.speed_m_s, 9))


def _curvature(point: tuple) -> float:
    return 0.0 if point[0] is None else 1.0 / point[0]


def _solve_points(vehicle: BogieVehicle, points: list[tuple], table, fastsim_grid: int,
                  warm: dict | None = None, warm_first: bool = False
                  ) -> list[CurvingResult | None]:
    """Batched curving of the operating points in one batch; a point that does not converge
    from centred wheelsets is retried from its last equilibrium (``warm``: operating point ->
    ``CurvingResult.state`` on the previous profile) if it has one, else it is None (the caller
    falls back to a neighbour or the previous contact). ``warm_first``: start every point that
    has a last equilibrium from it (Newton at full load, no continuation) and retry the failures
    by continuation from centred wheelsets (faster when the profile changed little)."""
    cases = [curve_case(r, cant, v, "left") for r, cant, v in points]
    labels = [(r, "left", cant) for r, cant, _ in points]
    first = None
    if warm_first and warm:
        first = [warm.get(p) for p in points]
    out = solve_curving_cases_or_none(vehicle, cases, labels, table,
                                      fastsim_grid=fastsim_grid, initial_states=first)
    if first is not None:
        retry = [i for i, r in enumerate(out) if r is None and first[i] is not None]
        init: list = [None] * len(retry)
    else:
        retry = [i for i, r in enumerate(out) if r is None and points[i] in (warm or {})]
        init = [(warm or {})[points[i]] for i in retry]
    if retry:
        again = solve_curving_cases_or_none(
            vehicle, [cases[i] for i in retry], [labels[i] for i in retry], table,
            fastsim_grid=fastsim_grid, initial_states=init)
        for i, res in zip(retry, again, strict=True):
            out[i] = res
    return out


#: The four wheels of a bogie, (axle, side); axle 1 leads.
BOGIE_WHEELS: tuple[tuple[int, str], ...] = ((1, "left"), (1, "right"), (2, "left"),
                                             (2, "right"))


def class_contacts(vehicle: BogieVehicle, classes: Sequence[LoopClass], y_mm: NDArray,
                   z_mm: NDArray, *, axle: int = 1, side: str = "right",
                   unbalanced_acceleration_m_s2: float = 0.58, tangent_speed_kmh: float = 100.0,
                   fastsim_grid: int = 20, previous: ClassContacts | None = None,
                   patch_width: str = "hertz") -> tuple[ClassContacts, int]:
    """Quasi-static contacts of the tracked wheel per class for the wheel profile z(y).

    patch_width : ``hertz`` (the curving model's ellipse, from the gap smoothed over 2 mm) or
        ``kik_piotrowski`` (the lateral semi-axis widened to the extent of the unsmoothed gap
        within 0.55 x the approach, ``curving.conformal_half_width_mm``: conformal flange-root
        patches become wide and mild; the equilibrium and creepages are unchanged)

    Returns (contacts, number of classes that kept the previous contact). Raises
    CurvingConvergenceError when a class fails and there is no previous contact.
    """
    if axle not in (1, 2) or side not in ("left", "right"):
        raise ValueError("axle must be 1 or 2 and side 'left' or 'right'")
    out, fallbacks = class_contacts_all_wheels(
        vehicle, classes, y_mm, z_mm, wheels=((axle, side),),
        unbalanced_acceleration_m_s2=unbalanced_acceleration_m_s2,
        tangent_speed_kmh=tangent_speed_kmh, fastsim_grid=fastsim_grid,
        previous=None if previous is None else {(axle, side): previous},
        patch_width=patch_width)
    return out[(axle, side)], fallbacks


def class_contacts_all_wheels(vehicle: BogieVehicle, classes: Sequence[LoopClass],
                              y_mm: NDArray, z_mm: NDArray, *,
                              wheels: Sequence[tuple[int, str]] = BOGIE_WHEELS,
                              unbalanced_acceleration_m_s2: float = 0.58,
                              tangent_speed_kmh: float = 100.0, fastsim_grid: int = 20,
                              previous: Mapping[tuple[int, str], ClassContacts] | None = None,
                              patch_width: str = "hertz", warm_first: bool = False
                              ) -> tuple[dict[tuple[int, str], ClassContacts], int]:
    """:func:`class_contacts` of several wheels of the bogie from ONE curving solve per
    operating point (all four wheels by default). ``previous``: per wheel the contacts of the
    previous update (fallback and warm start); ``warm_first``: see :func:`_solve_points`.
    Returns ({(axle, side): contacts}, class fallbacks summed over the wheels)."""
    for axle, side in wheels:
        if axle not in (1, 2) or side not in ("left", "right"):
            raise ValueError("axle must be 1 or 2 and side 'left' or 'right'")
    if patch_width not in PATCH_WIDTHS:
        raise ValueError(f"patch_width must be one of {', '.join(PATCH_WIDTHS)}, "
                         f"got {patch_width!r}")
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    table = build_contact_table(lambda q: np.interp(q, y, z), vehicle.rail_profile,
                                vehicle.rail_inclination, vehicle.wheel_radius_m)
    points = [_operating_point(c, unbalanced_acceleration_m_s2, tangent_speed_kmh)
              for c in classes]
    unique = sorted(set(points), key=lambda p: (p[0] is None, p[0] or 0.0, p[1], p[2]))
    prev = dict(previous or {})
    warm: dict | None = None
    for pc in prev.values():
        warm = {**(warm or {}), **pc.states}
    solved = dict(zip(unique, _solve_points(vehicle, unique, table, fastsim_grid, warm,
                                            warm_first), strict=True))
    states = dict(warm or {})
    states.update({p: r.state for p, r in solved.items() if r is not None})
    good = [p for p, r in solved.items() if r is not None]
    if not good and not prev:
        raise CurvingConvergenceError("quasi-static curving did not converge for any class",
                                      np.inf, float("nan"))
    out = {}
    fallbacks = 0
    for wheel in wheels:
        out[wheel], fb = _wheel_contacts(vehicle, classes, points, solved, good, y, z, wheel,
                                         prev.get(wheel), patch_width, states)
        fallbacks += fb
    return out, fallbacks


def _wheel_contacts(vehicle: BogieVehicle, classes: Sequence[LoopClass], points: list,
                    solved: dict, good: list, y: NDArray, z: NDArray, wheel: tuple[int, str],
                    previous: ClassContacts | None, patch_width: str, states: dict
                    ) -> tuple[ClassContacts, int]:
    """Contacts of one wheel per class from the solved operating points (fallbacks counted)."""
    axle, side = wheel
    ai = axle - 1
    n = len(classes)
    slots = [np.shape(r.normal_force_n)[-1] for r in solved.values() if r is not None]
    if previous is not None:
        slots.append(previous.normal_n.shape[-1])
    n_slot = max(slots) if slots else 2
    data = {f: np.zeros((n, n_slot)) for f in _CONTACT_FIELDS}
    rail = {f: np.zeros((n, 2, n_slot)) for f in _RAIL_FIELDS}
    speed = np.zeros(n)
    fallbacks = 0
    if not good and previous is None:
        raise CurvingConvergenceError("quasi-static curving did not converge for any class",
                                      np.inf, float("nan"))
    for k, (c, p) in enumerate(zip(classes, points, strict=True)):
        res = solved[p]
        if res is None and previous is None:
            # Nearest converged operating point in curvature (then cant) of the same profile.
            fallbacks += 1
            res = solved[min(good, key=lambda q: (abs(_curvature(q) - _curvature(p)),
                                                  abs(q[1] - p[1])))]
        # Mirror: the tracked wheel of a right curve is the opposite wheel of the left curve.
        own = 0 if side == "left" else 1
        si = own if (c.direction == "left" or c.is_tangent) else 1 - own
        if res is None:
            assert previous is not None
            fallbacks += 1
            m = previous.normal_n.shape[-1]
            for f, name in _FIELD_NAMES.items():
                data[f][k, :m] = getattr(previous, name)[k]
            data["rolling_radius_m"][k, :m] = previous.rolling_radius_mm[k] / 1000.0
            for f in rail:
                rail[f][k, :, :m] = previous.rail_axles[f][k]
            speed[k] = previous.speed_m_s[k]
            continue
        m = np.shape(res.normal_force_n)[-1]
        for f in _CONTACT_FIELDS:
            data[f][k, :m] = np.asarray(getattr(res, f))[ai, si]
        for f in rail:
            rail[f][k, :, :m] = np.asarray(getattr(res, f))[:, si]
        speed[k] = res.speed_m_s
    loaded = data["in_contact"].astype(bool) & (data["normal_force_n"] > 1.0)
    if patch_width == "kik_piotrowski":
        data["b_mm"] = np.where(loaded, conformal_half_width_mm(
            y, z, vehicle.rail_profile, vehicle.rail_inclination, data["wheel_y_mm"],
            data["rail_y_mm"], np.where(loaded, data["normal_force_n"], 0.0), data["a_mm"],
            data["b_mm"]), data["b_mm"])
    rail["in_contact"] = rail["in_contact"].astype(bool) & (rail["normal_force_n"] > 1.0)
    return ClassContacts(
        normal_n=data["normal_force_n"], wheel_y_mm=data["wheel_y_mm"],
        rail_y_mm=data["rail_y_mm"], angle_rad=data["contact_angle_rad"],
        rolling_radius_mm=data["rolling_radius_m"] * 1000.0, a_mm=data["a_mm"],
        b_mm=data["b_mm"], xi=data["xi"], eta=data["eta"], phi_per_mm=data["phi_per_mm"],
        fx_n=data["fx_n"], fy_n=data["fy_n"], mz_nmm=data["mz_nmm"],
        tau_max_mpa=data["tau_max_mpa"], t_gamma_n=data["t_gamma_n"], loaded=loaded,
        speed_m_s=speed, rail_axles=rail, states=states), fallbacks


def contact_volume_basis(contacts: ClassContacts, law: WearLaw) -> NDArray[np.float64]:
    """Worn volume per metre rolled of each patch, as a basis: shape (n_class, n_slot, n_basis)
    [mm^3/m]; n_basis = 4 (zones) for Archard/KTH, else 1 (coefficient 1)."""
    c = contacts
    v = np.broadcast_to(c.speed_m_s[:, None], c.normal_n.shape)
    area = np.pi * np.where(c.loaded, c.a_mm * c.b_mm, 1.0)
    if law.name == "archard_kth":
        vs = rigid_sliding_velocity_m_s(v, c.xi, c.eta)
        basis = archard_basis(c.normal_n, vs, v, c.normal_n / area, law.archard)
    elif law.name == "krause_poll":
        basis = krause_poll_rate(c.t_gamma_n, v, area)[..., None]
    elif law.name == "usfd":
        jump: Any = law.usfd_jump  # 'continuous' or 'as_printed', checked by WearLaw
        basis = usfd_rate(c.t_gamma_n, area, jump)[..., None]
    else:
        basis = tau_max_rate(c.tau_max_mpa, area, law.tau_coefficient_mm_per_m_mpa,
                             law.tau_threshold_mpa)[..., None]
    return np.where(c.loaded[..., None], basis, 0.0)


def law_coefficients(law: WearLaw) -> NDArray[np.float64]:
    """Coefficients that multiply the basis (the effective KTH zone coefficients, or [1])."""
    return law.archard.effective_coefficients if law.name == "archard_kth" else np.ones(1)


def wheel_depth_basis(contacts: ClassContacts, law: WearLaw, y_grid_mm: NDArray,
                      application: str = "global", fastsim_grid: int = 20,
                      friction: float = 0.35) -> NDArray[np.float64]:
    """Normal depth of the WHEEL per metre rolled per class and basis function:
    (n_class, n_basis, n) [mm/m].

    ``application``: ``global`` (semi-elliptic, seed 004 eqs. 3-5) or ``local`` (FASTSIM grid:
    Archard/KTH per zone, seed 002 eqs. 4-5; USFD, Krause-Poll and tau_max per element,
    seed 003 §4.2, ``wear_laws.element_depth_rate_mm_per_m``). The wheel's share of the law's
    volume (``wear_laws.wheel_rail_split``) is applied here.
    """
    wheel_share, _ = wheel_rail_split(law)
    c = contacts
    n_class = c.normal_n.shape[0]
    safe_b = np.where(c.loaded, c.b_mm, 1.0)
    if application == "global":
        vol = contact_volume_basis(c, law)                     # (n_class, 2, nb) per m
        safe_r = np.where(c.loaded, c.rolling_radius_mm, 1.0)
        shape = semi_elliptic_depth(y_grid_mm, c.wheel_y_mm, safe_b, 1.0,
                                    safe_r, c.angle_rad)  # (n_class, n_slot, n)
        return wheel_share * np.einsum("csb,csn->cbn", vol, shape)
    if application != "local":
        raise ValueError(f"application must be 'global' or 'local', got {application!r}")
    n_basis = 4 if law.name == "archard_kth" else 1
    out = np.zeros((n_class, n_basis, np.size(y_grid_mm)))
    idx = np.nonzero(c.loaded)
    if idx[0].size == 0:
        return out
    xi, eta, phi, a_mm, b_mm, normal_n = (np.asarray(getattr(c, f))[idx] for f in (
        "xi", "eta", "phi_per_mm", "a_mm", "b_mm", "normal_n"))
    fs = fastsim(xi, eta, phi, a_mm, b_mm, normal_n, friction, SHEAR_MODULUS_MPA,
                 n_x=fastsim_grid, n_y=fastsim_grid)
    if law.name == "archard_kth":
        basis = local_archard_depth(fs, c.speed_m_s[idx[0]], c.wheel_y_mm[idx],
                                    c.rolling_radius_mm[idx], c.angle_rad[idx], y_grid_mm,
                                    law.archard)
    else:
        v = c.speed_m_s[idx[0]][:, None, None]
        rate = element_depth_rate_mm_per_m(law, fs.shear_traction_mpa,
                                           np.hypot(fs.sx, fs.sy), fs.pn_mpa, v)
        basis = local_rate_depth(fs, rate, c.wheel_y_mm[idx], c.rolling_radius_mm[idx],
                                 c.angle_rad[idx], y_grid_mm)[:, None, :]
    np.add.at(out, idx[0], basis)
    return wheel_share * out


def rail_depth_per_vehicle(contacts: ClassContacts, law: WearLaw, shares: NDArray,
                           rail_grid_mm: NDArray, bogies_per_vehicle: int = 2
                           ) -> NDArray[np.float64]:
    """Rail normal depth per vehicle passage, class-averaged with p_k (seed 003 eq. 4) [mm].

    The rail's share of the law's volume is ``wear_laws.wheel_rail_split``. Both axles of the
    bogie on the tracked wheel's rail; the per-wheel volume rate is taken
    from the tracked wheel's law basis scaled by the axle's normal force share (a first-order
    approximation: the trailing axle's creepages are not recomputed for the rail).
    """
    _, rail_share = wheel_rail_split(law)
    vol = rail_share * contact_volume_basis(contacts, law) @ law_coefficients(
        law)                                                            # (n_class, slot) mm^3/m
    r = contacts.rail_axles
    lead_n = np.where(contacts.normal_n > 0, contacts.normal_n, 1.0)
    scale = r["normal_force_n"] / lead_n[:, None, :]                # (n_class, axle, slot)
    area_per_pass = (vol[:, None, :] * np.where(contacts.loaded[:, None, :], scale, 0.0)
                     / 1000.0)                                          # mm^2 per passage
    b = np.where(r["in_contact"], r["b_mm"], 1.0)
    # Unit radius 1/(2 pi) makes semi_elliptic_depth spread "volume" = area as a depth on y.
    depth = semi_elliptic_depth(rail_grid_mm, r["rail_y_mm"], b,
                                np.where(r["in_contact"], area_per_pass, 0.0),
                                1.0 / (2.0 * np.pi), r["contact_angle_rad"])
    per_class = bogies_per_vehicle * depth.sum(axis=(1, 2))
    return np.einsum("c,cn->n", shares, per_class)


def rail_depth_per_vehicle_all_wheels(contacts: Mapping[tuple[int, str], ClassContacts],
                                      law: WearLaw, classes: Sequence[LoopClass],
                                      shares: NDArray, rail_grid_mm: NDArray,
                                      bogies_per_vehicle: int = 2
                                      ) -> dict[str, NDArray[np.float64]]:
    """Rail normal depth per vehicle passage from every wheel of the bogie [mm], class-averaged
    with p_k (seed 003 eq. 4), on the rail grid of the inclined rail frame.

    Each wheel's patches wear the rail under it with the rail's share of the law's volume
    (``wear_laws.wheel_rail_split``): per passage the cross-section area removed is the patch
    volume per metre rolled / 1000 mm, spread semi-elliptically at the patch's rail position.
    ``high``: the outer rail of each curve (the wheels on that side); ``low``: the inner rail;
    on tangent track both rails take the mean of the two sides. ``mean``: (high + low) / 2,
    the rail of seed 003's single mean rail profile (every rail of a line is the high rail of
    some curves and the low rail of the others). Returns {"high", "low", "mean"}: (n_rail,).
    """
    _, rail_share = wheel_rail_split(law)
    coeffs = law_coefficients(law)
    n_class = len(classes)
    side_depth = {s: np.zeros((n_class, np.size(rail_grid_mm))) for s in ("left", "right")}
    for (_, side), c in contacts.items():
        vol = rail_share * contact_volume_basis(c, law) @ coeffs          # (n_class, slot)
        area = np.where(c.loaded, vol, 0.0) / 1000.0                       # mm^2 per passage
        b = np.where(c.loaded, c.b_mm, 1.0)
        # Unit radius 1/(2 pi): semi_elliptic_depth spreads "volume" = area on the rail's y.
        depth = semi_elliptic_depth(rail_grid_mm, c.rail_y_mm, b, area, 1.0 / (2.0 * np.pi),
                                    c.angle_rad)
        side_depth[side] += depth.sum(axis=1)
    high = np.zeros_like(side_depth["left"])
    low = np.zeros_like(high)
    for k, cls in enumerate(classes):
        if cls.is_tangent:
            high[k] = low[k] = 0.5 * (side_depth["left"][k] + side_depth["right"][k])
            continue
        outer = "right" if cls.direction == "left" else "left"
        inner = "left" if outer == "right" else "right"
        high[k], low[k] = side_depth[outer][k], side_depth[inner][k]
    h = bogies_per_vehicle * np.einsum("c,cn->n", shares, high)
    lo = bogies_per_vehicle * np.einsum("c,cn->n", shares, low)
    return {"high": h, "low": lo, "mean": 0.5 * (h + lo)}


@dataclass(frozen=True)
class WearSimulation:
    """Result of :func:`simulate_wear`.

    y_mm (n,), profiles_mm (n_steps+1, n) wheel profile z after each step (row 0: initial),
    mileage_km (n_steps+1,), sh_mm / sd_mm / qr_mm (n_steps+1,) flange parameters (FH, FT, qR),
    step_km (n_steps,), step_max_depth_mm (n_steps,), worn_volume_mm3 (n_steps+1,) (seed 002
    eq. 8 against the initial profile), contact_fallbacks, contact_updates, elapsed_s, law,
    application, rail_y_mm, rail_depth_per_vehicle_mm (n_rail,), rail_steps (rail step ->
    vehicles, tonnage [t], max depth), rail_high/low_depth_per_vehicle_mm (n_rail,) with
    ``rail_from_all_wheels`` (else None), rail (the rail the wheel ran on: a name or a rail
    shape), step_basis_mm (n_steps, n_basis, n): vertical-equivalent
    depth of each step per unit basis coefficient (the zone coefficients for Archard/KTH), used
    by the exact calibration; coefficients (n_basis,).
    """

    y_mm: NDArray
    profiles_mm: NDArray
    mileage_km: NDArray
    sh_mm: NDArray
    sd_mm: NDArray
    qr_mm: NDArray
    step_km: NDArray
    step_max_depth_mm: NDArray
    worn_volume_mm3: NDArray
    contact_fallbacks: int
    contact_updates: int
    elapsed_s: float
    law: str
    application: str
    n_classes: int
    rail_y_mm: NDArray
    rail_depth_per_vehicle_mm: NDArray
    rail_steps: tuple
    step_basis_mm: NDArray
    coefficients: NDArray
    rail_high_depth_per_vehicle_mm: NDArray | None = None
    rail_low_depth_per_vehicle_mm: NDArray | None = None
    rail: Any = "60E1"

    @property
    def wear_mm(self) -> NDArray:
        """Vertical wear w(y) = z_initial - z after each step [mm], (n_steps+1, n)."""
        return self.profiles_mm[0] - self.profiles_mm

    def wear_at(self, mileage_km: float) -> NDArray:
        """Vertical wear at a mileage, linear between steps [mm], (n,)."""
        m = self.mileage_km
        if not m[0] <= mileage_km <= m[-1] + 1e-9:
            raise ValueError(f"mileage {mileage_km} km outside the simulated 0..{m[-1]:.0f} km")
        i = int(np.clip(np.searchsorted(m, mileage_km, side="right") - 1, 0, m.size - 2))
        t = (mileage_km - m[i]) / (m[i + 1] - m[i])
        w = self.wear_mm
        return (1 - t) * w[i] + t * w[i + 1]

    def mileage_to_depth(self, depth_mm: float) -> float:
        """First mileage at which the maximum wear depth reaches depth_mm [km] (linear between
        steps; NaN if never)."""
        dmax = self.wear_mm.max(axis=1)
        hit = np.nonzero(dmax >= depth_mm)[0]
        if hit.size == 0:
            return float("nan")
        i = hit[0]
        if i == 0:
            return 0.0
        t = (depth_mm - dmax[i - 1]) / (dmax[i] - dmax[i - 1])
        return float(self.mileage_km[i - 1] + t * (self.mileage_km[i] - self.mileage_km[i - 1]))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (lists of floats)."""
        return {
            "law": self.law, "application": self.application, "n_classes": self.n_classes,
            "y_mm": self.y_mm.tolist(), "profiles_mm": self.profiles_mm.tolist(),
            "mileage_km": self.mileage_km.tolist(), "sh_mm": self.sh_mm.tolist(),
            "sd_mm": self.sd_mm.tolist(), "qr_mm": self.qr_mm.tolist(),
            "step_km": self.step_km.tolist(), "step_max_depth_mm": self.step_max_depth_mm.tolist(),
            "worn_volume_mm3": self.worn_volume_mm3.tolist(),
            "contact_fallbacks": self.contact_fallbacks, "contact_updates": self.contact_updates,
            "elapsed_s": self.elapsed_s, "rail_y_mm": self.rail_y_mm.tolist(),
            "rail_depth_per_vehicle_mm": self.rail_depth_per_vehicle_mm.tolist(),
            "rail_steps": [dict(s) for s in self.rail_steps],
        }


def _grid(spec: tuple[float, float, float]) -> NDArray[np.float64]:
    lo, hi, step = spec
    return np.linspace(lo, hi, int(round((hi - lo) / step)) + 1)


def _contact_key(vehicle: BogieVehicle, classes: list[LoopClass], axle: int, side: str,
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
                  rail_from_all_wheels: bool = False) -> WearSimulation:
    """Simulate the wear of one wheel over a route described by curve classes.

    Parameters
    ----------
    vehicle : BogieVehicle or preset name (``vehicles.vehicle_preset``, trailer bogie)
    route_classes : curve classes (:func:`as_loop_classes` accepts LoopClass, mappings,
        CurveClass / RouteClass objects or a Route)
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
        (:func:`rail_depth_per_vehicle_all_wheels`; ``rail_depth_per_vehicle_mm`` is then the
        mean rail of seed 003); default: from the tracked wheel's rail only
        (:func:`rail_depth_per_vehicle`). The rail itself is ``vehicle.rail_profile`` (a name,
        a measured or a :class:`~wearcast.physics.rail_head_wear.WornRail`), in the contact
        table of every contact update.

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
    if application not in ("global", "local"):
        raise ValueError(f"application must be 'global' or 'local', got {application!r}")
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
    cache_key = None if contact_cache is None else _contact_key(
        veh, classes, axle, side, unbalanced_acceleration_m_s2, tangent_speed_kmh, fastsim_grid,
        y, patch_width) + (rail_from_all_wheels,)
    linear = Smoothing(sm.method, sm.window_mm, sm.lam, clip_negative=False)
    eps = 1e-3
    for i in range(st.n_steps):
        remaining = st.step_km if st.mode == "fixed" else None
        z_start = z.copy()
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
                per_class = wheel_depth_basis(contacts, wl, y, application, fastsim_grid,
                                              veh.friction)                # mm per m rolled
                # Smooth each basis row linearly; clipping acts on the sum below.
                basis_km = linear.apply(np.einsum("c,cbn->bn", shares, per_class) * 1000.0, y)
                if all_contacts is not None:
                    sides = rail_depth_per_vehicle_all_wheels(all_contacts, wl, classes, shares,
                                                              rail_y)
                    rail_sides.append(sides)
                    rail_rates.append(sides["mean"])
                else:
                    rail_rates.append(rail_depth_per_vehicle(contacts, wl, shares, rail_y))
            assert basis_km is not None
            rate = basis_km.T @ coeffs                                     # mm/km, normal
            if sm.clip_negative:
                rate = np.maximum(rate, 0.0)
            slope = np.gradient(z, y)
            peak = float(np.max(rate * np.sqrt(1.0 + slope * slope)))
            if remaining is not None:
                # Fixed step, cut into sub-steps of at most max_depth_per_step_mm.
                ds = remaining if peak <= 0 else min(remaining, max(
                    st.max_depth_per_step_mm / peak, st.step_km / st.max_substeps))
            else:
                ds = st.max_step_km if peak <= 0 else min(st.depth_per_step_mm / peak,
                                                           st.max_step_km)
            z_new = apply_normal_wear(y, z, rate * ds)
            if remaining is None and ds < st.max_step_km:
                for _ in range(2):  # nearly linear in ds: rescale to D_step exactly
                    actual = float(np.max(z - z_new))
                    if actual <= 0:
                        break
                    ds = min(ds * st.depth_per_step_mm / actual, st.max_step_km)
                    z_new = apply_normal_wear(y, z, rate * ds)
            # Vertical wear per unit coefficient, linearised (Jacobian of eq. 9).
            sub = np.stack([(z - apply_normal_wear(y, z, row * ds * eps)) / eps
                            for row in basis_km])
            step_basis = sub if step_basis is None else step_basis + sub
            since_update += float(np.max(z - z_new))
            _check_diverged(z_new, profiles[0], i, mileage[-1] + taken + ds)
            z = z_new
            taken += ds
            if remaining is None:
                break
            remaining -= ds
            if remaining <= 1e-9 * st.step_km:
                break
        basis_steps.append(step_basis)
        step_depth.append(float(np.max(z_start - z)))
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
    rail_steps = _rail_steps(rail_rate, rail_step_depth_mm, n_rail_steps, veh)
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
        rail=veh.rail_profile)


def _check_diverged(z_mm: NDArray, z_initial_mm: NDArray, step: int, mileage_km: float) -> None:
    """Raise :class:`WearLoopDivergedError` on a non-finite profile or wear beyond
    :data:`MAX_WHEEL_WEAR_MM` (a worn profile is never returned from a diverged run)."""
    if not np.all(np.isfinite(z_mm)):
        raise WearLoopDivergedError(
            f"wear loop diverged in step {step + 1} near {mileage_km:.0f} km: non-finite "
            "profile; use shorter steps (adaptive mode or a smaller step_km)")
    depth = float(np.max(z_initial_mm - z_mm))
    if depth > MAX_WHEEL_WEAR_MM:
        raise WearLoopDivergedError(
            f"wear loop diverged in step {step + 1} near {mileage_km:.0f} km: {depth:.3g} mm "
            f"of wear exceeds a wheel rim's {MAX_WHEEL_WEAR_MM:.0f} mm; use shorter steps "
            "(adaptive mode or a smaller step_km) or check the wear coefficients")


def _rail_steps(rate: NDArray, depth_mm: float, n_steps: int, vehicle: BogieVehicle) -> tuple:
    """Rail steps of seed 003 eq. (4): N_step = D^r / max(depth per vehicle)."""
    peak = float(np.max(rate))
    vehicle_mass_t = 4.0 * vehicle.wheel_load_n / GRAVITY_M_S2 / 1000.0 * 2.0  # two bogies
    out = []
    for k in range(1, n_steps + 1):
        n_veh = k * depth_mm / peak if peak > 0 else float("inf")
        out.append((("rail_step", k), ("vehicles", n_veh),
                    ("tonnage_mt", n_veh * vehicle_mass_t / 1e6),
                    ("max_depth_mm", k * depth_mm if peak > 0 else 0.0)))
    return tuple(tuple(s) for s in out)


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
    mass_t = 4.0 * veh.wheel_load_n / GRAVITY_M_S2 / 1000.0 * 2.0  # two bogies, as _rail_steps
    return RailStepSimulation(
        wheel_runs=tuple(runs), rails=tuple(rails), high_rails=tuple(highs),
        low_rails=tuple(lows), km_tot=np.array(km_tot), vehicles_per_step=np.array(n_step),
        rail_y_mm=rail_y, rail_depth_per_vehicle_mm=np.array(depths),
        rail_step_depth_mm=float(rail_step_depth_mm), vehicle_mass_t=mass_t,
        elapsed_s=time.perf_counter() - start)


def _with_rail(vehicle: BogieVehicle, rail: str | RailShape) -> BogieVehicle:
    """The vehicle on another rail (a name or a rail shape)."""
    from dataclasses import replace

    return replace(vehicle, rail_profile=rail)
