"""Wear of each curve class's contact patches: worn volume per metre rolled and wheel depth.

Step 2 of the wear loop (:mod:`wearcast.physics.wear_loop`): from the contacts of a class
(:class:`~wearcast.physics.class_contacts.ClassContacts`), the law's worn volume per metre
rolled of each patch (:mod:`wearcast.physics.wear_laws`), written as a linear basis times the
law's coefficients (the four KTH zone coefficients for Archard/KTH, seed 004 eqs. 3-5; one
coefficient 1 for the other laws), and the WHEEL's normal depth per metre rolled: spread with
the semi-elliptic distribution (global application, seed 004) or per element of the FASTSIM
grid (local application, seed 002 eqs. 4-5 and seed 003 §4.2;
:mod:`wearcast.physics.wear_distribution`). The wheel's share of the law's volume is the law's
own definition (``wear_laws.wheel_rail_split``: half for seed 004's wheel-and-rail KTH
coefficients, all of it for USFD).

Volumes in mm^3 per m rolled, depths in mm per m rolled, speeds in m/s.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.class_contacts import ClassContacts
from wearcast.physics.contact.fastsim import fastsim
from wearcast.physics.curving import SHEAR_MODULUS_MPA
from wearcast.physics.wear_distribution import (
    check_application,
    local_archard_depth,
    local_rate_depth,
    semi_elliptic_depth,
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


def contact_volume_basis(contacts: ClassContacts, law: WearLaw) -> NDArray[np.float64]:
    """Worn volume per metre rolled of each patch, as a basis: shape (n_class, n_slot, n_basis)
    [mm^3/m]; n_basis = 4 (zones) for Archard/KTH, else 1 (coefficient 1)."""
    c = contacts
    v = np.broadcast_to(c.speed_m_s[:, None], c.normal_force_n.shape)
    area = np.pi * np.where(c.in_contact, c.a_mm * c.b_mm, 1.0)
    if law.name == "archard_kth":
        vs = rigid_sliding_velocity_m_s(v, c.xi, c.eta)
        basis = archard_basis(c.normal_force_n, vs, v, c.normal_force_n / area, law.archard)
    elif law.name == "krause_poll":
        basis = krause_poll_rate(c.t_gamma_n, v, area)[..., None]
    elif law.name == "usfd":
        jump: Any = law.usfd_jump  # 'continuous' or 'as_printed', checked by WearLaw
        basis = usfd_rate(c.t_gamma_n, area, jump)[..., None]
    else:
        basis = tau_max_rate(c.tau_max_mpa, area, law.tau_coefficient_mm_per_m_mpa,
                             law.tau_threshold_mpa)[..., None]
    return np.where(c.in_contact[..., None], basis, 0.0)


def law_coefficients(law: WearLaw) -> NDArray[np.float64]:
    """Coefficients that multiply the basis (the effective KTH zone coefficients, or [1])."""
    return law.archard.effective_coefficients if law.name == "archard_kth" else np.ones(1)


def _global_volume_and_shape(c: ClassContacts, law: WearLaw, y_grid_mm: NDArray
                             ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Global application's factors: each patch's worn volume basis per metre rolled
    (n_class, n_slot, n_basis) [mm^3/m] and its semi-elliptic normal depth per unit volume
    (n_class, n_slot, n) [mm/mm^3] (seed 004 eqs. 3-5, ``semi_elliptic_depth``)."""
    safe_b = np.where(c.in_contact, c.b_mm, 1.0)
    safe_r = np.where(c.in_contact, c.rolling_radius_m * 1000.0, 1.0)
    vol = contact_volume_basis(c, law)
    shape = semi_elliptic_depth(y_grid_mm, c.wheel_y_mm, safe_b, 1.0, safe_r,
                                c.contact_angle_rad)
    return vol, shape


def wheel_depth_basis_by_slot(contacts: ClassContacts, law: WearLaw, y_grid_mm: NDArray
                              ) -> NDArray[np.float64]:
    """Global application of :func:`wheel_depth_basis` per patch slot: (n_slot, n_class,
    n_basis, n) [mm/m], slot s the depth of the slot-s patches alone -- bit for bit
    ``wheel_depth_basis`` of the contacts with only slot s in contact (the basis is additive
    in patches; the other slots' volumes are 0 there), from one volume basis and one
    semi-elliptic spread of all patches instead of one per slot."""
    wheel_share, _ = wheel_rail_split(law)
    vol, shape = _global_volume_and_shape(contacts, law, y_grid_mm)
    return np.stack([wheel_share * (vol[:, s, :, None] * shape[:, s, None, :])
                     for s in range(vol.shape[1])])


def fastsim_on_loaded_patches(contacts: ClassContacts, fastsim_grid: int, friction: float
                              ) -> tuple[tuple[NDArray[np.intp], ...], Any] | None:
    """FASTSIM (``contact.fastsim``, CONTACT's flexibilities) on every loaded patch of the
    classes' contacts, for the local application of a wear law on the wheel or the rail:
    (the loaded patches' indices into the contacts' arrays, the FASTSIM result on a
    ``fastsim_grid`` x ``fastsim_grid`` grid), or None when no patch is loaded."""
    c = contacts
    idx = np.nonzero(c.in_contact)
    if idx[0].size == 0:
        return None
    xi, eta, phi, a_mm, b_mm, normal_n = (np.asarray(getattr(c, f))[idx] for f in (
        "xi", "eta", "phi_per_mm", "a_mm", "b_mm", "normal_force_n"))
    return idx, fastsim(xi, eta, phi, a_mm, b_mm, normal_n, friction, SHEAR_MODULUS_MPA,
                        n_x=fastsim_grid, n_y=fastsim_grid)


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
    check_application(application)
    wheel_share, _ = wheel_rail_split(law)
    c = contacts
    n_class = c.normal_force_n.shape[0]
    radius_mm = c.rolling_radius_m * 1000.0
    if application == "global":
        vol, shape = _global_volume_and_shape(c, law, y_grid_mm)
        return wheel_share * np.einsum("csb,csn->cbn", vol, shape)
    n_basis = 4 if law.name == "archard_kth" else 1
    out = np.zeros((n_class, n_basis, np.size(y_grid_mm)))
    loaded = fastsim_on_loaded_patches(c, fastsim_grid, friction)
    if loaded is None:
        return out
    idx, fs = loaded
    if law.name == "archard_kth":
        basis = local_archard_depth(fs, c.speed_m_s[idx[0]], c.wheel_y_mm[idx],
                                    radius_mm[idx], c.contact_angle_rad[idx], y_grid_mm,
                                    law.archard)
    else:
        v = c.speed_m_s[idx[0]][:, None, None]
        rate = element_depth_rate_mm_per_m(law, fs.shear_traction_mpa,
                                           np.hypot(fs.sx, fs.sy), fs.pn_mpa, v)
        basis = local_rate_depth(fs, rate, c.wheel_y_mm[idx], radius_mm[idx],
                                 c.contact_angle_rad[idx], y_grid_mm)[:, None, :]
    np.add.at(out, idx[0], basis)
    return wheel_share * out
