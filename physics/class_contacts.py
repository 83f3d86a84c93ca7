"""Quasi-static contacts of a wheel per curve class, for the current (worn) wheel profile.

Step 1 of the wear loop (:mod:`wearcast.physics.wear_loop`; seeds 000, 002, 003, 004 in
docs/references.md): the quasi-static bogie curving of :mod:`wearcast.physics.curving` with the
contact table rebuilt from the wheel profile z(y) on the vehicle's rail. Classes of the same
radius, cant and speed share one solution (an operating point); a right-hand class is the
mirror image of a left-hand one, so the tracked wheel of a right curve is the opposite wheel of
the left-curve solution. A vehicle with a high and a low rail of their own
(``BogieVehicle.high_rail_profile`` / ``low_rail_profile``) runs every curve with the high
rail outside, so the mirror still holds: the curves are solved as left curves on the table
pair (low rail left, high rail right), tangent track on ``rail_profile``
(``curving_table.track_rails``). If the batched solve does not converge for some operating
point, it is retried from its last equilibrium; if it still fails, the class keeps the
contact of its previous contact update, or, on the first update, the contact of the converged
operating point nearest in curvature (then cant) -- the stated simpler contact; both are
counted as fallbacks.
If no class converges, :class:`~wearcast.physics.curving.CurvingConvergenceError` is raised.

Forces in N, lengths in mm (rolling radius in mm), speeds in m/s.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_equations import BogieContacts
from wearcast.physics.conformal_patch_width import conformal_half_width_mm
from wearcast.physics.curving import (
    ContactTable,
    CurvingConvergenceError,
    CurvingResult,
    build_contact_table,
    curve_case,
    solve_curving_cases_or_none,
)
from wearcast.physics.curving_table import same_rail, track_rails
from wearcast.physics.vehicles import BogieVehicle
from wearcast.physics.vocabulary import AXLES, SIDES, CurveClass

#: Patch-width models of :func:`class_contacts`.
PatchWidth = Literal["hertz", "kik_piotrowski"]
PATCH_WIDTHS: tuple[PatchWidth, ...] = get_args(PatchWidth)


@dataclass(frozen=True)
class ClassContacts(BogieContacts):
    """Contacts of the tracked wheel per class, shape (n_class, n_slot) (patch slots of the
    curving model, field side first).

    The per-contact quantities of the curving results (:class:`~wearcast.physics.
    bogie_equations.BogieContacts`, same names and units), their wear measures tau_max_mpa,
    t_gamma_n, and in_contact (bool: a patch carrying more than 1 N); speed_m_s (n_class,).
    Rail-side arrays of both axles of the bogie on the same rail: rail_* with shape (n_class,
    2 axles, n_slot). ``states``: the last curving equilibrium per operating point (the warm
    start of the next update's failed points).
    """

    tau_max_mpa: NDArray
    t_gamma_n: NDArray
    in_contact: NDArray
    speed_m_s: NDArray
    rail_axles: dict = field(default_factory=dict)
    states: dict = field(default_factory=dict)


#: The per-contact fields of ClassContacts, taken from the curving results by name.
_CONTACT_FIELDS = (*(f.name for f in fields(BogieContacts)), "tau_max_mpa", "t_gamma_n",
                   "in_contact")


_RAIL_FIELDS = ("normal_force_n", "rail_y_mm", "contact_angle_rad", "b_mm", "rolling_radius_m",
                "in_contact")


def _operating_point(c: CurveClass, unbalanced_acceleration_m_s2: float,
                     tangent_speed_kmh: float) -> tuple:
    if c.is_tangent:
        v = (c.speed_kmh if c.speed_kmh is not None else tangent_speed_kmh) / 3.6
        return (None, 0.0, round(v, 9))
    speed_m_s = None if c.speed_kmh is None else c.speed_kmh / 3.6
    assert c.radius_m is not None  # not tangent here
    radius_m = float(c.radius_m)
    case = curve_case(radius_m, c.cant_mm, speed_m_s, "left", unbalanced_acceleration_m_s2)
    return (radius_m, float(c.cant_mm), round(case.speed_m_s, 9))


def _no_class_converged(points: Sequence[tuple]) -> CurvingConvergenceError:
    """The error when no operating point converged, naming the sharpest curve's radius (inf:
    tangent track only) and every radius tried."""
    radii = sorted(p[0] for p in points if p[0] is not None)
    tried = ", ".join(f"{r:g}" for r in radii) + (", tangent" if len(radii) < len(points) else "")
    return CurvingConvergenceError(
        f"quasi-static curving did not converge for any class (radii tried: {tried} m)",
        radii[0] if radii else np.inf, float("nan"))


def _curvature(point: tuple) -> float:
    return 0.0 if point[0] is None else 1.0 / point[0]


def _solve_points(vehicle: BogieVehicle, points: list[tuple],
                  tables: tuple[ContactTable, ContactTable], fastsim_grid: int,
                  warm: dict | None = None, warm_first: bool = False
                  ) -> list[CurvingResult | None]:
    """:func:`_solve_table_points` of the curve points on ``tables[0]`` and the tangent
    points on ``tables[1]`` (one batch when they are one table)."""
    if tables[0] is tables[1]:
        return _solve_table_points(vehicle, points, tables[0], fastsim_grid, warm, warm_first)
    out: list[CurvingResult | None] = [None] * len(points)
    for tangent, table in ((False, tables[0]), (True, tables[1])):
        idx = [k for k, p in enumerate(points) if (p[0] is None) == tangent]
        if idx:
            res = _solve_table_points(vehicle, [points[k] for k in idx], table, fastsim_grid,
                                      warm, warm_first)
            for k, r in zip(idx, res, strict=True):
                out[k] = r
    return out


def _solve_table_points(vehicle: BogieVehicle, points: list[tuple], table: ContactTable,
                        fastsim_grid: int, warm: dict | None = None, warm_first: bool = False
                        ) -> list[CurvingResult | None]:
    """Batched curving of the operating points in one batch; a point that does not converge
    from the tangent track's equilibrium is retried from its last equilibrium (``warm``:
    operating point -> ``CurvingResult.saturation_state`` on the previous profile) if it has
    one, else it is None
    (the caller falls back to a neighbour or the previous contact). ``warm_first``: start every
    point that has a last equilibrium from it (Newton at full load, no continuation) and retry
    the failures by continuation from the tangent track's equilibrium (faster when the profile
    changed little). The vehicle's traction torque acts at every point."""
    cases = [curve_case(r, cant, v, "left", torque_nm=vehicle.traction_torque_nm)
             for r, cant, v in points]
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


