"""Request and response bodies of the ``/v1`` contract (pydantic v2), one family per resource.

Numbers must be finite (NaN/inf are refused), unknown fields are refused, and enumerations
accept only their documented values, so every bad input is a 422 naming its field.
"""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from wearcast.physics.vocabulary import (
    Axle,
    BogieType,
    Direction,
    Region,
    RunningMode,
    Side,
    Wheelset,
)
from wearcast.physics.vocabulary import WearMeasure as Measure

FilterValue = str | int | float | bool | None
Filter = dict[str, FilterValue | list[FilterValue]]


#: Largest mileage [km] accepted anywhere (a wheel runs a few million km in its life).
MAX_MILEAGE_KM = 1e8
#: Most points of one measured profile (instruments give a few hundred to a few thousand).
MAX_PROFILE_POINTS = 20_000


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


# --- routes -----------------------------------------------------------------------------

class RouteClassIn(Strict):
    radius_m: float | None = Field(default=None, gt=0, description="radius [m]; null = tangent")
    direction: Direction | None = Field(default=None, description="side the track bends towards")
    cant_mm: float = Field(default=0.0, ge=0, le=250, description="cant [mm]")
    speed_kmh: float = Field(gt=0, le=500, description="running speed [km/h]")
    share: float = Field(ge=0, le=1, description="share of the route's length [-]")

    @model_validator(mode="after")
    def _direction_for_curves(self) -> RouteClassIn:
        if self.radius_m is not None and self.direction is None:
            raise ValueError("a curve class (radius_m given) needs a direction: left or right")
        return self


class SegmentIn(Strict):
    length_m: float = Field(gt=0, description="segment length [m]")
    radius_m: float | None = Field(default=None, gt=0, description="radius [m]; null = tangent")
    direction: Direction | None = None
    cant_mm: float = Field(default=0.0, ge=0, le=250)
    speed_kmh: float = Field(gt=0, le=500)

    @model_validator(mode="after")
    def _direction_for_curves(self) -> SegmentIn:
        if self.radius_m is not None and self.direction is None:
            raise ValueError("a curved segment (radius_m given) needs a direction: left or right")
        return self


class RouteSpec(Strict):
    """A route given inline: curve classes or segments (exactly one of them)."""

    classes: list[RouteClassIn] | None = Field(default=None, min_length=1)
    segments: list[SegmentIn] | None = Field(default=None, min_length=1)
    attributes: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _one_of(self) -> RouteSpec:
        if (self.classes is None) == (self.segments is None):
            raise ValueError("give either classes or segments (exactly one)")
        return self


class RouteIn(RouteSpec):
    name: str = Field(min_length=1, max_length=200)

    @field_validator("name")
    @classmethod
    def _not_numeric(cls, name: str) -> str:
        if name.strip().isdigit():
            raise ValueError("a route name must not be a bare number (numbers are route ids)")
        return name.strip()


class RouteClassOut(BaseModel):
    radius_m: float | None
    direction: str | None
    cant_mm: float
    speed_kmh: float
    share: float


class RouteOut(BaseModel):
    id: int
    name: str
    classes: list[RouteClassOut]
    segments: list[dict[str, Any]] | None = None
    attributes: dict[str, Any]


# --- wear tables ------------------------------------------------------------------------

class WearTableRowOut(BaseModel):
    bogie_type: str
    wheelset: str
    rail: str
    radius_m: float | None
    region: str
    measure: str
    value: float


class WearTableOut(BaseModel):
    id: int
    name: str
    source: str
    sha256: str
    n_rows: int
    kind: str = "uploaded"
    spec: dict[str, Any] | None = None
    rows: list[WearTableRowOut] | None = None


class VehiclePairIn(Strict):
    """Two presets: the motor bogie of one and the trailer bogie of another (or the same)."""

    motor: str = Field(min_length=1, max_length=50, description="preset for the motor bogie")
    trailer: str = Field(min_length=1, max_length=50, description="preset for the trailer bogie")


