"""Where the curving contact table puts the flange contact, against the unsmoothed rigid gap.

A known defect of the default smoothing (stop 29, helper flange12; README "Limits and known
gaps"), held by a strict xfail: the table's 2 mm Gaussian smoothing of the vertical gap averages
the 100 mm fill of the wheel points beyond the rail's gauge face (no rail below them) into the
flank, which drags the smoothed minimum 3-6 mm down to the flange root. The opt-in
``gap_smoothing="masked"`` (``physics/gap_smoothing.py``) passes. Printed by
``benchmarks/curving_flange_table_vs_rigid.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics import curving as cv

_DEFECT = pytest.mark.xfail(strict=True, raises=AssertionError, reason=(
    "known defect of the default smoothing: it averages the 100 mm fill beyond the gauge face "
    "into the flank; the table's flange contact sits 3-6 mm down at the root (33-56 deg) where "
    "the rigid contact is on the flank (60-70 deg) and the rigid gap at the table's point is "
    "1-4 mm (benchmarks/curving_flange_table_vs_rigid.py). gap_smoothing='masked' fixes it but "
    "is not the default: the whole-vehicle loop is not step-converged with it (README)"))


@pytest.mark.parametrize("gap_smoothing", [pytest.param("gaussian", marks=_DEFECT), "masked"])
@pytest.mark.parametrize("inclination, pos_tol_mm, angle_tol_deg",
                         [(1 / 40, 2.5, 15.0), (1 / 20, 1.0, 6.0)])
def test_flange_contact_of_the_table_touches_the_rigid_geometry(inclination, pos_tol_mm,
                                                                 angle_tol_deg, gap_smoothing):
    # Once the flange touches (contact-level shift 7.5-9 mm for S1002 on 60E1), the table's
    # deepest candidate must lie near the minimum of the unsmoothed rigid gap (contact.geometry,
    # roll solved, the table's own rows before smoothing) and its contact angle near the rigid
    # one. Tolerances: what a smoothing restricted to the wheel points with rail below reaches
    # (1:40 0.7-2.2 mm and 4-13 deg, the one-sided average at the gauge face; 1:20 0.1-0.8 mm
    # and 1-4 deg), rounded up; today's table is 3-6 mm and up to 30 deg off.
    from wearcast.physics.contact.geometry import rigid_wheel_gap

    table = cv.build_contact_table(None, "60E1", inclination, 0.43,
                                   gap_smoothing=gap_smoothing)
    r0 = 430.0
    centre = np.arange(6.0, 8.5, 0.01)
    y_geo, raw, roll = rigid_wheel_gap(table.track, centre, "left")
    contact_level = centre + r0 * roll
    order = np.argsort(y_geo)
    y_geo, raw = y_geo[order], raw[:, order]
    slope = np.interp(y_geo, table.wheel_y_mm, table.wheel_slope)
    for shift in (7.5, 8.0, 8.5, 9.0):
        i = int(np.argmin(np.abs(contact_level - shift)))
        ours = table.candidates(contact_level[i])
        k = int(np.argmin(ours["gap_mm"]))
        row = raw[i]
        j = int(np.argmin(np.where(np.isfinite(row), row, np.inf)))
        assert abs(ours["wheel_y_mm"][k] - y_geo[j]) < pos_tol_mm, (shift, ours["wheel_y_mm"][k])
        rigid_angle = np.arctan(abs(slope[j]))
        assert abs(ours["angle_rad"][k] - rigid_angle) < np.radians(angle_tol_deg), shift