def class_contacts(vehicle: BogieVehicle, classes: Sequence[CurveClass], y_mm: NDArray,
                   z_mm: NDArray, *, axle: int = 1, side: str = "right",
                   unbalanced_acceleration_m_s2: float = 0.58, tangent_speed_kmh: float = 100.0,
                   fastsim_grid: int = 20, previous: ClassContacts | None = None,
                   patch_width: str = "hertz") -> tuple[ClassContacts, int]:
    """Quasi-static contacts of the tracked wheel per class for the wheel profile z(y).

    patch_width : ``hertz`` (the curving model's ellipse, from the gap smoothed over 2 mm) or
        ``kik_piotrowski`` (the lateral semi-axis widened to the extent of the unsmoothed gap
        within 0.55 x the approach, ``conformal_patch_width.conformal_half_width_mm``:
        conformal flange-root patches become wide and mild; the equilibrium and creepages are
        unchanged)

    Returns (contacts, number of classes that kept the previous contact). Raises
    CurvingConvergenceError when a class fails and there is no previous contact.
    """
    out, fallbacks = class_contacts_all_wheels(
        vehicle, classes, y_mm, z_mm, wheels=((axle, side),),
        unbalanced_acceleration_m_s2=unbalanced_acceleration_m_s2,
        tangent_speed_kmh=tangent_speed_kmh, fastsim_grid=fastsim_grid,
        previous=None if previous is None else {(axle, side): previous},
        patch_width=patch_width)
    return out[(axle, side)], fallbacks


