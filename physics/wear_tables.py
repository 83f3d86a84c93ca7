"""Curve-radius wear-measure tables from the quasi-static curving model.

The hybrid model of seed 001 (§2.2, eq. 2) needs, per bogie type, wheelset position (leading,
trailing), rail (high, low, tangent) and profile region (tread, flange), the wear measure
(tau_max or T-gamma) as a function of the curve radius. Seed 001 took these from SIMPACK runs
at one speed per radius (unbalanced lateral acceleration 0.58 m/s^2); here they come from
:mod:`wearcast.physics.curving`.

Conventions
-----------
* Every curve class is solved as a LEFT curve (track bending to the vehicle's left), so the
  right wheels run on the high rail and the left wheels on the low rail (docs/conventions.md "Sides
  and
  curves"); the model is mirror symmetric (tested), so a right curve gives the same table with
  the sides exchanged. The class ``direction`` is therefore only carried into the raw frame.
* Axle 1 of the (front) bogie leads: ``leading`` = axle 1, ``trailing`` = axle 2.
* A wheel's contact patches are attributed to a region by their lateral position on the wheel:
  wheel-frame y < -30 mm is ``flange``, the rest ``tread`` (docs/conventions.md). Per region
  T-gamma is
  the sum over its patches [N], tau_max the largest [MPa]; a region without contact gets 0.
* On tangent track both wheels are ``tangent``; the table gives their mean (they are equal
  by symmetry up to the solver tolerance) with ``radius_m`` NaN.
* ``contact_model`` chooses the contacts the wear measures come from, both at the table's
  curving equilibrium (the same pose, ``curving.solve_curving_cases``): ``"table"`` (default)
  the contact table's Hertz ellipses (``curving_table``), ``"pipeline"`` the one contact
  pipeline's patches (``curving_contacts``: multi-point geometry, patches merged or split,
  non-Hertzian normal contact where the patch is not elliptic, FASTSIM forces) evaluated at
  that pose. Either way tau_max and T-gamma are ``wear_measures.equilibrium_wear_measures`` of
  the chosen contacts (FASTSIM on the patch's (equivalent) ellipse, elliptic bound for
  tau_max); ``p0_mpa`` is the Hertz p0 of the table's ellipse or the pipeline's peak pressure.
  The pipeline costs ~30 ms per wheel and pose (``benchmarks/table_contact_models.py``).
  The pose is the table's, which the pipeline's forces do not balance: where its patch
  lies elsewhere (conformal treads, flanges up the flank) its creepages and measures differ
  from those of its own equilibrium (``curving_contacts``). ``"pipeline_equilibrium"``: the
  pipeline's patches at the equilibrium of the pipeline's own forces
  (``pipeline_equilibrium.pipeline_force_equilibrium``, a homotopy from the table's
  equilibrium; a few seconds per operating point); a class whose equilibrium is not found to
  ``curving.PIPELINE_TOLERANCE`` fails like one that does not converge. The table's
  ``wheelset_shift_mm`` and ``wheelset_yaw_rad`` are then the pipeline's equilibrium's.
* Several classes with the same radius (different cant or speed, as in seed 003 Table 3) are
  merged into one table row per radius by the share-weighted mean (equal weights when no
  share is given); the raw frame keeps every class.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Literal, cast, get_args

import numpy as np
import pandas as pd

from wearcast.physics.curving import (
    FLANGE_SPLIT_Y_MM,
    PIPELINE_TOLERANCE,
    CurvingConvergenceError,
    CurvingResult,
    curve_case,
    solve_curving_cases,
)
from wearcast.physics.vehicles import BogieVehicle, vehicle_preset
from wearcast.physics.vocabulary import SIDES, WEAR_MEASURES, WEAR_TABLE_COLUMNS, CurveClass
from wearcast.physics.wear_measures import (
    krause_poll_index,
    kth_archard_index,
    rigid_sliding_velocity_m_s,
    t_gamma_per_area,
)

#: Columns of the curve-radius table (``vocabulary.WEAR_TABLE_COLUMNS``), as a list.
TABLE_COLUMNS = list(WEAR_TABLE_COLUMNS)
MEASURES = WEAR_MEASURES
_KMH = 3.6
#: Contact models a table's wear measures can come from (module docstring).
ContactModel = Literal["table", "pipeline", "pipeline_equilibrium"]
CONTACT_MODELS: tuple[ContactModel, ...] = get_args(ContactModel)


ClassLike = CurveClass | Mapping[str, object]


def _as_class(item: ClassLike) -> CurveClass:
    if isinstance(item, CurveClass):
        return item
    known = {"radius_m", "cant_mm", "speed_kmh", "direction", "share"}
    unknown = set(item) - known
    if unknown:
        raise ValueError(f"unknown curve-class fields: {sorted(unknown)}")
    values = dict(item)
    for key in ("radius_m", "speed_kmh"):
        v = values.get(key)
        if v is not None and (isinstance(v, float) and np.isnan(v)):
            values[key] = None
    return CurveClass(**values)  # type: ignore[arg-type]


def _operating_points(classes: Sequence[CurveClass], unbalanced_acceleration_m_s2: float,
                      tangent_speed_kmh: float, max_speed_kmh: float | None,
                      torque_nm: float):
    cases = []
    labels = []
    speeds = []
    for c in classes:
        if c.is_tangent:
            v: float | None = (
                (c.speed_kmh if c.speed_kmh is not None else tangent_speed_kmh) / _KMH)
            case = curve_case(None, 0.0, v, "left", torque_nm=torque_nm)
        else:
            v = None if c.speed_kmh is None else c.speed_kmh / _KMH
            case = curve_case(c.radius_m, c.cant_mm, v, "left", unbalanced_acceleration_m_s2,
                              torque_nm)
            if c.speed_kmh is None and max_speed_kmh is not None and (
                    case.speed_m_s > max_speed_kmh / _KMH):
                case = curve_case(c.radius_m, c.cant_mm, max_speed_kmh / _KMH, "left",
                                  torque_nm=torque_nm)
        cases.append(case)
        labels.append((None if c.is_tangent else c.radius_m, "left", c.cant_mm))
        speeds.append(case.speed_m_s)
    return cases, labels, speeds


def _contacts_of(result: CurvingResult, contact_model: str) -> dict[str, np.ndarray]:
    """Per-contact arrays (2 axles, 2 sides, slots) of the chosen contact model at the
    equilibrium: the table's (the result's own fields) or the pipeline's (``result.pipeline``),
    with ``p0_mpa`` the table's Hertz p0 or the pipeline's peak pressure."""
    names = ("normal_force_n", "in_contact", "wheel_y_mm", "rail_y_mm", "contact_angle_rad",
             "rolling_radius_m", "xi", "eta", "phi_per_mm", "fx_n", "fy_n", "mz_nmm", "a_mm",
             "b_mm", "tau_max_mpa", "t_gamma_n")
    if contact_model == "table":
        out = {name: getattr(result, name) for name in names}
        out["p0_mpa"] = result.p0_mpa
        out["wheelset_shift_mm"] = result.wheelset_shift_mm
        out["wheelset_yaw_rad"] = result.wheelset_yaw_rad
        return out
    if result.pipeline is None:
        raise ValueError("the curving result carries no pipeline contacts")
    out = {name: result.pipeline[name] for name in names}
    out["p0_mpa"] = result.pipeline["peak_pressure_mpa"]
    pose = result.pipeline if contact_model == "pipeline_equilibrium" else {
        "wheelset_shift_mm": result.wheelset_shift_mm,
        "wheelset_yaw_rad": result.wheelset_yaw_rad}
    out["wheelset_shift_mm"] = pose["wheelset_shift_mm"]
    out["wheelset_yaw_rad"] = pose["wheelset_yaw_rad"]
    return out


def _contact_rows(bogie_type: str, k: int, cls: CurveClass, result: CurvingResult,
                  speed_m_s: float, contact_model: str = "table") -> list[dict]:
    c = _contacts_of(result, contact_model)
    rows = []
    for axle in range(2):
        for s, side in enumerate(SIDES):
            for slot in range(c["normal_force_n"].shape[-1]):
                fn = float(c["normal_force_n"][axle, s, slot])
                loaded = bool(c["in_contact"][axle, s, slot])
                y_w = float(c["wheel_y_mm"][axle, s, slot])
                a = float(c["a_mm"][axle, s, slot])
                b = float(c["b_mm"][axle, s, slot])
                rows.append({
                    "bogie_type": bogie_type, "class_index": k,
                    "radius_m": (np.nan if cls.is_tangent or cls.radius_m is None
                                 else float(cls.radius_m)),
                    "cant_mm": cls.cant_mm, "speed_kmh": speed_m_s * _KMH,
                    "direction": cls.direction, "share": cls.share,
                    "wheelset": "leading" if axle == 0 else "trailing", "axle": axle + 1,
                    "side": side, "rail": result.rail_of(side), "patch": slot,
                    "in_contact": loaded,
                    "region": "flange" if y_w < FLANGE_SPLIT_Y_MM else "tread",
                    "wheel_y_mm": y_w, "rail_y_mm": float(c["rail_y_mm"][axle, s, slot]),
                    "contact_angle_rad": float(c["contact_angle_rad"][axle, s, slot]),
                    "rolling_radius_m": float(c["rolling_radius_m"][axle, s, slot]),
                    "normal_force_n": fn if loaded else 0.0,
                    "xi": float(c["xi"][axle, s, slot]),
                    "eta": float(c["eta"][axle, s, slot]),
                    "phi_per_mm": float(c["phi_per_mm"][axle, s, slot]),
                    "fx_n": float(c["fx_n"][axle, s, slot]) if loaded else 0.0,
                    "fy_n": float(c["fy_n"][axle, s, slot]) if loaded else 0.0,
                    "mz_nmm": float(c["mz_nmm"][axle, s, slot]) if loaded else 0.0,
                    "a_mm": a if loaded else 0.0, "b_mm": b if loaded else 0.0,
                    "p0_mpa": float(c["p0_mpa"][axle, s, slot]),
                    "tau_max_mpa": float(c["tau_max_mpa"][axle, s, slot]),
                    "t_gamma_n": float(c["t_gamma_n"][axle, s, slot]),
                    "wheelset_shift_mm": float(c["wheelset_shift_mm"][axle]),
                    "wheelset_yaw_rad": float(c["wheelset_yaw_rad"][axle]),
                })
    return rows


def _add_indices(contacts: pd.DataFrame) -> pd.DataFrame:
    """T-gamma/A, KTH/Archard and Krause-Poll indices and regimes of the loaded patches."""
    df = contacts.copy()
    loaded = df["in_contact"].to_numpy()
    v = df["speed_kmh"].to_numpy() / _KMH
    a = np.where(loaded, df["a_mm"].to_numpy(), 1.0)
    b = np.where(loaded, df["b_mm"].to_numpy(), 1.0)
    tg = df["t_gamma_n"].to_numpy()
    area = np.pi * a * b
    v_slide = rigid_sliding_velocity_m_s(v, df["xi"].to_numpy(), df["eta"].to_numpy())
    pressure = np.where(loaded, df["normal_force_n"].to_numpy() / area, 0.0)
    arch = kth_archard_index(df["normal_force_n"].to_numpy(), v_slide, v, pressure)
    kp = krause_poll_index(tg, v, area)
    df["t_gamma_per_area_n_per_mm2"] = np.where(loaded, t_gamma_per_area(tg, a, b), 0.0)
    df["sliding_velocity_m_s"] = np.where(loaded, v_slide, 0.0)
    df["archard_zone"] = np.where(loaded, arch.zone, 0)
    df["archard_regime"] = np.where(loaded, arch.regime, "")
    df["archard_wear_rate_mm3_per_m"] = np.where(loaded, arch.wear_rate_mm3_per_m, 0.0)
    df["krause_poll_power_density_w_per_mm2"] = np.where(loaded, kp.power_density_w_per_mm2,
                                                         0.0)
    df["krause_poll_regime"] = np.where(loaded, kp.regime, "")
    df["krause_poll_wear_rate_mm3_per_m"] = np.where(loaded, kp.wear_rate_mm3_per_m, 0.0)
    return df


def table_from_contacts(contacts: pd.DataFrame) -> pd.DataFrame:
    """Aggregate the raw contacts (``compute_wear_table_with_contacts``'s frame) into the table
    of docs/conventions.md (regions, rails, radii): per wheel and region tau_max is the largest
    ``tau_max_mpa`` of its loaded patches, T-gamma the sum of ``t_gamma_n``."""
    df = contacts.copy()
    df["tau_max"] = np.where(df["in_contact"], df["tau_max_mpa"], 0.0)
    df["t_gamma"] = np.where(df["in_contact"], df["t_gamma_n"], 0.0)
    df["radius_key"] = df["radius_m"].fillna(-1.0)  # groupby keys without NaN
    wheel = ["bogie_type", "class_index", "radius_key", "share", "wheelset", "side", "rail"]
    per_region = df.groupby(wheel + ["region"], sort=False).agg(
        tau_max=("tau_max", "max"), t_gamma=("t_gamma", "sum"))
    # every wheel gets both regions; a region without a patch gets 0
    per_region = cast(pd.DataFrame, per_region.unstack("region", fill_value=0.0)
                      .stack("region", future_stack=True))
    per_region = per_region.fillna(0.0).reset_index()
    # tangent track: both wheels are "tangent" -> their mean
    cls_keys = ["bogie_type", "class_index", "radius_key", "share", "wheelset", "rail", "region"]
    per_class = per_region.groupby(cls_keys, sort=False)[["tau_max", "t_gamma"]].mean()
    per_class = per_class.reset_index()
    # classes with the same radius -> share-weighted mean (equal weights if all shares are 0)
    keys = ["bogie_type", "wheelset", "rail", "radius_key", "region"]
    w = per_class["share"].clip(lower=0.0)
    total = w.groupby([per_class[k] for k in keys]).transform("sum")
    count = per_class.groupby(keys)["share"].transform("size")
    per_class["w"] = np.where(total > 0, w / total.where(total > 0, 1.0), 1.0 / count)
    for m in MEASURES:
        per_class[m] = per_class[m] * per_class["w"]
    merged = per_class.groupby(keys, sort=False)[list(MEASURES)].sum().reset_index()
    table = merged.melt(id_vars=keys, value_vars=list(MEASURES), var_name="measure",
                        value_name="value")
    table["radius_m"] = table["radius_key"].where(table["radius_key"] >= 0, np.nan)
    order = {"leading": 0, "trailing": 1, "high": 0, "low": 1, "tangent": 2, "tread": 0,
             "flange": 1, "tau_max": 0, "t_gamma": 1}
    table = table.sort_values(
        ["bogie_type", "wheelset", "rail", "radius_key", "region", "measure"],
        key=lambda col: col.map(order) if col.name in ("wheelset", "rail", "region",
                                                        "measure") else col)
    return table[TABLE_COLUMNS].reset_index(drop=True)


def compute_wear_table_with_contacts(vehicle_motor: BogieVehicle, vehicle_trailer: BogieVehicle,
                                     classes: Iterable[ClassLike],
                                     unbalanced_acceleration_m_s2: float = 0.58,
                                     tangent_speed_kmh: float = 100.0,
                                     max_speed_kmh: float | None = None,
                                     fastsim_grid: int = 20, contact_model: str = "table"
                                     ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Curve-radius table and the raw per-contact quantities behind it.

    Parameters
    ----------
    vehicle_motor, vehicle_trailer : the two bogie types (``vehicles.vehicle_preset``)
    classes : curve classes, :class:`CurveClass` or mappings with ``radius_m`` (None = tangent),
        ``cant_mm``, ``speed_kmh`` (None: from the unbalanced lateral acceleration, capped by
        ``max_speed_kmh``), ``direction``, ``share``
    unbalanced_acceleration_m_s2 : a_nc for classes without a speed (seed 001: 0.58 m/s^2)
    tangent_speed_kmh : speed on tangent classes without a speed [km/h]
    max_speed_kmh : optional line-speed cap for speeds derived from a_nc [km/h]
    fastsim_grid : FASTSIM grid size for tau_max
    contact_model : ``"table"`` (default) the wear measures of the contact table's Hertz
        ellipses at the curving equilibrium, ``"pipeline"`` those of the contact pipeline's
        patches at the same pose (module docstring; ~30 ms per wheel and pose),
        ``"pipeline_equilibrium"`` those of the pipeline's patches at the equilibrium of its
        own forces (a few seconds per operating point)

    Returns
    -------
    (table, contacts): ``table`` in the format of docs/conventions.md (columns ``TABLE_COLUMNS``;
    tau_max in
    MPa, t_gamma in N); ``contacts`` one row per bogie type, class, axle, side and contact
    patch with positions, angle, forces, creepages, Hertz patch, tau_max, T-gamma, T-gamma/A,
    KTH/Archard and Krause-Poll indices and regimes (wear_measures; the Archard sliding velocity
    is V sqrt(xi^2 + eta^2), spin not included).

    Raises
    ------
    ValueError for bad classes or an unknown ``contact_model``; curving.CurvingConvergenceError
    if a class does not converge (with ``"pipeline"`` also if the pipeline fails at its pose,
    with ``"pipeline_equilibrium"`` if the equilibrium of its forces is not found).
    """
    if contact_model not in CONTACT_MODELS:
        raise ValueError(f"contact_model must be one of {list(CONTACT_MODELS)}, not "
                         f"{contact_model!r}")
    cls = [_as_class(c) for c in classes]
    if not cls:
        raise ValueError("classes must not be empty")
    rows: list[dict] = []
    for bogie_type, vehicle in (("motor", vehicle_motor), ("trailer", vehicle_trailer)):
        cases, labels, speeds = _operating_points(cls, unbalanced_acceleration_m_s2,
                                                  tangent_speed_kmh, max_speed_kmh,
                                                  vehicle.traction_torque_nm)
        balanced = contact_model == "pipeline_equilibrium"
        results = solve_curving_cases(vehicle, cases, labels, fastsim_grid=fastsim_grid,
                                      contact_pipeline=contact_model != "table",
                                      pipeline_equilibrium=balanced)
        for k, (c, res, v) in enumerate(zip(cls, results, speeds, strict=True)):
            if balanced and not res.pipeline_residual_norm < PIPELINE_TOLERANCE:
                raise CurvingConvergenceError(
                    "the equilibrium with the contact pipeline's forces was not found",
                    np.inf if c.is_tangent or c.radius_m is None else float(c.radius_m),
                    res.pipeline_residual_norm)
            rows.extend(_contact_rows(bogie_type, k, c, res, v, contact_model))
    contacts = _add_indices(pd.DataFrame(rows))
    return table_from_contacts(contacts), contacts


def compute_wear_table(vehicle_motor: BogieVehicle, vehicle_trailer: BogieVehicle,
                       classes: Iterable[ClassLike], unbalanced_acceleration_m_s2: float = 0.58,
                       tangent_speed_kmh: float = 100.0, max_speed_kmh: float | None = None,
                       fastsim_grid: int = 20, contact_model: str = "table") -> pd.DataFrame:
    """The curve-radius table only; see :func:`compute_wear_table_with_contacts`."""
    return compute_wear_table_with_contacts(vehicle_motor, vehicle_trailer, classes,
                                            unbalanced_acceleration_m_s2, tangent_speed_kmh,
                                            max_speed_kmh, fastsim_grid, contact_model)[0]


def wear_table_for_route(vehicle: str | tuple[BogieVehicle, BogieVehicle],
                         radii_m: Sequence[float | None],
                         cant_mm: float | Sequence[float] = 0.0,
                         speed_kmh: float | Sequence[float | None] | None = None,
                         shares: Sequence[float] | None = None,
                         unbalanced_acceleration_m_s2: float = 0.58,
                         tangent_speed_kmh: float = 100.0, max_speed_kmh: float | None = None,
                         with_contacts: bool = False, contact_model: str = "table"):
    """Build a curve-radius table from plain lists (what ``POST /v1/wear-tables/compute``
    needs).

    Parameters
    ----------
    vehicle : a preset name (``manchester``, ``metro_b``, ``minuetto``: motor and trailer
        variants are used) or a (motor, trailer) pair of BogieVehicle
    radii_m : radius per class [m]; None (or inf) for tangent track
    cant_mm : cant per class, or one value for all [mm]
    speed_kmh : speed per class (None entries: from a_nc), one value, or None for all
    shares : optional share of each class in the route (merges equal radii)
    unbalanced_acceleration_m_s2, tangent_speed_kmh, max_speed_kmh : as
        :func:`compute_wear_table_with_contacts`
    with_contacts : also return the raw per-contact frame
    contact_model : ``"table"``, ``"pipeline"`` or ``"pipeline_equilibrium"``
        (:func:`compute_wear_table_with_contacts`)

    Returns
    -------
    table, or (table, contacts) when ``with_contacts``.
    """
    if isinstance(vehicle, str):
        motor, trailer = vehicle_preset(vehicle, "motor"), vehicle_preset(vehicle, "trailer")
    else:
        motor, trailer = vehicle
    n = len(radii_m)
    if n == 0:
        raise ValueError("radii_m must not be empty")

    def per_class(value, name):
        if value is None or np.isscalar(value):
            return [value] * n
        values = list(value)
        if len(values) != n:
            raise ValueError(f"{name} has {len(values)} values for {n} radii")
        return values

    cants = per_class(cant_mm, "cant_mm")
    speeds = per_class(speed_kmh, "speed_kmh")
    share_list = per_class(1.0 if shares is None else shares, "shares")
    classes = [CurveClass(radius_m=None if r is None or not np.isfinite(r) else float(r),
                          cant_mm=float(c), speed_kmh=None if v is None else float(v),
                          share=float(s))
               for r, c, v, s in zip(radii_m, cants, speeds, share_list, strict=True)]
    table, contacts = compute_wear_table_with_contacts(
        motor, trailer, classes, unbalanced_acceleration_m_s2, tangent_speed_kmh,
        max_speed_kmh, contact_model=contact_model)
    return (table, contacts) if with_contacts else table
