"""The model extended by the discrepancy finder's findings (saved, predicted, corrected).

``ExtendedModel`` carries the calibrated hybrid model of seed 001 and the fitted parameters
of one cause (or of several, joined by ``+``, from forward selection). Its rates are the
base model's times the cause's rate factor, computed by the cause's own ``predict``
(:mod:`wearcast.statistics.causes`). ``profile_misalignment`` changes the data, not the
rates: ``correct_wear_curves`` / ``correct_profile`` undo an instrument's fitted geometric
error (seed 000 §IV.A).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics import causes as cz
from wearcast.statistics.hybrid import HybridModel
from wearcast.statistics.hybrid_prediction import Prediction, predict
from wearcast.statistics.hybrid_profiles import profile_at_areas
from wearcast.statistics.json_values import json_value
from wearcast.statistics.residuals import geometric_basis
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import WearTable

if TYPE_CHECKING:
    from wearcast.statistics.findings import Finding


def build_finder_data(*args: Any, **kwargs: Any) -> cz.FinderData:
    from wearcast.statistics.discrepancy_data import build_data

    return build_data(*args, **kwargs)


@dataclass(frozen=True)
class ExtendedModel:
    """A hybrid model with one fitted extension of the catalogue.

    ``rate_factors`` gives the per-region multiplier of the base model's rate for one wheel
    (its covariates); ``for_wheel`` returns a plain HybridModel whose c_s carries that factor,
    so ``hybrid_prediction.predict`` and ``reprofiling.reprofiling_mileage`` work unchanged;
    ``predict`` adds the mileage dependence of ``nonlinear_progression``.
    """

    base: HybridModel
    cause: str
    parameters: dict[str, Any]
    log_scale: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "extended", "base": self.base.to_dict(), "cause": self.cause,
                "parameters": json_value(self.parameters), "log_scale": dict(self.log_scale)}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ExtendedModel:
        return cls(HybridModel.from_dict(data["base"]), str(data["cause"]),
                   dict(data["parameters"]), {k: float(v) for k, v in
                                              data["log_scale"].items()})

    def correct_wear_curves(self, frame: pd.DataFrame, curves_mm: Any) -> NDArray[np.float64]:
        """``profile_misalignment`` only: measured wear curves on the base model's grid with
        each instrument's geometric error removed (module ``correct_wear_curves``)."""
        return correct_wear_curves(self, frame, curves_mm, grid_y_mm=self.base.grid_y_mm,
                                   split_y_mm=self.base.split_y_mm)

    def correct_profile(self, instrument_id: str, y_mm: Any, z_mm: Any
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``profile_misalignment`` only: a raw profile's points corrected (module
        ``correct_profile``)."""
        return correct_profile(self, instrument_id, y_mm, z_mm, split_y_mm=self.base.split_y_mm)

    def rate_factors(self, route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                     axle: int, side: str, covariates: Mapping[str, Any] | None = None
                     ) -> dict[str, float]:
        """Multiplier of the base rate per region for one wheel (scale included).

        The wheel is written as a one-row measurement (its covariates as columns, e.g.
        ``flange_lubrication``, ``load_t``, ``running_mode``) and the fitted cause's own
        ``predict`` gives the factor: the same code that fitted it.
        """
        cov = dict(covariates or {})
        row = {"wheel_id": "w", "vehicle_id": "v", "bogie_type": bogie_type, "axle": axle,
               "side": side, "mileage_km": 100_000.0, "route": route.name,
               "flange_area_mm2": 1.0, "tread_area_mm2": 1.0,
               "running_mode": cov.pop("running_mode", self.base.running_mode)}
        row.update({k: v for k, v in cov.items() if k not in row})
        data = build_finder_data(self.base, pd.DataFrame([row]), None, {route.name: route},
                                 table)
        est = self.estimator()
        g = est.log_factor(data, est.theta_)[0] if est.code != "profile_misalignment" \
            else np.zeros(2)
        return {r: math.exp(self.log_scale.get(r, 0.0) + float(g[j]))
                for j, r in enumerate(REGIONS)}

    def estimator(self) -> cz.Cause:
        """The fitted cause (or composite of causes) this extension carries."""
        codes = self.cause.split("+")
        if len(codes) == 1:
            return cz.cause_by_code(codes[0]).from_params(self.parameters)
        members = tuple(cz.cause_by_code(c).from_params(self.parameters[c]) for c in codes)
        comp = cz.Composite(members)
        comp.sizes = [len(m.theta_) for m in members]
        comp.theta_ = np.concatenate([m.theta_ for m in members])
        comp.log_scale_ = np.zeros(2)
        return comp

    def for_wheel(self, route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                  axle: int, side: str, covariates: Mapping[str, Any] | None = None
                  ) -> HybridModel:
        """A plain HybridModel whose rates equal the extended model's for this wheel."""
        f = self.rate_factors(route, table, bogie_type=bogie_type, axle=axle, side=side,
                              covariates=covariates)
        m = self.base
        return replace(m, flange=replace(m.flange, c_s=m.flange.c_s * f["flange"]),
                       tread=replace(m.tread, c_s=m.tread.c_s * f["tread"]))

    def predict(self, route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                axle: int, side: str, mileage_km: Any,
                covariates: Mapping[str, Any] | None = None) -> Prediction:
        """``hybrid_prediction.predict`` with the extension (areas A = k s, or
        k s_ref (s/s_ref)^beta)."""
        m = self.for_wheel(route, table, bogie_type=bogie_type, axle=axle, side=side,
                           covariates=covariates)
        out = predict(m, route, table, bogie_type=bogie_type, axle=axle, side=side,
                      mileage_km=mileage_km)
        params = self.parameters if self.cause == "nonlinear_progression" else \
            self.parameters.get("nonlinear_progression") if "+" in self.cause else None
        if not params:
            return out
        s = out.mileage_km
        s_ref = float(params["reference_mileage_km"])
        g = {r: np.where(s > 0, (np.maximum(s, 1e-9) / s_ref)
                         ** (float(params[f"beta_{r}"]) - 1.0), 1.0)
             for r in REGIONS}
        fa = out.flange_area_mm2 * g["flange"][None, :]
        ta = out.tread_area_mm2 * g["tread"][None, :]
        median = out.quantiles.index(0.5)
        wear, z, params, extra = profile_at_areas(m, fa[median], ta[median])
        return replace(out, flange_area_mm2=fa, tread_area_mm2=ta, wear_mm=wear, z_mm=z,
                       sd_mm=params[:, 0], sh_mm=params[:, 1], qr_mm=params[:, 2],
                       extrapolated=extra)


