"""Wear laws: worn volume per metre rolled of a wheel-rail contact patch.

Four laws, each a pure function of contact quantities, vectorised over any batch shape:

* Archard with the KTH/Jendel wear map (seeds 000 §III, 002 §2.2, 004 eq. 2 and Table 1):
  Delta V = k(v_s, p) N s_slide / H. Zones by sliding speed (v1 = 0.2, v2 = 0.7 m/s) and by the
  contact pressure against 0.8 H (zone 4, seizure). Configurable coefficients, zone bounds,
  hardness and a contamination factor that divides the map's nominal values (seed 002 §2.2
  divides by 7). Seed 004 Table 1 (1.43e-4, 1e-3, 1.43e-4, 1e-2) equals seed 000's map means
  (5e-4, 35e-4, 5e-4, 350e-4) doubled (wheel AND rail, seed 004 §2.1) and divided by 7:
  :meth:`ArchardKTH.from_map_means` rebuilds it. The zone split is also returned as a linear
  basis (volume per unit coefficient, one column per zone): worn volume is linear in the zone
  coefficients, which the exact calibration of ``statistics.coefficient_fit`` exploits.
* Krause-Poll (seed 004 eq. 1): Delta V = C W_fric with C_mild / C_severe split at
  P/A = 4 W/mm^2; reuses :func:`wearcast.physics.wear_measures.krause_poll_index`.
* USFD-type energy law (seed 003 eq. 1): wear rate K_w(I_w) [ug/(m mm^2)] of the wear index
  I_w = T gamma / A [N/mm^2]; K_w = 5.3 I_w (I_w < 10.4), 55.1 (10.4 <= I_w <= 77.2),
  61.9 I_w - 4778.7 (I_w > 77.2). THE JUMP: as printed, the third branch starts at
  61.9 * 77.2 - 4778.7 = -0.02, i.e. the rate falls from 55.1 to zero at 77.2 N/mm^2 and only
  regains 55.1 at I_w = 78.09. ``usfd_jump="continuous"`` (default) keeps 55.1 until the line
  crosses it (K_w = max(55.1, 61.9 I_w - 4778.7) for I_w > 77.2: continuous and monotonic);
  ``"as_printed"`` reproduces the printed law (clipped at 0, never negative).
  Mass to volume with the steel density 7.85 g/cm^3 = 7850 ug/mm^3.
* tau_max law (the hypothesis of seed 001: wear grows with the maximum surface shear traction
  of the FASTSIM solution, ``wear_measures.tau_max``): Delta V / Delta s = c_tau
  (tau_max - tau_0)_+ A, c_tau [mm/(m MPa)], threshold tau_0 [MPa]. No paper publishes c_tau:
  fit it to measured wear with ``statistics.coefficient_fit.calibrate`` (``law="tau_max"``;
  ``POST /v1/coefficient-fits`` with ``law: "tau_max"``); the default is a placeholder.

All laws return the worn volume per metre rolled [mm^3/m]; the caller multiplies by the
distance. Velocities in m/s, forces N, pressures MPa (N/mm^2), lengths mm.

Wheel and rail (:func:`wheel_rail_split`): each law's volume is attributed to the bodies by the
law's own definition. KTH/Jendel's map values are the wear of ONE body (the wheel; seed 004
§2.1: "given for the wheel only"), and seed 004 Table 1 (our default) doubles them for the
wheel-rail system, so a volume computed with ``coefficient_scope="wheel_and_rail"`` is shared
half and half, with ``"per_body"`` each body loses the full volume. The USFD law is "the same
both for the wheel and for the rail" (seed 003 §4.2): each body loses the full volume.
Krause-Poll's C is taken per body (ASSUMED: seed 004 quotes UniFi's values without a scope);
the tau_max law is fitted to wheel wear, so the wheel loses the full volume and the rail the
same (ASSUMED).

Local application (:func:`element_depth_rate_mm_per_m`): every law is also written per element
of the FASTSIM grid, as a depth rate per metre travelled while the element is in contact
[mm/m], from the element's frictional power index I = |p_t| |s| [N/mm^2] (seed 003 eq. 1:
I_w = p s / V with the element's shear traction p_t and slip s = v_slide / V), its pressure and
shear traction.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.wear_measures import (
    HB_TO_MPA,
    KRAUSE_POLL_C_MILD_M3_PER_J,
    KRAUSE_POLL_C_SEVERE_M3_PER_J,
    KRAUSE_POLL_TRANSITION_W_PER_MM2,
    KTH_COEFFICIENTS,
    KTH_PRESSURE_FRACTION_OF_HARDNESS,
    KTH_VELOCITY_LIMITS_M_S,
    STEEL_HARDNESS_HB,
    krause_poll_index,
)

#: Seed 000 §III/§VI: means of the Jendel/KTH map ranges per zone (nominal, wheel only) [-].
JENDEL_MAP_MEANS = (5e-4, 35e-4, 5e-4, 350e-4)
#: Seed 002 §2.2: reduction of the map values for natural contamination (divide by 7).
CONTAMINATION_FACTOR_SEED_002 = 7.0
#: Seed 004 §2.1: SIMPACK's coefficients are for wheel and rail together: twice KTH's.
WHEEL_AND_RAIL_FACTOR = 2.0
#: Steel density [ug/mm^3] (7.85 g/cm^3).
STEEL_DENSITY_UG_PER_MM3 = 7850.0
#: USFD-type law (seed 003 eq. 1): regime bounds [N/mm^2] and coefficients [ug/(m mm^2)].
USFD_BOUNDS_N_PER_MM2 = (10.4, 77.2)
USFD_MILD_SLOPE = 5.3
USFD_SEVERE_VALUE = 55.1
USFD_CATASTROPHIC = (61.9, -4778.7)
#: PLACEHOLDER c_tau of the tau_max law [mm/(m MPa)]: of the order of Archard's mild regime on a
#: tread patch, published nowhere. Replace it by a fitted value (``statistics.coefficient_fit``).
TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA = 1e-6

#: Scopes of a coefficient: the wear of one body, or of the wheel and rail together.
COEFFICIENT_SCOPES = ("per_body", "wheel_and_rail")

UsfdJump = Literal["continuous", "as_printed"]
LawName = Literal["archard_kth", "krause_poll", "usfd", "tau_max"]
LAW_NAMES: tuple[LawName, ...] = get_args(LawName)


@dataclass(frozen=True)
class ArchardKTH:
    """Archard's law with the KTH/Jendel map.

    coefficients : k for zones 1-4 as USED (after the contamination factor) [-]
    velocity_limits_m_s : (v1, v2) sliding-speed zone bounds [m/s]
    pressure_fraction : seizure when p > pressure_fraction * H [-] (0.8, seed 000)
    hardness_mpa : H [MPa] (300 HB by default, seed 002)
    contamination_factor : divides ``coefficients`` (1 = use them as given)
    coefficient_scope : ``wheel_and_rail`` (the coefficients give the volume of wheel and rail
        together, as seed 004 Table 1, the default: each body loses half) or ``per_body``
        (KTH's own map values, the wear of one body: each loses the full volume)
    """

    coefficients: tuple[float, float, float, float] = KTH_COEFFICIENTS
    velocity_limits_m_s: tuple[float, float] = KTH_VELOCITY_LIMITS_M_S
    pressure_fraction: float = KTH_PRESSURE_FRACTION_OF_HARDNESS
    hardness_mpa: float = STEEL_HARDNESS_HB * HB_TO_MPA
    contamination_factor: float = 1.0
    coefficient_scope: str = "wheel_and_rail"

    def __post_init__(self) -> None:
        if self.coefficient_scope not in COEFFICIENT_SCOPES:
            raise ValueError(f"coefficient_scope must be one of {', '.join(COEFFICIENT_SCOPES)}"
                             f", got {self.coefficient_scope!r}")
        if len(self.coefficients) != 4 or any(c < 0 for c in self.coefficients):
            raise ValueError("coefficients must be four non-negative numbers (zones 1-4)")
        v1, v2 = self.velocity_limits_m_s
        if not 0 < v1 < v2:
            raise ValueError("velocity_limits_m_s must satisfy 0 < v1 < v2")
        if self.hardness_mpa <= 0 or self.pressure_fraction <= 0:
            raise ValueError("hardness_mpa and pressure_fraction must be positive")
        if self.contamination_factor <= 0:
            raise ValueError("contamination_factor must be positive")

    @classmethod
    def from_map_means(cls, means: tuple[float, float, float, float] = JENDEL_MAP_MEANS,
                       contamination_factor: float = CONTAMINATION_FACTOR_SEED_002,
                       wheel_and_rail_factor: float = WHEEL_AND_RAIL_FACTOR) -> ArchardKTH:
        """Coefficients from the KTH map's nominal zone means (seed 000), doubled for the
        wheel-rail system (seed 004 §2.1) and divided by the contamination factor (seed 002).
        A factor other than 1 makes the scope ``wheel_and_rail``; 1 keeps KTH's ``per_body``."""
        scope = "per_body" if wheel_and_rail_factor == 1.0 else "wheel_and_rail"
        return cls(coefficients=tuple(m * wheel_and_rail_factor for m in means),  # type: ignore
                   contamination_factor=contamination_factor, coefficient_scope=scope)

    @property
    def effective_coefficients(self) -> NDArray[np.float64]:
        """k per zone after the contamination factor [-], shape (4,)."""
        return np.asarray(self.coefficients, dtype=float) / self.contamination_factor

    def with_coefficients(self, coefficients: ArrayLike) -> ArchardKTH:
        """Same map with new effective coefficients (contamination factor reset to 1)."""
        k = tuple(float(c) for c in np.asarray(coefficients, dtype=float).reshape(4))
        return replace(self, coefficients=k, contamination_factor=1.0)  # type: ignore[arg-type]


def kth_zone(sliding_velocity_m_s: ArrayLike, pressure_mpa: ArrayLike,
             law: ArchardKTH = ArchardKTH()) -> NDArray[np.int_]:
    """Zone 1-4 of the KTH map (seed 000 §III) for v_s [m/s] and pressure [MPa]."""
    v = np.abs(np.asarray(sliding_velocity_m_s, dtype=float))
    p = np.asarray(pressure_mpa, dtype=float)
    v1, v2 = law.velocity_limits_m_s
    zone = np.where(v < v1, 1, np.where(v <= v2, 2, 3))
    return np.where(p > law.pressure_fraction * law.hardness_mpa, 4, zone)


def archard_basis(normal_force_n: ArrayLike, sliding_velocity_m_s: ArrayLike,
                  rolling_speed_m_s: ArrayLike, pressure_mpa: ArrayLike,
                  law: ArchardKTH = ArchardKTH()) -> NDArray[np.float64]:
    """Archard worn volume per metre rolled PER UNIT zone coefficient [mm^3/m], shape S + (4,).

    N [N] / H [MPa] times the sliding distance per metre rolled 1000 |v_s| / v_roll [mm/m],
    placed in the column of the contact's zone (others 0). ``basis @ k`` is the volume rate.
    Seed 004 eq. (2); the pressure decides zone 4 (seed 004 uses the mean N / (pi a b)).
    """
    v_roll = np.asarray(rolling_speed_m_s, dtype=float)
    if np.any(v_roll <= 0):
        raise ValueError("rolling_speed_m_s must be positive")
    zone = kth_zone(sliding_velocity_m_s, pressure_mpa, law)
    value = (np.asarray(normal_force_n, dtype=float) / law.hardness_mpa
             * np.abs(np.asarray(sliding_velocity_m_s, dtype=float)) / v_roll * 1000.0)
    value, zone = np.broadcast_arrays(value, zone)
    return np.where(zone[..., None] == np.arange(1, 5), value[..., None], 0.0)


def archard_kth_rate(normal_force_n: ArrayLike, sliding_velocity_m_s: ArrayLike,
                     rolling_speed_m_s: ArrayLike, pressure_mpa: ArrayLike,
                     law: ArchardKTH = ArchardKTH()) -> NDArray[np.float64]:
    """Archard/KTH worn volume per metre rolled [mm^3/m] (seed 004 eq. 2, seed 000 §III)."""
    return archard_basis(normal_force_n, sliding_velocity_m_s, rolling_speed_m_s, pressure_mpa,
                         law) @ law.effective_coefficients


def krause_poll_rate(t_gamma_n: ArrayLike, rolling_speed_m_s: ArrayLike,
                     contact_area_mm2: ArrayLike) -> NDArray[np.float64]:
    """Krause-Poll worn volume per metre rolled [mm^3/m] (seed 004 eq. 1); see
    :func:`wearcast.physics.wear_measures.krause_poll_index` for the regimes."""
    return krause_poll_index(t_gamma_n, rolling_speed_m_s, contact_area_mm2).wear_rate_mm3_per_m


def usfd_coefficient(wear_index_n_per_mm2: ArrayLike, jump: UsfdJump = "continuous"
                     ) -> NDArray[np.float64]:
    """USFD-type wear rate K_w [ug/(m mm^2)] of I_w = T gamma / A [N/mm^2] (seed 003 eq. 1).

    ``jump="continuous"`` (default): K_w = max(55.1, 61.9 I_w - 4778.7) above 77.2 N/mm^2,
    which removes the printed law's drop to ~0 at 77.2 (module docstring);
    ``"as_printed"``: the printed branches, clipped at zero.
    """
    if jump not in ("continuous", "as_printed"):
        raise ValueError(f"jump must be 'continuous' or 'as_printed', got {jump!r}")
    iw = np.asarray(wear_index_n_per_mm2, dtype=float)
    if np.any(iw < 0):
        raise ValueError("the wear index must be >= 0")
    lo, hi = USFD_BOUNDS_N_PER_MM2
    slope, offset = USFD_CATASTROPHIC
    top = slope * iw + offset
    top = np.maximum(top, USFD_SEVERE_VALUE) if jump == "continuous" else np.maximum(top, 0.0)
    return np.where(iw < lo, USFD_MILD_SLOPE * iw, np.where(iw <= hi, USFD_SEVERE_VALUE, top))


def usfd_rate(t_gamma_n: ArrayLike, contact_area_mm2: ArrayLike, jump: UsfdJump = "continuous"
              ) -> NDArray[np.float64]:
    """USFD-type worn volume per metre rolled [mm^3/m]: K_w(Tg/A) A / rho (seed 003 eq. 1)."""
    area = np.asarray(contact_area_mm2, dtype=float)
    if np.any(area <= 0):
        raise ValueError("contact_area_mm2 must be positive")
    iw = np.asarray(t_gamma_n, dtype=float) / area
    return usfd_coefficient(iw, jump) * area / STEEL_DENSITY_UG_PER_MM3


def tau_max_rate(tau_max_mpa: ArrayLike, contact_area_mm2: ArrayLike,
                 coefficient_mm_per_m_mpa: float = TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA,
                 threshold_mpa: float = 0.0
                 ) -> NDArray[np.float64]:
    """tau_max law: worn volume per metre rolled c (tau_max - tau_0)_+ A [mm^3/m].

    tau_max [MPa] is the FASTSIM maximum shear traction (``wear_measures.tau_max``); A [mm^2];
    c [mm/(m MPa)] must be calibrated (the default is
    ``TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA``, a placeholder; fit c with
    ``statistics.coefficient_fit.calibrate(..., law="tau_max")``).
    """
    if coefficient_mm_per_m_mpa < 0 or threshold_mpa < 0:
        raise ValueError("coefficient and threshold must be >= 0")
    excess = np.maximum(np.asarray(tau_max_mpa, dtype=float) - threshold_mpa, 0.0)
    return coefficient_mm_per_m_mpa * excess * np.asarray(contact_area_mm2, dtype=float)


@dataclass(frozen=True)
class WearLaw:
    """A wear law and its parameters, as the wear loop takes it.

    name : ``archard_kth`` | ``krause_poll`` | ``usfd`` | ``tau_max``
    archard : map and coefficients for ``archard_kth``
    usfd_jump : treatment of the USFD jump at 77.2 N/mm^2
    tau_coefficient_mm_per_m_mpa, tau_threshold_mpa : parameters of the tau_max law, c_tau
        [mm/(m MPa)] and tau_0 [MPa]. The default c_tau (1e-6,
        ``TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA``) is a PLACEHOLDER, published nowhere: take
        c_tau from the calibration of ``statistics.coefficient_fit`` (``CalibrationProblem(...,
        law="tau_max", tau_threshold_mpa=tau_0)`` then ``calibrate``; or ``POST
        /v1/coefficient-fits`` / ``wearcast fit-coefficients --law tau_max``), which fits c_tau
        to measured wear for the given tau_0 (the result's ``c_tau_mm_per_m_mpa``).
    """

    name: str = "archard_kth"
    archard: ArchardKTH = field(default_factory=ArchardKTH)
    usfd_jump: str = "continuous"
    tau_coefficient_mm_per_m_mpa: float = TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA
    tau_threshold_mpa: float = 0.0

    def __post_init__(self) -> None:
        if self.name not in LAW_NAMES:
            raise ValueError(f"unknown wear law {self.name!r}; known: {', '.join(LAW_NAMES)}")
        if self.usfd_jump not in ("continuous", "as_printed"):
            raise ValueError("usfd_jump must be 'continuous' or 'as_printed'")



def wheel_rail_split(law: WearLaw) -> tuple[float, float]:
    """Fractions of the law's worn volume removed from the wheel and from the rail [-].

    Archard/KTH: (0.5, 0.5) for ``coefficient_scope="wheel_and_rail"`` (seed 004 §2.1: its
    coefficients are twice KTH's, which are for the wheel only), (1, 1) for ``per_body``.
    USFD: (1, 1) (seed 003 §4.2: K_w is "the same both for the wheel and for the rail").
    Krause-Poll and tau_max: (1, 1) (ASSUMED, module docstring).
    """
    if law.name == "archard_kth" and law.archard.coefficient_scope == "wheel_and_rail":
        return 0.5, 0.5
    return 1.0, 1.0


def element_depth_rate_mm_per_m(law: WearLaw, shear_traction_mpa: ArrayLike, slip: ArrayLike,
                                pressure_mpa: ArrayLike, rolling_speed_m_s: ArrayLike
                                ) -> NDArray[np.float64]:
    """Local form of every law: normal depth per metre travelled while a surface element is in
    contact [mm/m] (multiply by the element length dx / 1000 for the depth of one passage).

    shear_traction_mpa : |p_t| [MPa]; slip : |v_slide| / V [-] (0 in adhesion);
    pressure_mpa : p [MPa]; rolling_speed_m_s : V [m/s] (broadcast).

    * USFD (seed 003 eq. 1 per element): K_w(I) / rho, I = |p_t| s [N/mm^2].
    * Krause-Poll (seed 004 eq. 1 per element): C I 1e9 with the frictional work per metre and
      mm^2, I [J/(m mm^2)]; C severe where the power density I V > 4 W/mm^2.
    * tau_max: c_tau (|p_t| - tau_0)_+ on elements that slip.
    * Archard/KTH: k p 1000 s / H with the element's zone (``local_archard_depth`` keeps the
      zone basis for the calibration).

    Volume: integrating these rates over a uniform patch reproduces the global laws (tested).
    """
    pt = np.abs(np.asarray(shear_traction_mpa, dtype=float))
    s = np.abs(np.asarray(slip, dtype=float))
    p = np.asarray(pressure_mpa, dtype=float)
    v = np.asarray(rolling_speed_m_s, dtype=float)
    index = pt * s                                               # N/mm^2 = J/(m mm^2)
    if law.name == "usfd":
        jump: UsfdJump = "as_printed" if law.usfd_jump == "as_printed" else "continuous"
        return usfd_coefficient(index, jump) / STEEL_DENSITY_UG_PER_MM3
    if law.name == "krause_poll":
        c = np.where(index * v > KRAUSE_POLL_TRANSITION_W_PER_MM2,
                     KRAUSE_POLL_C_SEVERE_M3_PER_J, KRAUSE_POLL_C_MILD_M3_PER_J)
        return c * index * 1e9
    if law.name == "tau_max":
        return np.where(s > 0, law.tau_coefficient_mm_per_m_mpa
                        * np.maximum(pt - law.tau_threshold_mpa, 0.0), 0.0)
    zone = kth_zone(s * v, p, law.archard)
    k = law.archard.effective_coefficients[zone - 1]
    return k * p * 1000.0 * s / law.archard.hardness_mpa
