"""Flange contact of the curving model against the rigid geometry module on the same pose.

For S1002 on 60E1 1:40 (the Manchester vehicle) the quasi-static curving is solved at radii
150-600 m; for the leading wheelset's high-rail wheel the loaded flange patch (wheel y < -30
mm) is compared with the rigid contact geometry (``contact.geometry.contact_table``) at the
curving solution's wheelset shift: position on the wheel [mm] and contact angle [deg]. The
elastic approach moves the loaded point a little; the rest is the curving table's smoothing of
the gap (2 mm, ``curving.build_contact_table``).

Run: ``.venv/bin/python benchmarks/curving_flange_vs_geometry.py``
"""

from __future__ import annotations

import numpy as np

from wearcast.physics import curving
from wearcast.physics.contact.geometry import contact_table, s1002_60e1
from wearcast.physics.vehicles import vehicle_preset


def main() -> None:
    vehicle = vehicle_preset("manchester", "trailer")
    radii = [150.0, 200.0, 250.0, 300.0, 400.0, 500.0, 600.0]
    cases = [curving.curve_case(r, 0.0, None, "left", 0.58) for r in radii]
    results = curving.solve_curving_cases(vehicle, cases)
    track = s1002_60e1()
    print("radius  shift   curving y  angle | geometry y  angle | diff y [mm]")
    diffs = []
    for r, res in zip(radii, results, strict=True):
        high = curving.SIDES.index(res.high_rail_side)
        loaded = res.in_contact[0, high] & (res.wheel_y_mm[0, high] < curving.FLANGE_SPLIT_Y_MM)
        if not np.any(loaded):
            print(f"{r:6.0f}  no flange contact")
            continue
        k = int(np.argmax(np.where(loaded, res.normal_force_n[0, high], -1.0)))
        shift = float(res.wheelset_shift_mm[0])
        geo = contact_table(track, [shift])
        wheel = geo.right if high == 1 else geo.left
        ys = [wheel.primary.y_wheel_mm[0]]
        angles = [wheel.primary.contact_angle_rad[0]]
        if wheel.secondary.valid[0]:
            ys.append(wheel.secondary.y_wheel_mm[0])
            angles.append(wheel.secondary.contact_angle_rad[0])
        j = int(np.argmin(ys))  # the flange point is the one nearer the flange
        dy = float(res.wheel_y_mm[0, high, k] - ys[j])
        diffs.append(abs(dy))
        print(f"{r:6.0f} {shift:6.2f}   {res.wheel_y_mm[0, high, k]:8.2f} "
              f"{np.degrees(res.contact_angle_rad[0, high, k]):6.1f} | {ys[j]:9.2f} "
              f"{np.degrees(abs(angles[j])):6.1f} | {dy:6.2f}")
    if diffs:
        print(f"max |diff y| {max(diffs):.2f} mm over {len(diffs)} radii with flange contact")


if __name__ == "__main__":
    main()
