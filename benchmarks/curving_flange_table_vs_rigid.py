"""Where the curving table puts the flange contact, against the unsmoothed rigid geometry.

For S1002 on 60E1 (the Minuetto's 1:20 by default, ``--inclination 0.025`` for 1:40, r0 from
the ``minuetto`` preset) two blocks:

1. Over the contact-level shift of the wheelset (``curving_table.ContactTable.shift_mm``): the
   table's deepest contact candidate (wheel y [mm], contact angle [deg]) and the rigid geometry's
   (``contact.geometry.rigid_wheel_gap``, roll solved, the rows the table is built from before
   the 2 mm Gaussian smoothing: its minimum, the wheel's slope angle there, and the range of
   wheel y within 0.1 mm of it, a patch's approach), with the unsmoothed gap at the table's
   candidate: how far the point the table loads is from touching.
2. The leading high-rail wheel of the Minuetto (``--bogie``) at the Aosta radii of seed 003
   Table 3 (cant and speed of its first class of each radius): contact-level shift, the loaded
   flange patch (y, angle, N, semi-axis b), Y/Q of that wheel (lateral and vertical rail forces
   from N and the lateral creep force), the lateral creep coefficient mu_y = Fy / N, the
   smallest contact angle at which Nadal's relation Y/Q = (tan d - mu_y) / (1 + mu_y tan d)
   carries that Y/Q, and the unsmoothed rigid gap at the patch's y at that shift.
3. The Manchester trailer (S1002 on 60E1 1:40, cant 100 mm) at 150-600 m: the leading
   high-rail wheel's most loaded patch from the table (its Hertz ellipse on the smoothed gap:
   y, angle, N, b, peak pressure p0, tau_max of FASTSIM, T_gamma) against the one contact
   pipeline in its own force equilibrium (``solve_curving(contact_pipeline=True,
   pipeline_equilibrium=True)``: the multi-point geometry, patches merged by the
   interpenetration region, the non-Hertzian normal contact where the patch is not elliptic,
   FASTSIM on the patch, the bogie balanced with these forces; the pipeline matches CONTACT on
   the Manchester benchmark, README). The loaded patch's width, pressure and tau_max, not
   only its position, decide the wear; the unloaded first touch of blocks 1-2 is no reference
   for them (the approach spans root and flank). About 20 s (masked) to 45 s (gaussian).
4. Why the two flange patches of block 3 sit where they do, at the pipeline's balanced pose:
   the pipeline's pressure centre y_p, its reference (the interpenetration centre of gravity
   of ``contact.patches``) and contact angle delta_r (the mean of the locus angles over the
   interpenetration region, the direction of its normal force); the wheel's slope angle at
   y_p, at the point and averaged with the gap's own weights at the wheel's shift
   (``ContactTable.contact_slope_at``);
   and the table's patch at the same pose (y, angle). The force angle is what the equilibrium
   fixes; the table puts its patch where its contact angle equals it.

Run: ``.venv/bin/python benchmarks/curving_flange_table_vs_rigid.py [--inclination 0.05]
[--bogie trailer] [--gap-smoothing masked] [--rail-edge-ramp-mm 3]`` (about 1 min).
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from wearcast.physics import gap_smoothing as gs
from wearcast.physics.bogie_equations import (
    SHEAR_MODULUS_MPA,
    SIDE_SIGN,
    bogie_residual,
    centre_shift,
    wheel_loads,
    wheelset_roll,
    wheelset_unknowns,
)
from wearcast.physics.contact.geometry import rigid_wheel_gap
from wearcast.physics.contact.pose_contact import Pose, contact_at_poses
from wearcast.physics.curving import DEFAULT_CREEP_GRID, solve_curving
from wearcast.physics.curving_table import build_contact_table, vehicle_contact_table
from wearcast.physics.vehicles import vehicle_preset

#: Seed 003 Table 3 (n_class = 7): radius [m], cant [mm], speed [km/h] of the first class of
#: each of the four sharpest radii.
AOSTA_POINTS = ((162.0, 110.0, 57.0), (195.0, 90.0, 60.0), (237.0, 70.0, 60.0),
                (293.0, 50.0, 60.0))


def _rigid_rows(table, r0_mm: float):
    """Unsmoothed rigid gap rows over a fine grid of centre shifts, with their contact-level
    shift: (contact-level shift (n,), wheel y sorted (m,), gap (n, m) [mm])."""
    centre = np.arange(0.0, 12.0, 0.01)
    y, gap, roll = rigid_wheel_gap(table.track, centre, "left")
    order = np.argsort(y)
    return centre + r0_mm * roll, y[order], gap[:, order]


def _rigid_at(level, y, gap, shift_mm: float):
    """The rigid row nearest the contact-level shift: (wheel y, gap) where the rail is below."""
    row = gap[int(np.argmin(np.abs(level - shift_mm)))]
    on = np.isfinite(row)
    return y[on], row[on]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--inclination", type=float, default=None,
                        help="rail inclination (default: the preset's, 1/20)")
    parser.add_argument("--bogie", default="trailer", choices=("trailer", "motor"))
    parser.add_argument("--gap-smoothing", default=gs.GAP_SMOOTHING,
                        choices=gs.GAP_SMOOTHING_METHODS,
                        help="how the contact table's gap is smoothed (physics/gap_smoothing.py)")
    parser.add_argument("--rail-edge-ramp-mm", type=float, default=gs.RAIL_EDGE_RAMP_MM,
                        help="the masked smoothing's ramp of the rail's coverage [mm]")
    args = parser.parse_args()
    gs.GAP_SMOOTHING = args.gap_smoothing
    gs.RAIL_EDGE_RAMP_MM = args.rail_edge_ramp_mm
    print(f"gap smoothing {gs.GAP_SMOOTHING}"
          + (f", rail-edge ramp {gs.RAIL_EDGE_RAMP_MM:g} mm" if gs.GAP_SMOOTHING == "masked"
             else ""))
    vehicle = vehicle_preset("minuetto", args.bogie)
    if args.inclination is not None:
        vehicle = replace(vehicle, rail_inclination=args.inclination)
    r0_mm = 1000.0 * vehicle.wheel_radius_m
    table = build_contact_table(None, vehicle.rail_profile, vehicle.rail_inclination,
                                vehicle.wheel_radius_m)
    level, y_geo, gap = _rigid_rows(table, r0_mm)
    slope = np.interp(y_geo, table.wheel_y_mm, table.wheel_slope)
    print(f"S1002 on {vehicle.rail_profile} 1:{1 / vehicle.rail_inclination:.0f}, "
          f"r0 {r0_mm:.0f} mm")
    print("shift | table: y, angle | rigid: y, angle, within 0.1 mm | rigid gap at table's y")
    for shift in np.arange(6.0, 10.01, 0.5):
        c = table.candidates(shift)
        k = int(np.argmin(c["gap_mm"]))
        yr, gr = _rigid_at(level, y_geo, gap, shift)
        j = int(np.argmin(gr))
        near = yr[gr - gr[j] < 0.1]
        angle = np.degrees(np.arctan(abs(np.interp(yr[j], y_geo, slope))))
        at_table = np.interp(c["wheel_y_mm"][k], yr, gr) - gr[j]
        print(f"{shift:5.1f} | {c['wheel_y_mm'][k]:6.1f} {np.degrees(c['angle_rad'][k]):5.1f} | "
              f"{yr[j]:6.1f} {angle:5.1f} [{near.min():6.1f}, {near.max():6.1f}] | "
              f"{at_table:6.3f}")
    print(f"\nleading high-rail wheel, minuetto {args.bogie}, mu {vehicle.friction}")
    print("R m | shift | patch y, angle, N kN, b mm | Y/Q | mu_y | Nadal min angle | "
          "rigid gap at patch")
    for radius, cant, speed in AOSTA_POINTS:
        res = solve_curving(vehicle, radius, cant_mm=cant, speed_m_s=speed / 3.6,
                            direction="left", table=table)
        high = 1  # the right wheel runs on the high rail of a left curve
        on = res.in_contact[0, high] & (res.wheel_y_mm[0, high] < -30.0)
        n = res.normal_force_n[0, high]
        d = res.contact_angle_rad[0, high]
        fy = res.fy_n[0, high]
        loaded = res.in_contact[0, high]
        q = float(np.sum(np.where(loaded, n * np.cos(d) + fy * np.sin(d), 0.0)))
        y_force = float(np.sum(np.where(loaded, n * np.sin(d) - fy * np.cos(d), 0.0)))
        shift = abs(float(res.contact_shift_mm[0]))
        if not np.any(on):
            print(f"{radius:5.0f} | {shift:5.2f} | no flange patch | {y_force / q:4.2f}")
            continue
        k = int(np.argmax(np.where(on, n, -1.0)))
        mu_y = float(fy[k] / n[k])
        ratio = y_force / q
        nadal = np.degrees(np.arctan((ratio + mu_y) / (1.0 - mu_y * ratio)))
        yr, gr = _rigid_at(level, y_geo, gap, shift)
        at_patch = np.interp(res.wheel_y_mm[0, high, k], yr, gr) - np.min(gr)
        print(f"{radius:5.0f} | {shift:5.2f} | {res.wheel_y_mm[0, high, k]:6.1f} "
              f"{np.degrees(d[k]):5.1f} {n[k] / 1e3:5.1f} {res.b_mm[0, high, k]:5.2f} | "
              f"{ratio:4.2f} | {mu_y:4.2f} | {nadal:5.1f} | {at_patch:6.3f}")
    _table_against_pipeline()


def _table_against_pipeline() -> None:
    """Block 3 (module docstring)."""
    trailer = vehicle_preset("manchester", "trailer")
    print("\nleading high-rail wheel, manchester trailer, cant 100 mm: table vs the pipeline "
          "in its own equilibrium")
    print("R m | table: y, angle, N kN, b mm, p0 MPa, tau_max MPa, T_gamma N | "
          "pipeline: y, angle, N kN, b mm, pmax MPa, tau_max MPa, T_gamma N | residual")
    solved = []
    for radius in (150.0, 250.0, 400.0, 600.0):
        res = solve_curving(trailer, radius, cant_mm=100.0, contact_pipeline=True,
                            pipeline_equilibrium=True)
        solved.append(res)
        t, p = res.leading_high_rail_patch(), res.leading_high_rail_patch("pipeline")
        print(f"{radius:5.0f} | {t['wheel_y_mm']:6.2f} {np.degrees(t['contact_angle_rad']):5.1f} "
              f"{t['normal_force_n'] / 1e3:5.1f} {t['b_mm']:5.2f} {t['p0_mpa']:6.0f} "
              f"{t['tau_max_mpa']:6.0f} {t['t_gamma_n']:5.0f} | "
              f"{p['wheel_y_mm']:6.2f} {np.degrees(p['contact_angle_rad']):5.1f} "
              f"{p['normal_force_n'] / 1e3:5.1f} {p['b_mm']:5.2f} "
              f"{p['peak_pressure_mpa']:6.0f} {p['tau_max_mpa']:6.0f} "
              f"{p['t_gamma_n']:5.0f} | {res.pipeline_residual_norm:.1e}")
    _patch_reference(trailer, solved)


def _patch_reference(trailer, solved) -> None:
    """Block 4 (module docstring)."""
    table = vehicle_contact_table(trailer, "left")
    high = 1  # the right wheel runs on the high rail of a left curve

    def slope_deg(column, y):
        return np.degrees(np.arctan(-np.interp(y, table.wheel_y_mm, column)))

    def averaged_deg(shift, y):
        # the averaged slope at the wheel's shift (``ContactTable.contact_slope_at``)
        return float(np.degrees(np.arctan(-table.side(high).contact_slope_at(shift, [y])[0])))

    print("\nthe same patches at the pipeline's balanced pose (angles in deg, y in mm)")
    print("R m | pipeline: pressure centre y, reference y, delta_r | wheel slope angle at the "
          "pressure centre: point, averaged | table at this pose: y, angle")
    for res in solved:
        q = res.pipeline["state"][None]
        ws = wheelset_unknowns(q)
        y, d = ws[..., 0], ws[..., 3:5]
        kappa = np.array([1.0 / res.radius_m])
        a_unb = np.array([res.unbalanced_acceleration_m_s2])
        pose = Pose(float(centre_shift(table, y, d)[0, 0]), float(ws[0, 0, 1]) * 1e-3,
                    float(wheelset_roll(table, y, d)[0, 0]),
                    float(wheel_loads(trailer, a_unb)[0, high]),
                    1.0 + float(ws[0, 0, 2]) * 1e-3, float(kappa[0]))
        loaded = contact_at_poses(table.track, "right", [pose], speed_m_s=1.0,
                                  mu=trailer.friction, shear_modulus_mpa=SHEAR_MODULUS_MPA,
                                  n_grid=DEFAULT_CREEP_GRID)[0].loaded
        n = max((p.normal for p in loaded.patches), key=lambda n: n.normal_force_n)
        _, c = bogie_residual(q, trailer, table, kappa, a_unb, trailer.traction_torque_nm,
                              return_contacts=True, creep_grid=DEFAULT_CREEP_GRID)
        k = int(np.argmax(c.normal_force_n[0, 0, high]))
        yp = n.centre_y_wheel_mm
        print(f"{res.radius_m:5.0f} | {yp:6.2f} {n.region.y_wheel_mm:6.2f} "
              f"{np.degrees(-n.contact_angle_rad):5.1f} | "
              f"{slope_deg(table.wheel_slope, yp):5.1f} "
              f"{averaged_deg(SIDE_SIGN[high] * float(y[0, 0]), yp):5.1f}"
              f" | {c.wheel_y_mm[0, 0, high, k]:6.2f} "
              f"{np.degrees(c.contact_angle_rad[0, 0, high, k]):5.1f}")


if __name__ == "__main__":
    main()
