"""Flange contact of the curving model against the contact pipeline on the same pose.

For S1002 on 60E1 1:40 (the Manchester trailer) the quasi-static curving is solved at radii
150-600 m with ``contact_pipeline=True``; for the leading wheelset's high-rail wheel the most
loaded flange patch (wheel y < -30 mm) is compared, position on the wheel [mm] and contact
angle [deg]:

- the curving table's own contact (``curving_table``: vertical approach on the smoothed gap,
  which loads the flange root);
- the contact pipeline at the curving's pose (``CurvingResult.pipeline``,
  ``curving_contacts``: shift, yaw, roll, rolling ratio, curvature and wheel load);
- the rigid geometry (``contact.geometry.contact_table``) at the curving's wheelset shift and
  yaw, roll solved: the geometry module's first-touch flange point, the reference of issue 11
  (0.5 mm).

The pipeline's residual column is the scaled bogie equilibrium residual with the pipeline's
forces in place of the table's (the table's equilibrium is solved to 1e-6): how far the
pipeline's forces are from balancing the curving's state. The second block solves the
equilibrium with the pipeline's forces (``pipeline_equilibrium=True``, homotopy from the table's
equilibrium) and compares its flange contact with the table's contact, and shows the unloaded
first touch at that pose (``contact.locus``, the same roll) with the range of wheel y where the
gap is within 10 um of it (up to 6.7 mm on the conformal root-flank region): under a
patch's approach of ~0.1 mm the loaded patch spans root and flank, so the first-touch point is
no reference for it there.

Run: ``.venv/bin/python benchmarks/curving_flange_vs_geometry.py [--flange-smoothing MM]``
(about 3 min, mostly the second block's pipeline equilibria; the option builds the curving
table with that smoothing of the gap on the flange instead of ``curving_table.GAP_SMOOTHING_MM``'s)
"""

from __future__ import annotations

import argparse

import numpy as np

from wearcast.physics import curving
from wearcast.physics.contact.geometry import contact_table, s1002_60e1
from wearcast.physics.contact.locus import wheel_locus
from wearcast.physics.curving_table import GAP_SMOOTHING_MM, build_contact_table
from wearcast.physics.vehicles import vehicle_preset


