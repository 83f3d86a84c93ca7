"""Per-class contacts of the bogie's wheels (``physics/class_contacts.py``): the error when no
operating point of a route converges."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics import class_contacts as cc
from wearcast.physics.curving import CurvingConvergenceError
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicle_wear_simulation import vehicle_bogies
from wearcast.physics.vocabulary import CurveClass


def test_no_converged_class_names_the_sharpest_radius_and_every_radius_tried(monkeypatch):
    # When every operating point fails and there is no previous contact to keep, the error
    # names the radii (it used to say "radius inf m", as if only tangent track had been tried).
    monkeypatch.setattr(cc, "_solve_points",
                        lambda vehicle, points, *args, **kw: [None] * len(points))
    bogie = vehicle_bogies("metro_b")[0][0]
    y = np.linspace(-70.0, 60.0, 651)
    classes = [CurveClass(300.0, 100.0, None, "left", 0.3), CurveClass(120.0, 100.0, None,
                                                                       "right", 0.3),
               CurveClass(None, share=0.4)]
    for call in (cc.class_contacts_all_wheels, cc.class_contacts):
        with pytest.raises(CurvingConvergenceError,
                           match=r"radii tried: 120, 300, tangent m") as err:
            call(bogie, classes, y, s1002_height_mm(y))
        assert err.value.radius_m == 120.0
