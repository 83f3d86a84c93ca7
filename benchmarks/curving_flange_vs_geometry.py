"""Flange contact of the curving model against the contact pipeline on the same pose.

For S1002 on 60E1 1:40 (the Manchester trailer) the quasi-static curving is solved at radii
150-600 m; for the leading wheelset's high-rail wheel the most loaded flange patch (wheel
y < -30 mm) is compared, position on the wheel [mm] and contact angle [deg], with

- the rigid geometry (``contact.geometry.contact_table``) at the curving solution's wheelset
  shift, no yaw, roll solved (the first-touch point: it jumps from the flange root to the
  flank at a shift of about 6.3 mm, where the curving equilibria sit);
- the non-Hertzian pipeline (``contact.wheel_rail``, CONTACT's wheel-rail module: patches from
  the interpenetration region, normal problem by BEM/Hertz, FASTSIM) at the curving pose —
  shift, roll and the wheel's vertical load — first without yaw (the geometry the curving
  table is built on, so this column measures the table) and then with the curving yaw (what
  the table leaves out).

Run: ``.venv/bin/python benchmarks/curving_flange_vs_geometry.py [--flange-smoothing MM]``
(a few seconds; the option builds the curving table with that smoothing of the gap on the
flange instead of ``curving_table.GAP_SMOOTHING_MM``'s)
"""

from __future__ import annotations

import argparse

import numpy as np

from wearcast.physics import curving
from wearcast.physics.contact.geometry import contact_table, s1002_60e1
from wearcast.physics.contact.locus import wheel_locus
from wearcast.physics.contact.wheel_rail import loaded_wheel_contact
from wearcast.physics.curving_table import GAP_SMOOTHING_MM, build_contact_table
from wearcast.physics.vehicles import vehicle_preset


def _pipeline_patch(track, shift_mm: float, side: str, yaw_rad: float, roll_rad: float,
                    load_n: float, r0_mm: float) -> tuple[float, float]:
    """Wheel y [mm] and |contact angle| [deg] of the most loaded patch of the pipeline."""
    locus = wheel_locus(track, [shift_mm], side, yaw_rad=yaw_rad, roll_rad=roll_rad)
    patches = loaded_wheel_contact(locus, r0_mm, wheel_load_n=load_n, method="auto")[0].patches
    best = max(patches, key=lambda p: p.normal.normal_force_n)
    return best.normal.centre_y_wheel_mm, float(np.degrees(abs(best.normal.contact_angle_rad)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--flange-smoothing", type=float, default=GAP_SMOOTHING_MM[1],
                        help="Gaussian smoothing of the gap on the flange [mm]")
    args = parser.parse_args()
    vehicle = vehicle_preset("manchester", "trailer")
    table = build_contact_table(None, vehicle.rail_profile, vehicle.rail_inclination,
                                vehicle.wheel_radius_m,
                                smoothing_mm=(GAP_SMOOTHING_MM[0], args.flange_smoothing))
    print(f"gap smoothing: tread {GAP_SMOOTHING_MM[0]} mm, flange {args.flange_smoothing} mm")
    radii = [150.0, 200.0, 250.0, 300.0, 400.0, 500.0, 600.0]
    cases = [curving.curve_case(r, 0.0, None, "left", 0.58) for r in radii]
    results = curving.solve_curving_cases(vehicle, cases, table=table)
    track = s1002_60e1()
    r0_mm = 1000.0 * vehicle.wheel_radius_m
    print("radius  shift  yaw    | curving y angle | rigid y angle | pipeline y angle "
          "(no yaw) | pipeline y angle (yaw) | diff y vs rigid, pipeline, pipeline+yaw")
    diffs: dict[str, list[float]] = {"rigid": [], "pipeline": [], "yaw": []}
    for r, res in zip(radii, results, strict=True):
        high = curving.SIDES.index(res.high_rail_side)
        side = curving.SIDES[high]
        loaded = res.in_contact[0, high] & (res.wheel_y_mm[0, high] < curving.FLANGE_SPLIT_Y_MM)
        if not np.any(loaded):
            print(f"{r:6.0f}  no flange contact")
            continue
        k = int(np.argmax(np.where(loaded, res.normal_force_n[0, high], -1.0)))
        y_c = float(res.wheel_y_mm[0, high, k])
        a_c = float(np.degrees(res.contact_angle_rad[0, high, k]))
        shift = float(res.wheelset_shift_mm[0])
        yaw = float(res.wheelset_yaw_rad[0])
        roll = float(res.wheelset_roll_rad[0])
        on = res.in_contact[0, high]
        load = float(np.sum(res.normal_force_n[0, high][on]
                            * np.cos(res.contact_angle_rad[0, high][on])))
        geo = contact_table(track, [shift])
        wheel = geo.right if high == 1 else geo.left
        ys = [wheel.primary.y_wheel_mm[0]]
        angles = [wheel.primary.contact_angle_rad[0]]
        if wheel.secondary.valid[0]:
            ys.append(wheel.secondary.y_wheel_mm[0])
            angles.append(wheel.secondary.contact_angle_rad[0])
        j = int(np.argmin(ys))  # the flange point is the one nearer the flange
        y_p, a_p = _pipeline_patch(track, shift, side, 0.0, roll, load, r0_mm)
        y_py, a_py = _pipeline_patch(track, shift, side, yaw, roll, load, r0_mm)
        d = (y_c - ys[j], y_c - y_p, y_c - y_py)
        for key, v in zip(diffs, d, strict=True):
            diffs[key].append(abs(v))
        print(f"{r:6.0f} {shift:6.2f} {1e3 * yaw:6.2f} | {y_c:8.2f} {a_c:5.1f} | "
              f"{ys[j]:7.2f} {np.degrees(abs(angles[j])):5.1f} | {y_p:8.2f} {a_p:5.1f}"
              f"          | {y_py:8.2f} {a_py:5.1f}        | {d[0]:6.2f} {d[1]:6.2f} {d[2]:6.2f}")
    if diffs["rigid"]:
        n = len(diffs["rigid"])
        print(f"max |diff y| over {n} radii with flange contact: rigid geometry "
              f"{max(diffs['rigid']):.2f} mm, pipeline without yaw {max(diffs['pipeline']):.2f}"
              f" mm, pipeline with the curving yaw {max(diffs['yaw']):.2f} mm")


if __name__ == "__main__":
    main()