def _flange(y_mm: np.ndarray, angle_rad: np.ndarray, normal_n: np.ndarray,
            loaded: np.ndarray) -> tuple[float, float] | None:
    """Wheel y [mm] and contact angle [deg] of the most loaded flange patch (y < -30 mm)."""
    on = loaded & (y_mm < curving.FLANGE_SPLIT_Y_MM)
    if not np.any(on):
        return None
    k = int(np.argmax(np.where(on, normal_n, -1.0)))
    return float(y_mm[k]), float(np.degrees(angle_rad[k]))


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
    results = curving.solve_curving_cases(vehicle, cases, table=table, contact_pipeline=True)
    track = s1002_60e1()
    print("leading wheelset, high-rail wheel, most loaded flange patch: wheel y [mm], contact "
          "angle [deg]")
    print("radius  shift  yaw    | table y angle  | pipeline y angle | rigid y angle | "
          "|pipeline - rigid| |table - rigid| | pipeline equilibrium residual")
    diffs: dict[str, list[float]] = {"pipeline": [], "table": []}
    for r, res in zip(radii, results, strict=True):
        high = curving.SIDES.index(res.high_rail_side)
        tab = _flange(res.wheel_y_mm[0, high], res.contact_angle_rad[0, high],
                      res.normal_force_n[0, high], res.in_contact[0, high])
        p = res.pipeline
        assert p is not None
        pip = _flange(p["wheel_y_mm"][0, high], p["contact_angle_rad"][0, high],
                      p["normal_force_n"][0, high], p["in_contact"][0, high])
        if tab is None or pip is None:
            print(f"{r:6.0f}  no flange contact (table: {tab is not None}, pipeline: "
                  f"{pip is not None})")
            continue
        shift = float(res.wheelset_shift_mm[0])
        yaw = float(res.wheelset_yaw_rad[0])
        geo = contact_table(track, [shift], yaw_rad=yaw)
        wheel = geo.right if high == 1 else geo.left
        ys = [wheel.primary.y_wheel_mm[0]]
        angles = [wheel.primary.contact_angle_rad[0]]
        if wheel.secondary.valid[0]:
            ys.append(wheel.secondary.y_wheel_mm[0])
            angles.append(wheel.secondary.contact_angle_rad[0])
        j = int(np.argmin(ys))  # the flange point is the one nearer the flange
        d_p, d_t = abs(pip[0] - ys[j]), abs(tab[0] - ys[j])
        diffs["pipeline"].append(d_p)
        diffs["table"].append(d_t)
        print(f"{r:6.0f} {shift:6.2f} {1e3 * yaw:6.2f} | {tab[0]:7.2f} {tab[1]:5.1f} | "
              f"{pip[0]:8.2f} {pip[1]:5.1f}   | {ys[j]:7.2f} {np.degrees(abs(angles[j])):5.1f} | "
              f"{d_p:17.2f} {d_t:15.2f} | {res.pipeline_residual_norm:8.3f}")
    if diffs["pipeline"]:
        n = len(diffs["pipeline"])
        print(f"max |diff y| from the rigid geometry over {n} radii with flange contact: the "
              f"curving's pipeline contacts {max(diffs['pipeline']):.2f} mm, its table contacts "
              f"{max(diffs['table']):.2f} mm")

    print("\nequilibrium with the pipeline's forces (homotopy from the table's):")
    print("radius  shift  roll[mrad] | pipeline y angle | first touch, gap < 10 um from .. to | "
          "|pipeline - table| | residual")
    consistent = curving.solve_curving_cases(vehicle, cases, table=table, contact_pipeline=True,
                                             pipeline_equilibrium=True)
    worst: list[float] = []
    for r, res in zip(radii, consistent, strict=True):
        high = curving.SIDES.index(res.high_rail_side)
        p = res.pipeline
        assert p is not None
        pip = _flange(p["wheel_y_mm"][0, high], p["contact_angle_rad"][0, high],
                      p["normal_force_n"][0, high], p["in_contact"][0, high])
        tab = _flange(res.wheel_y_mm[0, high], res.contact_angle_rad[0, high],
                      res.normal_force_n[0, high], res.in_contact[0, high])
        shift = float(p["wheelset_shift_mm"][0])
        roll = float(p["wheelset_roll_rad"][0])
        if pip is None or tab is None:
            print(f"{r:6.0f} {shift:6.2f} {1e3 * roll:7.2f}  no flange contact "
                  f"(residual {res.pipeline_residual_norm:.2g})")
            continue
        locus = wheel_locus(track, [shift], curving.SIDES[high],
                            yaw_rad=np.array([float(p["wheelset_yaw_rad"][0])]),
                            roll_rad=np.array([roll]))
        gap = locus.gap_mm[0]
        first = int(np.argmin(gap))
        near = locus.y_wheel_mm[gap < 0.01]
        worst.append(abs(pip[0] - tab[0]))
        print(f"{r:6.0f} {shift:6.2f} {1e3 * roll:7.2f}    | {pip[0]:8.2f} {pip[1]:5.1f}   | "
              f"{locus.y_wheel_mm[first]:7.2f} {np.min(near):7.2f} {np.max(near):7.2f}   | "
              f"{abs(pip[0] - tab[0]):17.2f} | {res.pipeline_residual_norm:8.2g}")
    if worst:
        print(f"max |diff y| of the flange contact, pipeline at its equilibrium vs the table at "
              f"its own, over {len(worst)} radii: {max(worst):.2f} mm (radii whose residual is "
              f"above {curving.PIPELINE_TOLERANCE:g} included)")

if __name__ == "__main__":
    main()