class RadiusIn(Strict):
    radius_m: float | None = Field(gt=0, le=1e6, description="radius [m]; null = tangent")
    cant_mm: float = Field(default=0.0, ge=0, le=250, description="cant [mm]")
    speed_kmh: float | None = Field(default=None, gt=0, le=500, description=(
        "speed [km/h]; null = from the unbalanced lateral acceleration"))
    share: float | None = Field(default=None, ge=0, le=1, description="share of the route [-]")


class MeasuredProfileIn(Strict):
    """A measured wheel profile given as points in the wheel frame [mm] (y from the tape
    circle, back face at -70; z up, 0 at the tape circle), placed by its own datum."""

    y_mm: list[float] = Field(min_length=20, max_length=20000)
    z_mm: list[float] = Field(min_length=20, max_length=20000)
    mileage_km: float = Field(0.0, ge=0)
    reference_profile: str = "S1002"


class MeasuredProfilesIn(Strict):
    """The measured wheel and rail a physics request may use instead of the preset's S1002 on
    its nominal rail (``POST /v1/wear-tables/compute``, ``POST /v1/simulations``)."""

    rail_id: int | None = Field(default=None, ge=1, description=(
        "a stored measured rail (GET /v1/rails) in place of the preset's nominal rail, on "
        "both sides, placed by its gauge point"))
    measurement_id: int | None = Field(default=None, ge=1, le=2**62, description=(
        "a stored profile measurement whose wheel replaces the preset's S1002 on every wheel "
        "(a table) or starts the simulated wheel (a simulation), placed by the instrument's "
        "datum when the import found one"))
    wheel_id: str | None = Field(default=None, min_length=1, max_length=200, description=(
        "as measurement_id, with the wheel's latest measured profile"))
    profile: MeasuredProfileIn | None = Field(default=None, description=(
        "as measurement_id, with a profile sent in the request"))

    @model_validator(mode="after")
    def _at_most_one_wheel(self) -> MeasuredProfilesIn:
        given = [k for k in ("wheel_id", "measurement_id", "profile")
                 if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give at most one of wheel_id, measurement_id, profile (got "
                             f"{', '.join(given)})")
        return self


class WearTableComputeIn(MeasuredProfilesIn):
    """``POST /v1/wear-tables/compute``: a table from the physics core (quasi-static curving).

    ``vehicle`` is a preset name (motor and trailer variants) or ``{motor, trailer}`` preset
    names; the radii come from a stored route's classes (``route_id``: id or name) or are
    given (``radii``), exactly one of them. A tangent row is always computed.
    """

    name: str = Field(min_length=1, max_length=200)
    vehicle: str | VehiclePairIn
    route_id: int | str | None = None
    radii: list[RadiusIn] | None = Field(default=None, min_length=1, max_length=200)
    unbalanced_acceleration_m_s2: float = Field(default=0.58, ge=0, le=2, description=(
        "a_nc for classes without a speed [m/s²] (seed 001: 0.58)"))
    friction: float | None = Field(default=None, gt=0, le=1, description=(
        "wheel-rail friction coefficient (default: the preset's)"))
    tangent_speed_kmh: float = Field(default=100.0, gt=0, le=500)
    max_speed_kmh: float | None = Field(default=None, gt=0, le=500)

    @model_validator(mode="after")
    def _one_source(self) -> WearTableComputeIn:
        if (self.route_id is None) == (self.radii is None):
            raise ValueError("give either route_id or radii (exactly one)")
        return self


class WearTableContactsOut(BaseModel):
    """The raw per-contact quantities behind a computed table, one record per bogie type,
    curve class, axle, side and contact patch (units in the column names)."""

    wear_table_id: int
    n_contacts: int
    columns: list[str]
    contacts: list[dict[str, Any]]


# --- measurements -----------------------------------------------------------------------

class ReportedParameters(Strict):
    sd_mm: float | None = None
    sh_mm: float | None = None
    qr_mm: float | None = None


class MeasurementIn(Strict):
    """One measurement: a profile (``y_mm``/``z_mm``) or the parameters only."""

    wheel_id: str = Field(min_length=1, max_length=200)
    vehicle_id: str = Field(min_length=1, max_length=200)
    bogie_type: BogieType
    axle: Axle
    side: Side
    mileage_km: float = Field(ge=0, le=MAX_MILEAGE_KM)
    measured_on: dt.date | None = None
    route_id: int | Annotated[str, Field(max_length=200)] | None = None
    running_mode: RunningMode | None = None
    instrument_id: str | None = Field(default=None, max_length=200)
    load_t: float | None = Field(default=None, ge=0, le=1000)
    reference_profile: str = Field(default="S1002", max_length=100)
    covariates: dict[str, FilterValue] = Field(default_factory=dict, max_length=100)
    diameter_mm: float | None = Field(default=None, gt=0, le=2000)
    y_mm: list[float] | None = Field(default=None, max_length=MAX_PROFILE_POINTS)
    z_mm: list[float] | None = Field(default=None, max_length=MAX_PROFILE_POINTS)
    sd_mm: float | None = None
    sh_mm: float | None = None
    qr_mm: float | None = None
    instrument_parameters: ReportedParameters | None = None

    @model_validator(mode="after")
    def _points_or_parameters(self) -> MeasurementIn:
        has_points = self.y_mm is not None or self.z_mm is not None
        has_params = any(v is not None for v in (self.sd_mm, self.sh_mm, self.qr_mm))
        if has_points:
            if self.y_mm is None or self.z_mm is None:
                raise ValueError("y_mm and z_mm must be given together")
            if len(self.y_mm) != len(self.z_mm):
                raise ValueError(f"y_mm has {len(self.y_mm)} points, z_mm {len(self.z_mm)}")
            if len(self.y_mm) < 10:
                raise ValueError("a profile needs at least 10 points")
        elif has_params:
            if any(v is None for v in (self.sd_mm, self.sh_mm, self.qr_mm)):
                raise ValueError("a parameter-only measurement needs sd_mm, sh_mm and qr_mm")
        else:
            raise ValueError("give the profile (y_mm, z_mm) or the parameters (sd_mm, sh_mm, "
                             "qr_mm)")
        return self


class MeasurementOut(BaseModel):
    id: int
    batch_id: int | None
    wheel_id: str
    vehicle_id: str
    bogie_type: str
    axle: int
    side: str
    mileage_km: float
    kind: str
    measured_on: dt.date | None
    route_id: str | None
    running_mode: str | None
    instrument_id: str | None
    load_t: float | None
    diameter_mm: float | None = None
    reference_profile: str
    covariates: dict[str, Any]
    source_file: str | None
    source_line: int | None
    n_points: int
    flange_area_mm2: float | None
    tread_area_mm2: float | None
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    reported_sd_mm: float | None
    reported_sh_mm: float | None
    reported_qr_mm: float | None
    lateral_shift_mm: float | None
    vertical_shift_mm: float | None
    rotation_rad: float | None
    rms_residual_mm: float | None
    reference_fits: bool | None = Field(None, description="false: the shape does not fit "
                                        "reference_profile; no wear areas until one is given")
    placement: dict[str, Any] | None = Field(None, description="datum found/guessed, tilt, "
                                             "alignment kind")
    warnings: list[dict[str, Any]] | None = None
    y_mm: list[float] | None = None
    z_mm: list[float] | None = None


class MeasurementPage(BaseModel):
    total: int
    limit: int
    offset: int
    items: list[MeasurementOut]


class ImportOut(BaseModel):
    batch_id: int
    duplicate: bool = Field(description="true when this content or key was imported before")
    file_name: str
    records: int = Field(description="records read from the upload")
    created: int = Field(description="measurements stored by this batch")
    duplicates: int = Field(description="measurements already present, skipped")
    points: int
    warnings: list[dict[str, Any]] = Field(
        default_factory=list, description="per file and line: code, level (info | warning), "
        "message, wheel_id, mileage_km (at most 1000 listed)")
    warnings_total: int = 0


# --- models -----------------------------------------------------------------------------

class CalibrationIn(Strict):
    route_id: int | str
    filter: Filter = Field(default_factory=dict)


class ModelIn(Strict):
    """A hybrid model (seed 001): calibrated on profile measurements with a curve-radius
    table. ``kind`` may be omitted (hybrid is the default)."""

    kind: Literal["hybrid"] = "hybrid"
    name: str = Field(min_length=1, max_length=200)
    measure: Measure
    running_mode: RunningMode
    wear_table_id: int
    calibration: CalibrationIn


class PhysicsModelSummary(BaseModel):
    """``ModelOut.physics`` of a physics model."""

    vehicle: str
    law: str
    route_id: int
    options: dict[str, Any] = Field(description="VehicleWearOptions of the run")
    wear_scale: float = Field(description="fitted wear-coefficient scale c [-]")
    wear_scale_p10: float
    wear_scale_p90: float
    spread: dict[str, Any] = Field(description="how P10/P90 were derived (method, log_sigma, "
                                   "per-vehicle scales)")
    rms_mm: float = Field(description="RMS error of the fitted FT/FH/qR points [mm]")
    at_reach: bool = Field(description="the fit ended at the largest scale the run reaches")
    calibrated_on: dict[str, Any] = Field(description=(
        "filter, n_measurements, measurement_ids, vehicles, n_points and the vehicle-averaged "
        "series (vehicle, distance_km, FT_mm, FH_mm, QR_mm, n_wheels) the scale was fitted "
        "to"))
    series: dict[str, Any] = Field(description=(
        "vehicle means of the run at scale c: mileage_km (wheel km), ft_mm, fh_mm, qr_mm"))
    errors: dict[str, Any] = Field(description=(
        "per_vehicle and overall: n, bias_mm, rms_mm, measured and simulated loss per "
        "1,000 km, per quantity (FT_mm, FH_mm, QR_mm)"))
    simulation: dict[str, Any] = Field(description=(
        "the run: simulated mileage, steps, D_step, contact updates and fallbacks, elapsed_s, "
        "step_convergence, runs made"))
    warnings: list[str] = Field(default_factory=list)


class ModelOut(BaseModel):
    """A stored model. ``kind``: ``hybrid`` (seed 001's statistical model), ``extended`` (a
    hybrid model extended by the discrepancy finder) or ``physics`` (the whole-vehicle wear
    loop with a calibrated wear-coefficient scale: ``measure``, ``running_mode`` and
    ``wear_table_id`` are null, ``physics`` holds the calibration; a physics model saved by
    a diagnosis also has ``derived_from`` and ``extension``)."""

    id: int
    name: str
    measure: str | None
    running_mode: str | None
    wear_table_id: int | None
    route_id: int
    calibration: dict[str, Any]
    n_calibration_measurements: int
    summary: dict[str, Any]
    kind: Literal["hybrid", "extended", "physics"] = "hybrid"
    derived_from: int | None = None
    extension: dict[str, Any] | None = None
    physics: PhysicsModelSummary | None = None


class RouteRef(Strict):
    route_id: int | str | None = None
    route: RouteSpec | None = None

    @model_validator(mode="after")
    def _one_route(self) -> RouteRef:
        # neither: a physics model runs on its own route; a hybrid model answers 422 route_id
        if self.route_id is not None and self.route is not None:
            raise ValueError("give either route_id or route (exactly one)")
        return self


class WheelPosition(RouteRef):
    bogie_type: BogieType
    axle: Axle
    side: Side


class PredictIn(RouteRef):
    bogie_type: BogieType | None = None
    axle: Axle | None = None
    side: Side | None = None
    wheel_id: str | None = Field(None, description="start from the wheel's latest measured "
                                 "profile; mileage_km then counts from that measurement")
    measurement_id: int | None = Field(None, description="start from this measurement")
    profile: MeasuredProfileIn | None = Field(None, description="start from this profile")
    covariates: dict[str, Any] | None = Field(default=None, description=(
        "the wheel's covariates for an extended model (load_t, running_mode, ...)"))
    mileage_km: list[float] = Field(min_length=1, max_length=1000)

    @model_validator(mode="after")
    def _start(self) -> PredictIn:
        starts = [self.wheel_id, self.measurement_id, self.profile]
        if sum(v is not None for v in starts) > 1:
            raise ValueError("give at most one of wheel_id, measurement_id, profile")
        stored = self.wheel_id is not None or self.measurement_id is not None
        if not stored and None in (self.bogie_type, self.axle, self.side):
            raise ValueError("give wheel_id or measurement_id, or bogie_type, axle and side")
        return self

    @property
    def measured_start(self) -> bool:
        return any(v is not None for v in (self.wheel_id, self.measurement_id, self.profile))

    @field_validator("mileage_km")
    @classmethod
    def _non_negative(cls, values: list[float]) -> list[float]:
        for i, value in enumerate(values):
            if value < 0:
                raise ValueError(f"mileage_km[{i}] = {value} is negative")
            if value > MAX_MILEAGE_KM:
                raise ValueError(f"mileage_km[{i}] = {value:g} is beyond {MAX_MILEAGE_KM:g} km")
        return values


class QuantileValues(BaseModel):
    p10: float
    p50: float
    p90: float


class PredictionAt(BaseModel):
    mileage_km: float
    flange_area_mm2: QuantileValues
    tread_area_mm2: QuantileValues
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    extrapolated: bool
    wear_mm: list[float | None]
    z_mm: list[float | None]


class PredictionOut(BaseModel):
    model_id: int
    route: str
    bogie_type: str
    axle: int
    side: str
    weighted_measure: dict[str, float]
    rates_mm2_per_km: dict[str, QuantileValues]
    start_areas_mm2: dict[str, float]
    y_mm: list[float]
    reference_z_mm: list[float]
    points: list[PredictionAt]
    start_mileage_km: float | None = None
    start_measurement_id: int | None = None
    start_parameters_mm: dict[str, float] | None = None
    start_notes: list[str] = Field(default_factory=list)


class Limits(Strict):
    sd_min_mm: float | None = Field(default=None, gt=0)
    sh_max_mm: float | None = Field(default=None, gt=0)
    qr_min_mm: float | None = Field(default=None, gt=0)


class ReprofilingIn(Strict):
    route_id: int | str | None = None
    route: RouteSpec | None = None
    wheel_id: str | None = Field(None, description="start from the wheel's latest measured "
                                 "profile (its Sd/Sh/qR and wear areas)")
    measurement_id: int | None = Field(None, description="start from this measurement")
    profile: MeasuredProfileIn | None = Field(None, description="start from this profile")
    bogie_type: BogieType | None = None
    axle: Axle | None = None
    side: Side | None = None
    limits: Limits | None = None
    covariates: dict[str, Any] | None = None

    @model_validator(mode="after")
    def _check(self) -> ReprofilingIn:
        # neither: a physics model runs on its own route; a hybrid model answers 422 route_id
        if self.route_id is not None and self.route is not None:
            raise ValueError("give either route_id or route (exactly one)")
        starts = [self.wheel_id, self.measurement_id, self.profile]
        if sum(v is not None for v in starts) > 1:
            raise ValueError("give at most one of wheel_id, measurement_id, profile")
        stored = self.wheel_id is not None or self.measurement_id is not None
        if not stored and None in (self.bogie_type, self.axle, self.side):
            raise ValueError("give wheel_id or measurement_id, or bogie_type, axle and side")
        return self


class OptionalQuantiles(BaseModel):
    p10: float | None
    p50: float | None
    p90: float | None


class ReprofilingOut(BaseModel):
    """Mileages in km; ``None`` = no limit reached within the search horizon (see reason)."""

    model_id: int
    route: str
    wheel_id: str | None
    bogie_type: str
    axle: int
    side: str
    start_mileage_km: float
    start_measurement_id: int | None
    start_areas_mm2: dict[str, float]
    remaining_km: OptionalQuantiles
    mileage_km: OptionalQuantiles
    governing_limit: str | None
    sd_mm: float | None
    sh_mm: float | None
    qr_mm: float | None
    extrapolated: bool
    reason: str | None
    limits: dict[str, float]
    crossed_limits: dict[str, float] = Field(
        default_factory=dict, description="limits the measured start is already past, and by "
        "how much [mm]; remaining_km is then 0")
    start_parameters_mm: dict[str, float] | None = Field(
        None, description="measured Sd/Sh/qR the prediction starts from")
    start_notes: list[str] = Field(default_factory=list)


# --- diagnosis ----------------------------------------------------------------------------

class ProgressionAreasIn(Strict):
    bogie_type: BogieType
    wheelset: Wheelset
    region: Region
    areas_mm2: list[float] = Field(min_length=2, max_length=10_000, description=(
        "simulated wear area at each of mileage_km [mm²]"))


class ExpectedProgressionIn(Strict):
    """The wear-area progression a simulation of the route expects (e.g. a wear-loop
    simulation's areas per step): the finder's baseline then grows as it does instead of
    linearly in mileage (``statistics.discrepancy_progression``)."""

    mileage_km: list[float] = Field(min_length=2, max_length=10_000)
    areas: list[ProgressionAreasIn] = Field(min_length=1, max_length=64)

    @model_validator(mode="after")
    def _same_lengths(self) -> ExpectedProgressionIn:
        for i, a in enumerate(self.areas):
            if len(a.areas_mm2) != len(self.mileage_km):
                raise ValueError(f"areas[{i}].areas_mm2 has {len(a.areas_mm2)} values for "
                                 f"{len(self.mileage_km)} mileages")
        return self


class DiagnoseIn(Strict):
    """``POST /v1/models/{id}/diagnose``.

    ``filter`` selects the measurements to diagnose (default: every profile measurement on a
    stored route); the model's calibration measurements are always added (flagged as such).
    ``save_as`` stores the model extended by the verdict's cause as a new model.
    """

    filter: Filter = Field(default_factory=dict)
    save_as: str | None = Field(default=None, min_length=1, max_length=200)
    causes: list[str] | None = Field(default=None, min_length=1, description=(
        "cause codes to try (default: the whole catalogue)"))
    seed: int = Field(default=0, ge=0, description="random seed of the folds and bootstrap")
    expected_progression: ExpectedProgressionIn | None = Field(default=None, description=(
        "a simulated wear-area progression of the route per bogie type, wheelset and region "
        "(hybrid models): the null grows as it does instead of linearly in mileage"))
    expected_progression_simulations: list[int] | None = Field(
        default=None, min_length=1, max_length=32, description=(
            "ids of finished wear-loop simulations of the route (POST /v1/simulations, one per "
            "bogie type and axle, e.g. both sides): the expected progression is derived from "
            "their wear areas (statistics.discrepancy_progression.progression_from_simulations)"))

    @model_validator(mode="after")
    def _one_progression(self) -> DiagnoseIn:
        if self.expected_progression is not None and \
                self.expected_progression_simulations is not None:
            raise ValueError("give expected_progression or expected_progression_simulations, "
                             "not both")
        return self


class GainOut(BaseModel):
    before_error: float | None
    after_error: float | None
    relative: float | None
    ci95_low: float | None
    ci95_high: float | None
    calibrated_error: float | None
    metric: str


class FindingOut(BaseModel):
    cause: str
    summary: str
    evidence: dict[str, Any]
    extension: dict[str, Any]
    gain: GainOut
    significant: bool
    material: bool


class DiagnosisOut(BaseModel):
    model_id: int
    verdict: str
    findings: list[FindingOut]
    skipped: dict[str, str]
    n_measurements: int
    n_groups: int
    group_by: str
    selected: list[str] = Field(default_factory=list, description=(
        "causes named by forward selection, the verdict first"))
    runner_up: str | None = Field(default=None, description="the best other cause")
    margin: float | None = Field(default=None, description=(
        "the verdict's held-out gain over the runner-up, relative to the baseline's error"))
    margin_p_value: float | None = None
    candidates: list[str] = Field(default_factory=list, description=(
        "verdict 'ambiguous': the causes no tested margin separates"))
    unexplained: list[dict[str, Any]] = Field(default_factory=list, description=(
        "verdict 'outside_catalogue': residual structure by wheel position, route, date, "
        "mileage or instrument, with its size"))
    nuisance: dict[str, Any] = Field(default_factory=dict)
    null_test: str = ""
    excluded: dict[str, int] = Field(default_factory=dict, description=(
        "measurements left out, by reason"))
    expected_progression: dict[str, Any] | None = Field(default=None, description=(
        "the null's expected progression when one was given: its source and the factor "
        "g = A / (k s) per bogie type/wheelset/region at its mileages; null: linear in mileage"))
    saved_model: ModelOut | None = None
    save_reason: str | None = Field(default=None, description="why save_as saved nothing")


# --- simulations --------------------------------------------------------------------------

WearLawName = Literal["archard_kth", "krause_poll", "usfd", "tau_max"]


class SimulationClassIn(Strict):
    radius_m: float | None = Field(default=None, gt=0, le=1e6, description="null = tangent")
    direction: Direction = "left"
    cant_mm: float = Field(default=0.0, ge=0, le=250)
    speed_kmh: float | None = Field(default=None, gt=0, le=500)
    share: float = Field(default=1.0, ge=0, le=1)


class StepsIn(Strict):
    """Wheel steps: ``adaptive`` (max depth per step, seed 003's D_step) or ``fixed`` km."""

    mode: Literal["adaptive", "fixed"] = "adaptive"
    count: int = Field(default=20, ge=1, le=200, description="number of wheel steps")
    depth_per_step_mm: float | None = Field(default=None, gt=0, le=5)
    step_km: float | None = Field(default=None, gt=0, le=1e6)
    max_step_km: float | None = Field(default=None, gt=0, le=1e7)
    contact_update_depth_mm: float | None = Field(default=None, ge=0, le=5)


class SmoothingIn(Strict):
    method: Literal["moving_average", "spline", "none"] = "moving_average"
    window_mm: float | None = Field(default=None, gt=0, le=50)


class SimulationIn(MeasuredProfilesIn):
    """``POST /v1/simulations``: the wear loop of one wheel over a route's curve classes."""

    name: str | None = Field(default=None, max_length=200)
    vehicle: str = Field(min_length=1, max_length=50, description="vehicle preset")
    bogie_type: BogieType = "trailer"
    route_id: int | str | None = None
    classes: list[SimulationClassIn] | None = Field(default=None, min_length=1,
                                                    max_length=200)
    law: WearLawName = "archard_kth"
    application: Literal["global", "local"] = "global"
    patch_width: Literal["hertz", "kik_piotrowski"] = Field(default="hertz", description=(
        "contact patch width: hertz (the curving model's ellipse) or kik_piotrowski (widened to "
        "the unsmoothed gap: conformal flange-root patches become wide and mild)"))
    steps: StepsIn = Field(default_factory=StepsIn)
    axle: Axle = 1
    side: Side = "right"
    smoothing: SmoothingIn | None = None
    unbalanced_acceleration_m_s2: float = Field(default=0.58, ge=0, le=2)
    tangent_speed_kmh: float = Field(default=100.0, gt=0, le=500)

    @model_validator(mode="after")
    def _one_route(self) -> SimulationIn:
        if (self.route_id is None) == (self.classes is None):
            raise ValueError("give either route_id or classes (exactly one)")
        return self


JobStatus = Literal["queued", "running", "done", "failed", "cancelled"]


class JobStatusOut(BaseModel):
    """What every job answer says of the job: id, name, status, progress (0-1), message and
    error (simulations, coefficient fits, ``/v1/jobs``, the 202 of a physics job)."""

    id: int
    name: str | None
    status: JobStatus
    progress: float
    message: str | None = None
    error: str | None = None


class SimulationOut(JobStatusOut):
    spec: dict[str, Any]
    created_at: dt.datetime | None = None
    started_at: dt.datetime | None = None
    finished_at: dt.datetime | None = None
    result: dict[str, Any] | None = None