def class_contacts_all_wheels(vehicle: BogieVehicle, classes: Sequence[CurveClass],
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
        if axle not in AXLES or side not in SIDES:
            raise ValueError("axle must be 1 or 2 and side 'left' or 'right'")
    if patch_width not in PATCH_WIDTHS:
        raise ValueError(f"patch_width must be one of {', '.join(PATCH_WIDTHS)}, "
                         f"got {patch_width!r}")
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    tables = _class_tables(vehicle, y, z, classes)
    points = [_operating_point(c, unbalanced_acceleration_m_s2, tangent_speed_kmh)
              for c in classes]
    unique = sorted(set(points), key=lambda p: (p[0] is None, p[0] or 0.0, p[1], p[2]))
    prev = dict(previous or {})
    warm: dict | None = None
    for pc in prev.values():
        warm = {**(warm or {}), **pc.states}
    solved = dict(zip(unique, _solve_points(vehicle, unique, tables, fastsim_grid, warm,
                                            warm_first), strict=True))
    states = dict(warm or {})
    states.update({p: r.saturation_state for p, r in solved.items() if r is not None})
    good = [p for p, r in solved.items() if r is not None]
    if not good and not prev:
        raise _no_class_converged(unique)
    out = {}
    fallbacks = 0
    stacks: dict[str, NDArray] = {}  # the solved points' fields, stacked once for all wheels
    for wheel in wheels:
        out[wheel], fb = _wheel_contacts(vehicle, classes, points, solved, good, y, z, wheel,
                                         prev.get(wheel), patch_width, states, stacks)
        fallbacks += fb
    return out, fallbacks


def _class_tables(vehicle: BogieVehicle, y: NDArray, z: NDArray,
                  classes: Sequence[CurveClass]) -> tuple[ContactTable, ContactTable]:
    """(curve table, tangent table) of the wheel profile z(y): the curves' on the rails of
    a left curve (``track_rails``: low rail left, high rail right), tangent track's on
    ``rail_profile``; one table, built once, when those rails are all one profile."""
    def wheel(q: NDArray) -> NDArray:
        return np.interp(q, y, z)

    curve_left, curve_right = track_rails(vehicle, "left")
    plain = vehicle.rail_profile
    if same_rail(curve_left, plain) and same_rail(curve_right, plain):
        table = build_contact_table(wheel, plain, vehicle.rail_inclination,
                                    vehicle.wheel_radius_m)
        return table, table
    has_curves = any(not c.is_tangent for c in classes)
    has_tangent = any(c.is_tangent for c in classes)
    curve = (build_contact_table(wheel, curve_left, vehicle.rail_inclination,
                                 vehicle.wheel_radius_m, rail_right=curve_right)
             if has_curves or not has_tangent else None)
    tangent = (build_contact_table(wheel, plain, vehicle.rail_inclination,
                                   vehicle.wheel_radius_m) if has_tangent else curve)
    assert tangent is not None
    return (tangent if curve is None else curve), tangent


def _wheel_contacts(vehicle: BogieVehicle, classes: Sequence[CurveClass], points: list,
                    solved: dict, good: list, y: NDArray, z: NDArray, wheel: tuple[int, str],
                    previous: ClassContacts | None, patch_width: str, states: dict,
                    stacks: dict[str, NDArray]) -> tuple[ClassContacts, int]:
    """Contacts of one wheel per class from the solved operating points (fallbacks counted).
    ``stacks``: field name -> the converged points' values stacked in ``solved``'s order,
    filled on first use and shared by the wheels of one solve."""
    axle, side = wheel
    ai = axle - 1
    n = len(classes)
    slots = [np.shape(r.normal_force_n)[-1] for r in solved.values() if r is not None]
    if previous is not None:
        slots.append(previous.normal_force_n.shape[-1])
    n_slot = max(slots) if slots else 2
    data = {f: np.zeros((n, n_slot)) for f in _CONTACT_FIELDS}
    rail = {f: np.zeros((n, 2, n_slot)) for f in _RAIL_FIELDS}
    speed = np.zeros(n)
    fallbacks = 0
    if not good and previous is None:
        raise _no_class_converged(list(solved))
    # per class: the solved operating point whose contacts it takes (the nearest converged one
    # on a first update), or -1 to keep the previous update's contacts
    order = [p for p in solved if solved[p] is not None]
    index = {p: i for i, p in enumerate(order)}
    source = np.full(n, -1)
    for k, p in enumerate(points):
        if solved[p] is None and previous is None:
            # Nearest converged operating point in curvature (then cant) of the same profile.
            fallbacks += 1
            source[k] = index[min(good, key=lambda q: (abs(_curvature(q) - _curvature(p)),
                                                       abs(q[1] - p[1])))]
        elif solved[p] is not None:
            source[k] = index[p]
    # Mirror: the tracked wheel of a right curve is the opposite wheel of the left curve.
    own = 0 if side == "left" else 1
    mirrored = np.array([not (c.direction == "left" or c.is_tangent) for c in classes],
                        dtype=bool)
    si = np.where(mirrored, 1 - own, own)
    new = np.nonzero(source >= 0)[0]
    if new.size:
        m = np.shape(solved[order[0]].normal_force_n)[-1]
        rows, sides = source[new], si[new]
        for f in (*_CONTACT_FIELDS, "speed_m_s"):
            if f not in stacks:
                stacks[f] = np.stack([np.asarray(getattr(solved[p], f), dtype=float)
                                      for p in order])
        for f in _CONTACT_FIELDS:
            data[f][new, :m] = stacks[f][rows, ai, sides]
        for f in rail:
            rail[f][new, :, :m] = stacks[f][rows, :, sides]
        speed[new] = stacks["speed_m_s"][rows]
    kept = np.nonzero(source < 0)[0]
    if kept.size:
        assert previous is not None
        fallbacks += int(kept.size)
        m = previous.normal_force_n.shape[-1]
        for f in _CONTACT_FIELDS:
            data[f][kept, :m] = getattr(previous, f)[kept]
        for f in rail:
            rail[f][kept, :, :m] = previous.rail_axles[f][kept]
        speed[kept] = previous.speed_m_s[kept]
    loaded = data["in_contact"].astype(bool) & (data["normal_force_n"] > 1.0)
    if patch_width == "kik_piotrowski":
        # the rail under the tracked wheel: tangent track's, or in a curve (solved as a left
        # curve) the left rail of the curve table where the wheel is on the solution's left
        curve_rails = track_rails(vehicle, "left")
        under = [vehicle.rail_profile if c.is_tangent else curve_rails[int(si[k])]
                 for k, c in enumerate(classes)]
        for rail_k in {id(r): r for r in under}.values():
            rows = np.array([r is rail_k for r in under])
            width = conformal_half_width_mm(
                y, z, rail_k, vehicle.rail_inclination, data["wheel_y_mm"][rows],
                data["rail_y_mm"][rows],
                np.where(loaded[rows], data["normal_force_n"][rows], 0.0), data["a_mm"][rows],
                data["b_mm"][rows])
            data["b_mm"][rows] = np.where(loaded[rows], width, data["b_mm"][rows])
    rail["in_contact"] = rail["in_contact"].astype(bool) & (rail["normal_force_n"] > 1.0)
    data["in_contact"] = loaded
    return ClassContacts(**data, speed_m_s=speed, rail_axles=rail, states=states), fallbacks
