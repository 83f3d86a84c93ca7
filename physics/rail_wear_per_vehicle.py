"""Rail wear per vehicle passage from the contact patches of each curve class, and rail steps.

Rail wear does not grow with the vehicle's mileage but with the number of vehicles N (tonnage
N M_v; seed 003 §4.3, item 2). Per vehicle passage, the cross-section area a patch removes from
the rail is its worn volume per metre rolled (the rail's share of the law's volume,
``wear_laws.wheel_rail_split``; :mod:`wearcast.physics.patch_wear`) / 1000 mm, spread
semi-elliptically on the rail's own lateral coordinate and averaged over classes with the
shares p_k. Either from the tracked wheel's rail (both axles of the bogie, two bogies per
vehicle: :func:`rail_depth_per_vehicle`) or from all four wheels of the bogie, each with its
own patches (globally, or locally per FASTSIM element as seed 003 §4.2), split into the high
rail (the outer rail of each curve), the low rail and the mean rail of seed 003 (one mean rail
profile for all rails, §4.3: :func:`rail_depth_per_vehicle_all_wheels`). Rail steps:
N_step = D_step^r / max(depth per vehicle) (seed 003 eq. 4, :func:`rail_step_rows`).

Depths in mm per vehicle passage, lateral positions in mm on the inclined rail frame's grid,
masses in t (Mt = 1e6 t).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.adaptive_step import adaptive_step
from wearcast.physics.class_contacts import ClassContacts
from wearcast.physics.patch_wear import (
    contact_volume_basis,
    fastsim_on_loaded_patches,
    law_coefficients,
)
from wearcast.physics.vehicles import GRAVITY_M_S2, BogieVehicle
from wearcast.physics.vocabulary import SIDES, CurveClass
from wearcast.physics.wear_distribution import (
    check_application,
    local_rate_depth,
    semi_elliptic_depth,
)
from wearcast.physics.wear_laws import WearLaw, element_depth_rate_mm_per_m, wheel_rail_split


def vehicle_mass_t(vehicle: BogieVehicle, bogies_per_vehicle: int = 2) -> float:
    """Mass of one vehicle passage [t]: four wheel loads per bogie over g, two bogies."""
    return 4.0 * vehicle.wheel_load_n / GRAVITY_M_S2 / 1000.0 * bogies_per_vehicle


def rail_step_rows(rate: NDArray, depth_mm: float, n_steps: int, vehicle: BogieVehicle) -> tuple:
    """Rail steps of seed 003 eq. (4): N_step = D^r / max(depth per vehicle); per step k the
    pairs (rail_step k, vehicles k N_step, tonnage_mt, max_depth_mm k D^r) [-, -, Mt, mm]."""
    per_step = adaptive_step(rate, depth_mm)  # vehicles per rail step (inf: no wear)
    mass_t = vehicle_mass_t(vehicle)
    out = []
    for k in range(1, n_steps + 1):
        n_veh = k * per_step
        out.append((("rail_step", k), ("vehicles", n_veh),
                    ("tonnage_mt", n_veh * mass_t / 1e6),
                    ("max_depth_mm", k * depth_mm if math.isfinite(per_step) else 0.0)))
    return tuple(tuple(s) for s in out)


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
    lead_n = np.where(contacts.normal_force_n > 0, contacts.normal_force_n, 1.0)
    scale = r["normal_force_n"] / lead_n[:, None, :]                # (n_class, axle, slot)
    area_per_pass = (vol[:, None, :] * np.where(contacts.in_contact[:, None, :], scale, 0.0)
                     / 1000.0)                                          # mm^2 per passage
    b = np.where(r["in_contact"], r["b_mm"], 1.0)
    # Unit radius 1/(2 pi) makes semi_elliptic_depth spread "volume" = area as a depth on y.
    depth = semi_elliptic_depth(rail_grid_mm, r["rail_y_mm"], b,
                                np.where(r["in_contact"], area_per_pass, 0.0),
                                1.0 / (2.0 * np.pi), r["contact_angle_rad"])
    per_class = bogies_per_vehicle * depth.sum(axis=(1, 2))
    return np.einsum("c,cn->n", shares, per_class)


def _local_rail_depth_per_passage(c: ClassContacts, law: WearLaw, rail_grid_mm: NDArray,
                                  fastsim_grid: int, friction: float) -> NDArray[np.float64]:
    """Local application on the rail: normal depth of ONE passage of each class's patches
    (summed over the slots), (n_class, n_rail) [mm], the law's full volume (the caller applies
    the rail's share).

    Seed 003 §4.2: the specific volume K_w(I_w) / rho of each FASTSIM element is "the same
    both for the wheel and for the rail". The element's depth rate [mm per m in contact]
    (``wear_laws.element_depth_rate_mm_per_m``) over its length dx gives rate dx / 1000 [mm]
    per passage; each longitudinal strip is deposited at the patch's rail position
    (``wear_distribution.local_rate_depth`` with the circumference 2 pi R set to 1000 mm, one
    passage instead of the 1000 / (2 pi R_cp) passages per metre of a wheel point). The
    FASTSIM call is the wheel's (``patch_wear.fastsim_on_loaded_patches``) and the rail frame's y
    points the same way as the wheel's (gauge corner and flange negative).
    """
    out = np.zeros((c.normal_force_n.shape[0], np.size(rail_grid_mm)))
    loaded = fastsim_on_loaded_patches(c, fastsim_grid, friction)
    if loaded is None:
        return out
    idx, fs = loaded
    v = c.speed_m_s[idx[0]][:, None, None]
    rate = element_depth_rate_mm_per_m(law, fs.shear_traction_mpa, np.hypot(fs.sx, fs.sy),
                                       fs.pn_mpa, v)
    per_pass = local_rate_depth(fs, rate, c.rail_y_mm[idx], ONE_PASSAGE_RADIUS_MM,
                                c.contact_angle_rad[idx], rail_grid_mm)
    np.add.at(out, idx[0], per_pass)
    return out


#: Radius whose circumference is 1000 mm: ``local_rate_depth`` divides a strip's depth per
#: metre in contact by 2 pi R / 1000, i.e. gives one passage's depth with it [mm].
ONE_PASSAGE_RADIUS_MM = 1000.0 / (2.0 * np.pi)


def rail_depth_per_vehicle_all_wheels(contacts: Mapping[tuple[int, str], ClassContacts],
                                      law: WearLaw, classes: Sequence[CurveClass],
                                      shares: NDArray, rail_grid_mm: NDArray,
                                      bogies_per_vehicle: int = 2, application: str = "global",
                                      fastsim_grid: int = 20, friction: float = 0.35
                                      ) -> dict[str, NDArray[np.float64]]:
    """Rail normal depth per vehicle passage from every wheel of the bogie [mm], class-averaged
    with p_k (seed 003 eq. 4), on the rail grid of the inclined rail frame.

    Each wheel's patches wear the rail under it with the rail's share of the law's volume
    (``wear_laws.wheel_rail_split``). ``application="global"``: per passage the cross-section
    area removed is the patch volume per metre rolled / 1000 mm, spread semi-elliptically at
    the patch's rail position. ``"local"`` (seed 003 §4.2, as the wheel's local application):
    the law per element of the FASTSIM grid (``fastsim_grid``, ``friction``), only where the
    element slips, each strip at its own rail position (:func:`_local_rail_depth_per_passage`).
    ``high``: the outer rail of each curve (the wheels on that side); ``low``: the inner rail;
    on tangent track both rails take the mean of the two sides. ``mean``: (high + low) / 2,
    the rail of seed 003's single mean rail profile (every rail of a line is the high rail of
    some curves and the low rail of the others). Returns {"high", "low", "mean"}: (n_rail,).
    """
    _, rail_share = wheel_rail_split(law)
    coeffs = law_coefficients(law)
    n_class = len(classes)
    side_depth: dict[str, NDArray] = {s: np.zeros((n_class, np.size(rail_grid_mm))) for s in SIDES}
    check_application(application)
    for (_, side), c in contacts.items():
        if application == "local":
            side_depth[side] += rail_share * _local_rail_depth_per_passage(
                c, law, rail_grid_mm, fastsim_grid, friction)
            continue
        vol = rail_share * contact_volume_basis(c, law) @ coeffs          # (n_class, slot)
        area = np.where(c.in_contact, vol, 0.0) / 1000.0                       # mm^2 per passage
        b = np.where(c.in_contact, c.b_mm, 1.0)
        # Unit radius 1/(2 pi): semi_elliptic_depth spreads "volume" = area on the rail's y.
        depth = semi_elliptic_depth(rail_grid_mm, c.rail_y_mm, b, area, 1.0 / (2.0 * np.pi),
                                    c.contact_angle_rad)
        side_depth[side] += depth.sum(axis=1)
    high = np.zeros_like(side_depth["left"])
    low = np.zeros_like(high)
    for k, cls in enumerate(classes):
        if cls.is_tangent:
            high[k] = low[k] = 0.5 * (side_depth["left"][k] + side_depth["right"][k])
            continue
        on_rail = {cls.rail_for(side): side_depth[side][k] for side in SIDES}
        high[k], low[k] = on_rail["high"], on_rail["low"]
    h = bogies_per_vehicle * np.einsum("c,cn->n", shares, high)
    lo = bogies_per_vehicle * np.einsum("c,cn->n", shares, low)
    return {"high": h, "low": lo, "mean": 0.5 * (h + lo)}
