"""Two-axle bogie vehicles for quasi-static curving, with presets and their sources.

A :class:`BogieVehicle` describes ONE bogie and the share of the car body it carries: what the
quasi-static curving model of :mod:`wearcast.physics.curving` needs (wheelbase, wheel radius,
static wheel load, masses for the unbalanced lateral force, primary and secondary stiffnesses,
centre-of-gravity height for the load transfer, profiles, friction, traction torque).

Presets (each value says where it comes from; ``# ASSUMED`` marks an engineering assumption
that no cited source gives):

* ``manchester`` -- the Manchester benchmark passenger vehicle (vehicle 1 of Iwnicki (ed.),
  "The Manchester Benchmarks for Rail Vehicle Simulation", Vehicle System Dynamics Suppl. 31,
  1999). The masses, wheelbase, wheel radius and primary/secondary spring rates are the values
  recalled from that publication (not re-checked against the paper here: treat them as
  "literature values to be confirmed"); the original uses P8 wheels on BS113A rail, which we
  replace by S1002 on 60E1 1:40 (ASSUMED).
* ``metro_b`` -- the type B metro vehicle of seed 000 Table 1 (typed from
  ``reference/published/metro_vehicle_type_b.csv``); suspension rates other than the primary
  vertical one are not printed there and are ASSUMED.
* ``minuetto`` -- a DMU like the ALn 501 Minuetto of seed 003 (masses from seed 003 Table 1,
  S1002 on UIC60 (60E1) inclined 1:20, mu = 0.28 from seed 003 §5.1); geometry and stiffnesses
  are ASSUMED.
* ``aln663`` -- the FIAT ALn 663 diesel railcar of seed 002 (S1002 on UIC60, mu = 0.4 from
  seed 002 §2.1). Published data sheet (rficalabria.altervista.org/aln-663, FS data):
  mass in service 40 t, bogie wheelbase 2,450 mm, bogie pivot distance 15,940 mm, wheel
  diameter 920 mm, axle arrangement (1A)(A1). The split of the 40 t over body, bogies and
  wheelsets and every stiffness are ASSUMED. Seed 002 §2.1 describes the suspension: primary
  flexicoil springs plus a rubber joint on each axle-box control arm, bolsters free to rotate
  under the body (so no secondary yaw stiffness). The primary longitudinal stiffness decides
  whether the tread patches of seed 002's curves are in partial slip or saturated, so
  ``benchmarks/reproduce_seeds.py --only 002`` prints the seed 002 comparison over a range of it.

Each preset offers a ``motor`` and a ``trailer`` variant (:func:`vehicle_preset`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from wearcast.physics.profiles.measured_wheel import MeasuredWheel
from wearcast.physics.profiles.rails import RailShape
from wearcast.physics.vocabulary import BOGIE_TYPES

GRAVITY_M_S2 = 9.81


@dataclass(frozen=True)
class BogieVehicle:
    """One two-axle bogie with its share of the car body.

    Attributes
    ----------
    name : preset or user name
    bogie_type : ``motor`` or ``trailer``
    wheelbase_m : bogie wheelbase 2a [m]
    wheel_radius_m : nominal rolling radius r0 of the new wheel [m]
    wheelset_mass_kg : wheelset mass incl. axle boxes (and motor share for motor bogies) [kg]
    bogie_mass_kg : bogie frame mass [kg]
    body_mass_kg : car-body mass carried by this bogie (incl. payload) [kg]
    primary_longitudinal_stiffness_n_per_m : primary longitudinal stiffness per axle box [N/m]
    primary_lateral_stiffness_n_per_m : primary lateral stiffness per axle box [N/m]
    primary_semi_spacing_m : lateral semi-spacing b1 of the primary springs [m]
    secondary_lateral_stiffness_n_per_m : secondary lateral stiffness per bogie [N/m]
    secondary_yaw_stiffness_nm_per_rad : bogie-to-body yaw stiffness per bogie [N m/rad]
    bogie_centre_distance_m : distance of the two bogie pivots [m] (body chord in curves)
    cog_height_m : height above rail of the centre of gravity of the mass carried by one
        wheelset, used for the load transfer under cant deficiency [m]
    wheel_profile : wheel profile name (``S1002``) or a measured wheel
        (``profiles.measured_wheel.MeasuredWheel``, on every wheel)
    rail_profile : ``60E1`` or ``60E2``, or a measured rail
        (``profiles.measured_rail.MeasuredRail``, placed by its gauge point)
    rail_inclination : rail inclination as a slope (1/40 or 1/20)
    friction : wheel-rail coefficient of friction mu [-]
    traction_torque_nm : driving (+) or braking (-) torque per axle [N m]
    high_rail_profile, low_rail_profile : the outer and the inner rail of every curve when
        they are profiles of their own (a worn high rail, a measured low rail; None:
        ``rail_profile``); tangent track keeps ``rail_profile`` on both sides
        (``curving_table.track_rails``)
    """

    name: str
    bogie_type: str
    wheelbase_m: float
    wheel_radius_m: float
    wheelset_mass_kg: float
    bogie_mass_kg: float
    body_mass_kg: float
    primary_longitudinal_stiffness_n_per_m: float
    primary_lateral_stiffness_n_per_m: float
    primary_semi_spacing_m: float
    secondary_lateral_stiffness_n_per_m: float
    secondary_yaw_stiffness_nm_per_rad: float
    bogie_centre_distance_m: float
    cog_height_m: float
    wheel_profile: str | MeasuredWheel = "S1002"
    rail_profile: str | RailShape = "60E1"
    rail_inclination: float = 1.0 / 40.0
    friction: float = 0.35
    traction_torque_nm: float = 0.0
    high_rail_profile: str | RailShape | None = None
    low_rail_profile: str | RailShape | None = None

    def __post_init__(self) -> None:
        if self.bogie_type not in BOGIE_TYPES:
            raise ValueError(f"bogie_type must be 'motor' or 'trailer', got {self.bogie_type!r}")
        if isinstance(self.wheel_profile, str):
            if self.wheel_profile.upper() != "S1002":
                raise ValueError("wheel_profile must be 'S1002' (or a measured wheel), got "
                                 f"{self.wheel_profile!r}")
        elif not isinstance(self.wheel_profile, MeasuredWheel):
            raise ValueError("wheel_profile must be 'S1002' or a measured wheel "
                             f"(profiles.measured_wheel.MeasuredWheel), got "
                             f"{self.wheel_profile!r}")
        for name in ("rail_profile", "high_rail_profile", "low_rail_profile"):
            rail = getattr(self, name)
            if rail is None and name != "rail_profile":
                continue
            if isinstance(rail, str):
                if rail not in ("60E1", "60E2"):
                    raise ValueError(f"{name} must be '60E1' or '60E2' (or a measured rail), "
                                     f"got {rail!r}")
            elif not callable(getattr(rail, "contact_points", None)):
                raise ValueError(f"{name} must be '60E1', '60E2' or a rail given by its "
                                 "points (profiles.measured_rail.MeasuredRail), got "
                                 f"{rail!r}")
        positive = ("wheelbase_m", "wheel_radius_m", "wheelset_mass_kg", "bogie_mass_kg",
                    "primary_longitudinal_stiffness_n_per_m", "primary_lateral_stiffness_n_per_m",
                    "primary_semi_spacing_m", "friction")
        for field in positive:
            if not getattr(self, field) > 0:
                raise ValueError(f"{field} must be positive, got {getattr(self, field)}")
        for field in ("body_mass_kg", "secondary_lateral_stiffness_n_per_m",
                      "secondary_yaw_stiffness_nm_per_rad", "cog_height_m",
                      "bogie_centre_distance_m", "rail_inclination"):
            if getattr(self, field) < 0:
                raise ValueError(f"{field} must be >= 0, got {getattr(self, field)}")

    @property
    def semi_wheelbase_m(self) -> float:
        """Half the wheelbase a [m]."""
        return 0.5 * self.wheelbase_m

    @property
    def wheel_load_n(self) -> float:
        """Static vertical wheel load Q [N]: (body share + bogie + 2 wheelsets) g / 4."""
        total = self.body_mass_kg + self.bogie_mass_kg + 2.0 * self.wheelset_mass_kg
        return total * GRAVITY_M_S2 / 4.0

    @property
    def mass_per_wheelset_kg(self) -> float:
        """Mass whose unbalanced lateral force one wheelset carries [kg]."""
        return 0.5 * (self.body_mass_kg + self.bogie_mass_kg) + self.wheelset_mass_kg

    def with_(self, **changes: object) -> BogieVehicle:
        """A copy with some fields changed (e.g. ``friction=0.2``)."""
        return replace(self, **changes)  # type: ignore[arg-type]


# --- Manchester benchmark vehicle 1 (Iwnicki 1999) -------------------------------------------
# Literature values (recalled, to be confirmed against the paper): body 32 000 kg, bogie frame
# 2 615 kg, wheelset 1 813 kg, wheel radius 0.46 m, wheelbase 2.56 m, bogie centres 19 m,
# primary per axle box kx = 31.391 MN/m, ky = 3.884 MN/m at lateral semi-spacing 1.0 m,
# secondary per side kx = ky = 0.16 MN/m at semi-spacing 1.0 m (yaw 2 kx b2^2 = 0.32 MN m/rad).
_MANCHESTER_TRAILER = BogieVehicle(
    name="manchester",
    bogie_type="trailer",
    wheelbase_m=2.56,
    wheel_radius_m=0.46,
    wheelset_mass_kg=1813.0,
    bogie_mass_kg=2615.0,
    body_mass_kg=16_000.0,  # half of the 32 000 kg body
    primary_longitudinal_stiffness_n_per_m=31.391e6,
    primary_lateral_stiffness_n_per_m=3.884e6,
    primary_semi_spacing_m=1.0,
    secondary_lateral_stiffness_n_per_m=2 * 0.16e6,
    secondary_yaw_stiffness_nm_per_rad=2 * 0.16e6 * 1.0**2,
    bogie_centre_distance_m=19.0,
    cog_height_m=1.5,  # ASSUMED: mass-weighted CoG of body (~1.8 m) and bogie/wheelsets
    rail_profile="60E1",  # ASSUMED: benchmark uses BS113A 1:20; S1002/60E1 1:40 here
    rail_inclination=1.0 / 40.0,
    friction=0.35,  # ASSUMED: the value of seed 001's simulations
)
_MANCHESTER_MOTOR = replace(
    _MANCHESTER_TRAILER,
    bogie_type="motor",
    wheelset_mass_kg=1813.0 + 700.0,  # ASSUMED: axle-hung share of a traction motor/gearbox
    bogie_mass_kg=2615.0 + 1500.0,  # ASSUMED: motors and gearboxes on the frame
    primary_longitudinal_stiffness_n_per_m=1.5 * 31.391e6,  # ASSUMED: stiffer primary yaw
)

# --- Type B metro, seed 000 Table 1 ------------------------------------------------------------
# Printed (seed 000 Table 1): wheelset 1018 kg, axle box 110 kg, frame 2103 kg, wheelbase
# 2300 mm, bogie centres 12 600 mm, primary vertical 1.3 MN/m, wheel diameter 840 mm, mu 0.4,
# 60 kg/m rail inclined 1:40, body load 25.3 t (line 1 model) / 32.7 t (line 2 model).
_METRO_B_TRAILER = BogieVehicle(
    name="metro_b",
    bogie_type="trailer",
    wheelbase_m=2.300,
    wheel_radius_m=0.840 / 2,
    wheelset_mass_kg=1018.0 + 2 * 110.0,  # wheelset + two axle boxes
    bogie_mass_kg=2103.0,
    body_mass_kg=25_300.0 / 2,  # line-1 body load shared by two bogies
    primary_longitudinal_stiffness_n_per_m=12.0e6,  # ASSUMED: typical rubber-spring metro
    primary_lateral_stiffness_n_per_m=5.0e6,  # ASSUMED
    primary_semi_spacing_m=1.0,  # ASSUMED
    secondary_lateral_stiffness_n_per_m=2 * 0.2e6,  # ASSUMED: air springs
    secondary_yaw_stiffness_nm_per_rad=2 * 0.2e6 * 1.0**2,  # ASSUMED
    bogie_centre_distance_m=12.6,
    cog_height_m=1.2,  # ASSUMED
    rail_profile="60E1",  # "60 kg/m inclined 1:40"; the seed's LM wheel is replaced by S1002
    rail_inclination=1.0 / 40.0,
    friction=0.4,
)
_METRO_B_MOTOR = replace(
    _METRO_B_TRAILER,
    bogie_type="motor",
    wheelset_mass_kg=1018.0 + 2 * 110.0 + 400.0,  # ASSUMED: gearbox / motor share
    bogie_mass_kg=2103.0 + 1400.0,  # ASSUMED: two traction motors on the frame
    primary_longitudinal_stiffness_n_per_m=1.5 * 12.0e6,  # ASSUMED: stiffer primary yaw
)

# --- DMU like the ALn 501 Minuetto, seed 003 Table 1 -------------------------------------------
# Printed (seed 003 Table 1): coach motor 31 568 kg, coach trailer 14 496 kg, bogie motor
# 3 306 kg, bogie trailer 3 122 kg, wheelset motor 2 091 kg, wheelset trailer 1 462 kg (total
# 104 700 kg). Three coaches on four bogies: each motor coach on one motor bogie and one
# intermediate (Jacobs) trailer bogie, so a motor bogie carries half a motor coach and a trailer
# bogie half a motor coach plus half the trailer coach (the masses then add up to 104 700 kg).
_MINUETTO_TRAILER = BogieVehicle(
    name="minuetto",
    bogie_type="trailer",
    wheelbase_m=2.40,  # ASSUMED
    wheel_radius_m=0.43,  # ASSUMED
    wheelset_mass_kg=1462.0,
    bogie_mass_kg=3122.0,
    body_mass_kg=31_568.0 / 2 + 14_496.0 / 2,
    primary_longitudinal_stiffness_n_per_m=10.0e6,  # ASSUMED
    primary_lateral_stiffness_n_per_m=4.0e6,  # ASSUMED
    primary_semi_spacing_m=1.0,  # ASSUMED
    secondary_lateral_stiffness_n_per_m=2 * 0.2e6,  # ASSUMED
    secondary_yaw_stiffness_nm_per_rad=2 * 0.2e6 * 1.0**2,  # ASSUMED
    bogie_centre_distance_m=14.0,  # ASSUMED
    cog_height_m=1.4,  # ASSUMED
    rail_profile="60E1",  # seed 003: UIC60
    rail_inclination=1.0 / 20.0,  # seed 003: canted at 1/20
    friction=0.28,  # seed 003 §5.1: mu_c = 0.28
)
_MINUETTO_MOTOR = replace(
    _MINUETTO_TRAILER,
    bogie_type="motor",
    wheelset_mass_kg=2091.0,
    bogie_mass_kg=3306.0,
    body_mass_kg=31_568.0 / 2,
    primary_longitudinal_stiffness_n_per_m=1.5 * 10.0e6,  # ASSUMED: stiffer primary yaw
)

# --- FIAT ALn 663 railcar, seed 002 ----------------------------------------------------------
# Published (data sheet, see the module docstring): 40 t in service, bogie wheelbase 2.45 m,
# pivots 15.94 m apart, wheels 920 mm. Each bogie carries 20 t; the leading (outer) axle of each
# (1A) bogie is the non-powered one whose right wheel seed 002 tracks.
_ALN663_TRAILER = BogieVehicle(
    name="aln663",
    bogie_type="trailer",
    wheelbase_m=2.45,
    wheel_radius_m=0.920 / 2,
    wheelset_mass_kg=1300.0,  # ASSUMED
    bogie_mass_kg=2500.0,  # ASSUMED
    body_mass_kg=40_000.0 / 2 - 2500.0 - 2 * 1300.0,  # the rest of a bogie's 20 t
    primary_longitudinal_stiffness_n_per_m=2.0e6,  # ASSUMED: rubber joint of the control arm
    primary_lateral_stiffness_n_per_m=0.7e6,  # ASSUMED: flexicoil shear stiffness
    primary_semi_spacing_m=1.0,  # ASSUMED
    secondary_lateral_stiffness_n_per_m=2 * 0.15e6,  # ASSUMED: secondary flexicoils
    secondary_yaw_stiffness_nm_per_rad=0.0,  # seed 002 §2.1: bolster rotation free
    bogie_centre_distance_m=15.94,
    cog_height_m=1.3,  # ASSUMED
    rail_profile="60E1",  # seed 002: UIC60
    # ASSUMED: seed 002 does not print it. With 1:40 its route gives a global worn volume of
    # 86 mm^3 against the seed's 56.3 (Table 2); with 1:20 (RFI practice, seed 003) 432 mm^3.
    rail_inclination=1.0 / 40.0,
    friction=0.4,  # seed 002 §2.1
)
_ALN663_MOTOR = replace(
    _ALN663_TRAILER,
    bogie_type="motor",
    wheelset_mass_kg=1300.0 + 400.0,  # ASSUMED: final drive share on the powered axle
)

PRESETS: dict[str, dict[str, BogieVehicle]] = {
    "aln663": {"motor": _ALN663_MOTOR, "trailer": _ALN663_TRAILER},
    "manchester": {"motor": _MANCHESTER_MOTOR, "trailer": _MANCHESTER_TRAILER},
    "metro_b": {"motor": _METRO_B_MOTOR, "trailer": _METRO_B_TRAILER},
    "minuetto": {"motor": _MINUETTO_MOTOR, "trailer": _MINUETTO_TRAILER},
}


def preset_names() -> list[str]:
    """Names of the vehicle presets."""
    return sorted(PRESETS)


def vehicle_preset(name: str, bogie_type: str = "trailer",
                   traction_torque_nm: float | None = None) -> BogieVehicle:
    """A preset bogie vehicle.

    Parameters
    ----------
    name : ``aln663``, ``manchester``, ``metro_b`` or ``minuetto``
    bogie_type : ``motor`` or ``trailer``
    traction_torque_nm : optional driving (+) / braking (-) torque per axle [N m]; only a motor
        bogie can drive (a trailer accepts a negative, braking torque)

    Returns
    -------
    BogieVehicle
    """
    if name not in PRESETS:
        raise ValueError(f"unknown vehicle preset {name!r}; known: {', '.join(preset_names())}")
    if bogie_type not in PRESETS[name]:
        raise ValueError(f"bogie_type must be 'motor' or 'trailer', got {bogie_type!r}")
    vehicle = PRESETS[name][bogie_type]
    if traction_torque_nm is not None:
        if bogie_type == "trailer" and traction_torque_nm > 0:
            raise ValueError("a trailer bogie cannot apply a driving torque (only braking, < 0)")
        vehicle = replace(vehicle, traction_torque_nm=float(traction_torque_nm))
    return vehicle