def apply_extension(model: HybridModel, finding: Finding) -> HybridModel | ExtendedModel:
    """The model extended by a finding.

    ``wear_measure`` with a share of the other measure of 1 (within its 95 % interval)
    gives a plain HybridModel with the other measure and c_s refitted;
    ``profile_misalignment`` corrects the data, not the rates: an ``ExtendedModel`` that
    predicts exactly as the base model and carries the per-instrument corrections
    (``correct_wear_curves``, ``correct_profile``); every other cause an ``ExtendedModel``.
    """
    ext = finding.extension
    params = dict(ext["parameters"])
    if finding.cause == "wear_measure" and "c_s_flange" in params:
        return replace(model, measure=str(params["measure"]),
                       flange=replace(model.flange, c_s=float(params["c_s_flange"])),
                       tread=replace(model.tread, c_s=float(params["c_s_tread"])))
    if finding.cause == "profile_misalignment":
        # the wear model itself is right; what the extension carries is the per-instrument
        # geometric correction of the measurements (``correct_wear_curves``,
        # ``correct_profile``); its rates are the base model's (no scale change)
        return ExtendedModel(model, finding.cause, params, {"flange": 0.0, "tread": 0.0})
    return ExtendedModel(model, finding.cause, params, dict(ext["log_scale"]))


def _instrument_corrections(extension: Finding | ExtendedModel | Mapping[str, Any]
                            ) -> dict[str, dict[str, float]]:
    if hasattr(extension, "extension"):
        params = extension.extension["parameters"]
    elif isinstance(extension, ExtendedModel):
        params = extension.parameters
    else:
        params = extension.get("parameters", extension)
    corr = params.get("corrections")
    if corr is None:
        raise ValueError("extension: not a profile_misalignment extension with corrections")
    return {str(k): {n: float(x) for n, x in v.items()} for k, v in corr.items()}


def correct_wear_curves(extension: Finding | ExtendedModel | Mapping[str, Any],
                        frame: pd.DataFrame, curves_mm: Any, *, grid_y_mm: Any,
                        split_y_mm: float = -30.0) -> NDArray[np.float64]:
    """Measured wear curves with each instrument's fitted geometric error removed [mm].

    extension : the ``profile_misalignment`` finding, the saved ExtendedModel or its
        parameters (``corrections`` per instrument relative to the reference instrument)
    frame : one row per curve with ``instrument_id``; curves_mm : (n, g) on ``grid_y_mm``

    w_corrected = w - (e y z' + d_f z' [y < split] + d_s z') with the instrument's lateral
    scale error e, flange-tread offset d_f and lateral shift d_s (residuals.geometric_basis,
    seed 000 §IV.A). Instruments without a correction are returned unchanged.
    """
    corr = _instrument_corrections(extension)
    curves = np.array(curves_mm, dtype=float, copy=True)
    basis = geometric_basis(grid_y_mm, split_y_mm)
    if curves.ndim != 2 or curves.shape[1] != basis.shape[1]:
        raise ValueError(f"curves: must have shape (n, {basis.shape[1]}) on grid_y_mm")
    if "instrument_id" not in frame.columns or len(frame) != curves.shape[0]:
        raise ValueError("frame: needs instrument_id and one row per curve")
    inst = frame["instrument_id"].astype(str).to_numpy()
    names = cz.ProfileMisalignment.basis_names
    for name, c in corr.items():
        coef = np.array([c[k] for k in names])
        curves[inst == name] -= coef @ basis
    return curves


def correct_profile(extension: Finding | ExtendedModel | Mapping[str, Any], instrument_id: str,
                    y_mm: Any, z_mm: Any, *, split_y_mm: float = -30.0
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A measured profile's points with the instrument's fitted geometric error undone [mm].

    Inverse of the error model of ``correct_wear_curves``: y <- y - d_s - d_f [y < split],
    then y <- y / (1 + e) about the tape circle; z unchanged. Align and process the
    corrected points as usual (``processing.process_profile``).
    """
    corr = _instrument_corrections(extension).get(str(instrument_id))
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    if corr is None:
        return y.copy(), z.copy()
    y = y - corr["lateral_shift_mm"]
    y = np.where(y < split_y_mm, y - corr["flange_offset_mm"], y)
    return y / (1.0 + corr["lateral_scale"]), z.copy()


# --- figures and report -----------------------------------------------------------------------
