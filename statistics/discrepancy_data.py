"""What the discrepancy finder reads: the calibrated model's residuals per measurement and
region (log-area residuals, :mod:`wearcast.statistics.residuals`), the wear-curve shape
residuals projected on the geometric basis, and the covariates the causes read
(``causes.FinderData``).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import WEAR_MEASURES
from wearcast.statistics import causes as cz
from wearcast.statistics.discrepancy_progression import (
    ExpectedProgression,
    centred,
    exponent_offset,
)
from wearcast.statistics.hybrid import HybridModel
from wearcast.statistics.residuals import (
    geometric_basis,
    model_residuals,
    shape_residuals,
)
from wearcast.statistics.route_measure import leading_shares
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import WearTable


def _lubricated_share(flags: NDArray[np.bool_] | None, history: Any
                      ) -> NDArray[np.float64] | None:
    """Share of each measurement's mileage run lubricated (its route history)."""
    if flags is None:
        return None
    x = flags.astype(float)
    return np.asarray(history @ x) if history is not None else x


def build_data(model: HybridModel, measurements: pd.DataFrame, wear_curves: Any,
               routes_by_name: Mapping[str, Route], table: pd.DataFrame | WearTable, *,
               calibration_wheel_ids: Collection[Any] = (),
               route_attributes: Mapping[str, Mapping[str, Any]] | None = None,
               expected_progression: ExpectedProgression | None = None
               ) -> cz.FinderData:
    """Residuals and covariates in the form the causes read (see ``causes.FinderData``).

    With ``expected_progression`` the base prediction carries the simulated progression
    shape of every row (``discrepancy_progression``): the causes are departures from it.
    """
    res = model_residuals(model, measurements, routes_by_name, table,
                          calibration_wheel_ids=calibration_wheel_ids)
    frame = res.frame
    mileage = frame["mileage_km"].to_numpy(dtype=float)
    lead = leading_shares(frame["axle"].to_numpy(), res.mode)
    base = res.predicted_mm2
    factor = None
    if expected_progression is not None:
        factor = expected_progression.row_factors(
            frame["bogie_type"].to_numpy(), mileage, res.parts, lead,
            WEAR_MEASURES.index(model.measure))
        base = base * factor
    rcol = "route" if "route" in frame.columns else "route_id"
    route = frame[rcol].astype(str).to_numpy()
    shape = None
    basis = geometric_basis(model.grid_y_mm, model.split_y_mm)
    if wear_curves is not None:
        # keep only the part of each shape residual that a geometric error can produce:
        # its least-squares projection on the basis (the rest no extension can explain)
        d = np.nan_to_num(shape_residuals(model, res.measured_mm2, wear_curves), nan=0.0)
        coef, *_ = np.linalg.lstsq(basis.T, d.T, rcond=None)
        shape = (basis.T @ coef).T
    data = cz.FinderData(
        frame=frame, measured=res.measured_mm2, base=base, floor=res.floor_mm2,
        mileage_km=mileage,
        c_s=np.array([model.flange.c_s, model.tread.c_s]), parts=res.parts,
        measure_index=WEAR_MEASURES.index(model.measure),
        lead_share=lead, mode=res.mode,
        left_right=res.left_right_shares, route=route,
        lubricated=_lubricated_share(cz.lubrication_flags(frame, route, route_attributes),
                                     res.history),
        shape_res=shape, basis=basis,
    )
    if expected_progression is not None and factor is not None:
        # the expected progression's own exponent over these mileages: a named
        # nonlinear_progression reports expected + departure (``NonlinearProgression.public``)
        x = cz.NonlinearProgression().features(data, np.zeros(2))[:, 0, 0]
        data.cache["expected_exponent_offset"] = exponent_offset(
            centred(np.log(factor), cz.life_ids(frame, mileage), mileage), x)
        data.cache["expected_progression"] = expected_progression.source
    return data
