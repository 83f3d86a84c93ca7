"""Per-contact wear measures: T-gamma, tau_max, wear indices with their regimes.

* T-gamma (wear number) Tg = |Fx xi| + |Fy eta| + |Mz phi| [N] (seed 004 §2.1; seed 001).
* tau_max: the maximum surface shear traction magnitude of the FASTSIM solution [MPa]
  (default). Seed 001 eq. (5) computes tau_max = p0 / mu_eff with mu_eff = |F_t| / Fn because
  its multibody code does not output tractions; that variant is ``tau_max_p0_over_mu_eff``.
  It diverges as mu_eff -> 0 (free rolling on tangent track: no creep force, infinite
  "tau_max"), and as printed it is not a stress times a friction ratio but a quotient; it is
  kept, named, only to reproduce the seed.
* Tg/A with A = pi a b [N/mm^2] (frictional power per area divided by rolling speed).
* KTH/Archard index (Jendel map; seeds 000 §III, 002 §2.2, 004 eq. 2 and Table 1): worn
  volume Delta V = k(v_s, p) N Delta s / H with the zones
  zone 1 "mild" v_s < 0.2 m/s; zone 2 "severe" 0.2 <= v_s <= 0.7 m/s; zone 3 "mild"
  v_s > 0.7 m/s; zone 4 "catastrophic" (seizure) when the contact pressure exceeds 0.8 H.
  Default coefficients: seed 004 Table 1 (KTH means with the contamination reduction):
  1.43e-4, 1.00e-3, 1.43e-4, 1.00e-2; hardness 300 HB (seed 002 §2.2).
* Krause-Poll index (seed 004 eq. 1): Delta V = C W_fric, C_mild = 9.871e-14 m^3/J when the
  frictional power per area P/A <= 4 W/mm^2, C_severe = 9.871e-13 m^3/J above;
  P = Tg v_roll.

Velocities are explicit inputs in m/s: the sliding velocity v_s and the rolling (vehicle)
speed v_roll.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.fastsim import Bound, FastsimResult, fastsim
from wearcast.physics.contact.hertz import STEEL_SHEAR_MODULUS_MPA

#: Traction bound of the FASTSIM solution tau_max is read from: the elliptic bound mu p(x, y) has
#: the Hertz pressure's shape, so in the slip zone tau_max <= mu p0 as in the exact (variational)
#: solution; the parabolic bound (FASTSIM's default for forces) peaks at 4/3 mu p0 and overstates
#: tau_max by up to 33 % (tests/physics/test_curving.py, full slip).
TAU_MAX_BOUND: Bound = "elliptic"
#: Seed 004 Table 1: KTH wear coefficients per zone (mild 1, severe, mild 2, seizure) [-].
KTH_COEFFICIENTS = (1.43e-4, 1.00e-3, 1.43e-4, 1.00e-2)
#: KTH map sliding-velocity boundaries v1, v2 [m/s] (seed 000 §III).
KTH_VELOCITY_LIMITS_M_S = (0.2, 0.7)
#: Pressure limit of the seizure / catastrophic zone as a fraction of the hardness (seed 000).
KTH_PRESSURE_FRACTION_OF_HARDNESS = 0.8
#: Brinell hardness of wheel and rail steel (seed 002 §2.2) [HB].
STEEL_HARDNESS_HB = 300.0
#: Brinell number to MPa (kgf/mm^2 -> N/mm^2).
HB_TO_MPA = 9.80665
#: Krause-Poll coefficients [m^3/J] and regime transition [W/mm^2] (seed 004 eq. 1).
KRAUSE_POLL_C_MILD_M3_PER_J = 9.871e-14
KRAUSE_POLL_C_SEVERE_M3_PER_J = 9.871e-13
KRAUSE_POLL_TRANSITION_W_PER_MM2 = 4.0

_KTH_LABELS = np.array(["", "mild", "severe", "mild", "catastrophic"])


def t_gamma(fx_n: ArrayLike, fy_n: ArrayLike, mz_nmm: ArrayLike, xi: ArrayLike, eta: ArrayLike,
            phi_per_mm: ArrayLike) -> NDArray[np.float64]:
    """Wear number Tg = |Fx xi| + |Fy eta| + |Mz phi| [N] (seed 004 §2.1).

    Fx, Fy [N], Mz [N*mm], xi, eta [-], phi [1/mm] (so Mz phi is in N).
    """
    return (np.abs(np.asarray(fx_n, dtype=float) * np.asarray(xi, dtype=float))
            + np.abs(np.asarray(fy_n, dtype=float) * np.asarray(eta, dtype=float))
            + np.abs(np.asarray(mz_nmm, dtype=float) * np.asarray(phi_per_mm, dtype=float)))


def tau_max(result: FastsimResult) -> NDArray[np.float64]:
    """Maximum surface shear traction magnitude of a FASTSIM solution [MPa] (the default).

    Take it from a solution with the elliptic traction bound (``curving.TAU_MAX_BOUND``): the
    parabolic bound's peak 2 Fn / (pi a b) is 4/3 of the Hertz p0, so in full slip it reports
    4/3 mu p0 where the exact solution has mu p0."""
    return np.max(result.shear_traction_mpa, axis=(-2, -1))


def tau_max_p0_over_mu_eff(p0_mpa: ArrayLike, fx_n: ArrayLike, fy_n: ArrayLike,
                           normal_force_n: ArrayLike) -> NDArray[np.float64]:
    """Seed 001 eq. (5) as printed: p0 / mu_eff with mu_eff = sqrt(Fx^2 + Fy^2) / Fn.

    Returns p0/mu_eff [MPa]; +inf where mu_eff = 0. It diverges as mu_eff -> 0 (tangent track,
    free rolling), which is why it is not the default measure.
    """
    p0 = np.asarray(p0_mpa, dtype=float)
    ft = np.hypot(np.asarray(fx_n, dtype=float), np.asarray(fy_n, dtype=float))
    fn = np.asarray(normal_force_n, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        mu_eff = ft / fn
        return np.where(mu_eff > 0, p0 / np.where(mu_eff > 0, mu_eff, 1.0), np.inf)


def t_gamma_per_area(t_gamma_n: ArrayLike, a_mm: ArrayLike, b_mm: ArrayLike
                     ) -> NDArray[np.float64]:
    """Tg / A with the Hertz area A = pi a b [N/mm^2]."""
    return np.asarray(t_gamma_n, dtype=float) / (np.pi * np.asarray(a_mm, dtype=float)
                                                 * np.asarray(b_mm, dtype=float))


def rigid_sliding_velocity_m_s(rolling_speed_m_s: ArrayLike, xi: ArrayLike, eta: ArrayLike
                               ) -> NDArray[np.float64]:
    """Global sliding velocity v_s = v_roll sqrt(xi^2 + eta^2) [m/s] (spin not included)."""
    return np.asarray(rolling_speed_m_s, dtype=float) * np.hypot(xi, eta)


@dataclass(frozen=True)
class ArchardIndex:
    """KTH/Archard wear index of a contact.

    coefficient : k [-] from the KTH map
    zone : 1-4 (1 mild, 2 severe, 3 mild, 4 catastrophic/seizure)
    regime : label of the zone
    wear_rate_mm3_per_m : worn volume per metre rolled, k N (v_s / v_roll) / H [mm^3/m]
    """

    coefficient: NDArray[np.float64]
    zone: NDArray[np.int_]
    regime: NDArray[np.str_]
    wear_rate_mm3_per_m: NDArray[np.float64]


def kth_zone(sliding_velocity_m_s: ArrayLike, pressure_mpa: ArrayLike,
             hardness_mpa: float = STEEL_HARDNESS_HB * HB_TO_MPA) -> NDArray[np.int_]:
    """KTH wear-map zone 1-4 for a sliding velocity [m/s] and a contact pressure [MPa].

    Zone 4 when p > 0.8 H; otherwise 1 for v_s < 0.2, 2 for 0.2 <= v_s <= 0.7, 3 above
    (seed 000 §III; boundaries as in seed 004 Fig. 1).
    """
    v = np.abs(np.asarray(sliding_velocity_m_s, dtype=float))
    p = np.asarray(pressure_mpa, dtype=float)
    v1, v2 = KTH_VELOCITY_LIMITS_M_S
    zone = np.where(v < v1, 1, np.where(v <= v2, 2, 3))
    return np.where(p > KTH_PRESSURE_FRACTION_OF_HARDNESS * hardness_mpa, 4, zone)


def kth_archard_index(normal_force_n: ArrayLike, sliding_velocity_m_s: ArrayLike,
                      rolling_speed_m_s: ArrayLike, pressure_mpa: ArrayLike,
                      hardness_mpa: float = STEEL_HARDNESS_HB * HB_TO_MPA,
                      coefficients: tuple[float, float, float, float] = KTH_COEFFICIENTS
                      ) -> ArchardIndex:
    """Archard wear index with the KTH/Jendel coefficient map (seed 004 eq. 2).

    Parameters
    ----------
    normal_force_n : N [N]
    sliding_velocity_m_s : v_s [m/s] (e.g. ``rigid_sliding_velocity_m_s`` for a whole patch)
    rolling_speed_m_s : v_roll [m/s] (> 0)
    pressure_mpa : contact pressure deciding zone 4 [MPa]; seed 004 uses the average N/A
    hardness_mpa : H of the softer material [MPa] (300 HB by default)
    coefficients : k for zones 1-4 (seed 004 Table 1 by default)

    Returns
    -------
    ArchardIndex with k, zone, regime label and the worn volume per metre rolled [mm^3/m].
    """
    zone = kth_zone(sliding_velocity_m_s, pressure_mpa, hardness_mpa)
    k = np.asarray(coefficients, dtype=float)[zone - 1]
    v_roll = np.asarray(rolling_speed_m_s, dtype=float)
    if np.any(v_roll <= 0):
        raise ValueError("rolling_speed_m_s must be positive")
    slide_per_roll = np.abs(np.asarray(sliding_velocity_m_s, dtype=float)) / v_roll
    # k N [N] / H [N/mm^2] = mm^2; times sliding distance per metre rolled (1000 mm * ratio).
    rate = k * np.asarray(normal_force_n, dtype=float) / hardness_mpa * slide_per_roll * 1000.0
    return ArchardIndex(coefficient=k, zone=zone, regime=_KTH_LABELS[zone],
                        wear_rate_mm3_per_m=rate)


@dataclass(frozen=True)
class KrausePollIndex:
    """Krause-Poll wear index of a contact.

    power_density_w_per_mm2 : frictional power per contact area P/A [W/mm^2]
    coefficient_m3_per_j : C_mild or C_severe [m^3/J]
    regime : "mild" (P/A <= 4 W/mm^2) or "severe"
    wear_rate_mm3_per_m : worn volume per metre rolled, C Tg [mm^3/m]
    """

    power_density_w_per_mm2: NDArray[np.float64]
    coefficient_m3_per_j: NDArray[np.float64]
    regime: NDArray[np.str_]
    wear_rate_mm3_per_m: NDArray[np.float64]


def krause_poll_index(t_gamma_n: ArrayLike, rolling_speed_m_s: ArrayLike,
                      contact_area_mm2: ArrayLike) -> KrausePollIndex:
    """Krause-Poll wear index (seed 004 eq. 1): Delta V = C W_fric, P = Tg v_roll.

    Parameters
    ----------
    t_gamma_n : Tg [N]
    rolling_speed_m_s : v_roll [m/s]
    contact_area_mm2 : A [mm^2] (pi a b for a Hertz patch)

    Returns
    -------
    KrausePollIndex: P/A [W/mm^2], C [m^3/J] (mild up to and including 4 W/mm^2), regime label,
    worn volume per metre rolled C Tg * 1 m [mm^3/m].
    """
    tg = np.asarray(t_gamma_n, dtype=float)
    area = np.asarray(contact_area_mm2, dtype=float)
    if np.any(area <= 0):
        raise ValueError("contact_area_mm2 must be positive")
    density = tg * np.asarray(rolling_speed_m_s, dtype=float) / area
    severe = density > KRAUSE_POLL_TRANSITION_W_PER_MM2
    c = np.where(severe, KRAUSE_POLL_C_SEVERE_M3_PER_J, KRAUSE_POLL_C_MILD_M3_PER_J)
    rate = c * tg * 1e9  # m^3 per metre rolled -> mm^3/m
    return KrausePollIndex(power_density_w_per_mm2=density, coefficient_m3_per_j=c,
                           regime=np.where(severe, "severe", "mild"), wear_rate_mm3_per_m=rate)


def equilibrium_wear_measures(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, fx_n, fy_n, mz_nmm,
                              mu, fastsim_grid: int = 20) -> dict[str, NDArray]:
    """Tγ, τmax and p0 per contact of a curving equilibrium (``curving``); FASTSIM batched
    over the loaded contacts.

    Parameters
    ----------
    xi, eta [-], phi_per_mm [1/mm], a_mm, b_mm [mm], normal_force_n [N], creep forces
    fx_n, fy_n [N] and spin moment mz_nmm [N mm] of the equilibrium: any common shape
    mu : friction coefficient; fastsim_grid : n for the n x n FASTSIM grid

    Returns
    -------
    dict with ``t_gamma_n`` = |Fx xi| + |Fy eta| + |Mz phi| [N] (seed 004 eq. 1),
    ``tau_max_mpa`` the largest surface shear traction of the FASTSIM solution [MPa]
    (elliptic traction bound ``TAU_MAX_BOUND``, CONTACT's flexibilities; seed 001 §2.2,
    Al-Maliki), ``p0_mpa`` the Hertz
    peak pressure 3N/(2 pi a b), ``in_contact`` (loaded with at least 1 N). Unloaded contacts
    get zeros.
    """
    shape = np.shape(normal_force_n)
    fn = np.asarray(normal_force_n, dtype=float).reshape(-1)
    loaded = fn >= 1.0
    flat = [np.broadcast_to(np.asarray(v, dtype=float), shape).reshape(-1)
            for v in (xi, eta, phi_per_mm, a_mm, b_mm, fx_n, fy_n, mz_nmm)]
    t_gamma_n = np.where(loaded, t_gamma(flat[5], flat[6], flat[7], flat[0], flat[1],
                                         flat[2]), 0.0)
    tau = np.zeros(fn.size)
    p0 = np.zeros(fn.size)
    if np.any(loaded):
        sel = [v[loaded] for v in flat[:5]]
        fs = fastsim(sel[0], sel[1], sel[2], sel[3], sel[4], fn[loaded], mu,
                     STEEL_SHEAR_MODULUS_MPA, n_x=fastsim_grid, n_y=fastsim_grid,
                     bound=TAU_MAX_BOUND)
        tau[loaded] = tau_max(fs)
        p0[loaded] = 1.5 * fn[loaded] / (np.pi * sel[3] * sel[4])
    return {"t_gamma_n": t_gamma_n.reshape(shape), "tau_max_mpa": tau.reshape(shape),
            "p0_mpa": p0.reshape(shape), "in_contact": loaded.reshape(shape)}


@dataclass(frozen=True)
class ContactWearMeasures:
    """The wear measures of seed 001 for one batch of FASTSIM patches.

    t_gamma_n [N], tau_max_mpa [MPa], t_gamma_per_area_n_per_mm2 [N/mm^2]
    """

    t_gamma_n: NDArray[np.float64]
    tau_max_mpa: NDArray[np.float64]
    t_gamma_per_area_n_per_mm2: NDArray[np.float64]


def contact_wear_measures(result: FastsimResult, xi: ArrayLike, eta: ArrayLike,
                          phi_per_mm: ArrayLike, a_mm: ArrayLike, b_mm: ArrayLike
                          ) -> ContactWearMeasures:
    """Tg, tau_max (FASTSIM traction) and Tg/A for the patches of a FASTSIM solution."""
    tg = t_gamma(result.fx_n, result.fy_n, result.mz_nmm, xi, eta, phi_per_mm)
    return ContactWearMeasures(t_gamma_n=tg, tau_max_mpa=tau_max(result),
                               t_gamma_per_area_n_per_mm2=t_gamma_per_area(tg, a_mm, b_mm))
