"""The curving model's creepages (``bogie_equations``) against the exact rigid-body kinematics
(``contact.creepages``) at the contact points of the rigid geometry with yaw
(``contact.geometry``): the lateral creepage carries the contact point's lead."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.contact.creepages import rigid_creepages
from wearcast.physics.contact.geometry import contact_table, s1002_60e1


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("yaw_rad", [-0.015, 0.004])
def test_lateral_creepage_is_the_yaw_over_the_cosine_of_the_contact_angle(side, yaw_rad):
    # S1002 on 60E1 1:40, the wheelset shifted towards the flanging wheel from the tread
    # (4.5 deg) through the flange root to the flank (70 deg), yawed: the exact lateral
    # creepage at the geometry's contact point is psi / cos(delta) within 5 % (measured 0.2-4.5
    # %: the rest is the roll and the point's exact position), the curving model's formula
    # (bogie_equations); psi cos(delta), the formula before stop 30, is up to 9x too small.
    track = s1002_60e1()
    r0 = track.nominal_radius_mm
    sign = 1.0 if side == "left" else -1.0
    speed_m_s = 20.0
    ratios, old = [], []
    for shift in (2.0, 5.0, 6.0, 6.3, 6.6, 7.0, 8.0):
        t = contact_table(track, [sign * shift], yaw_rad=yaw_rad)
        p = (t.left if side == "left" else t.right).primary
        delta = p.contact_angle_rad[0]
        point = np.array([[p.x_track_mm[0]], [p.y_track_mm[0]], [p.z_track_mm[0]]])
        _, eta, _ = rigid_creepages(side, speed_m_s, speed_m_s * 1000.0 / r0, sign * shift,
                                    yaw_rad, t.roll_rad[0], t.height_mm[0], r0, point, [delta])
        ratios.append(abs(eta[0]) / (abs(yaw_rad) / np.cos(delta)))
        old.append(abs(eta[0]) / (abs(yaw_rad) * np.cos(delta)))
        # CONTACT's eta = s psi / cos(delta), the curving's -s psi / cos(delta) negated
        assert np.sign(eta[0]) == sign * np.sign(yaw_rad)
    np.testing.assert_allclose(ratios, 1.0, atol=0.05)
    assert max(old) > 8.0  # the flank: 1 / cos^2(70 deg)
