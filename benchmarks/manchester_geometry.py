"""Manchester contact benchmark A-2.2: wearcast's rigid contact geometry against CONTACT.

Prints, for both wheels and two profile sources (wearcast's analytic S1002 / 60E1 1:40, and
the benchmark's own profile files MBench_S1002_v3.prw / MBench_UIC60_v3.prr), with yaw
neglected and with the case's yaw angles, the max and RMS deviation of the wheel contact
position, the contact angle and the wheelset roll from the CONTACT reference results
(``reference/contact-benchmark/mbench_a22_{left,right}_ref.csv``), split by where the
flanging wheel touches (tread 0-4.5 mm, flange root 5-6 mm, flange 6.5-10 mm), plus the time
to build a contact table of 201 shifts.

Mapping of conventions (read from the .inp files): CONTACT's wheelset displacement y_ws > 0
moves the wheelset towards its RIGHT rail and its right wheel is the unmirrored one; wearcast
shifts are positive towards the LEFT rail.  By mirror symmetry CONTACT's right wheel at y_ws
equals wearcast's left wheel at shift +y_ws (same y_wheel, same contact angle sign), and
CONTACT's left wheel (printed mirrored: y_w = -y_wheel, delta = -delta) equals wearcast's right
wheel; CONTACT's roll = -wearcast roll.  CONTACT solves elastic contact at 10 kN per wheel with
the yaw angles of the case (up to 24 mrad); wearcast is rigid.

Usage: ``.venv/bin/python benchmarks/manchester_geometry.py [path/to/reference]``
"""

from __future__ import annotations

import itertools
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from wearcast.physics.contact.geometry import WheelsetTrack, contact_table, s1002_60e1
from wearcast.physics.profiles.simpack import rail_curve, read_simpack_profile, wheel_curve

DEFAULT_REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"


def mbench_wheelset(bench: Path) -> WheelsetTrack:
    """The benchmark's own profiles, read by ``physics.profiles.simpack`` (the wheel file's
    header mirrors it in y; the rail file is already canted 1:40 with z down, so it is turned
    to z up and not inclined again)."""
    wheel = wheel_curve(read_simpack_profile(bench / "MBench_S1002_v3.prw"))
    rail = rail_curve(read_simpack_profile(bench / "MBench_UIC60_v3.prr"))
    return WheelsetTrack(wheel=wheel, rail=rail, rail_inclination=0.0)


def compare(wt: WheelsetTrack, bench: Path, with_yaw: bool) -> pd.DataFrame:
    """Per-shift deviations of wearcast from the CONTACT reference for both wheels
    (CONTACT's yaw, turning the front towards the flanging rail, is wearcast's +yaw)."""
    right = pd.read_csv(bench / "mbench_a22_right_ref.csv")
    left = pd.read_csv(bench / "mbench_a22_left_ref.csv")
    yaw = right["yaw_rad"].to_numpy() if with_yaw else 0.0
    table = contact_table(wt, right["y_ws_mm"].to_numpy(), yaw_rad=yaw)
    frames = []
    for name, ref, ours, sign in (("right (ours: left)", right, table.left.primary, 1.0),
                                  ("left (ours: right)", left, table.right.primary, -1.0)):
        frames.append(pd.DataFrame({
            "wheel": name,
            "y_ws_mm": ref["y_ws_mm"],
            "d_y_wheel_mm": ours.y_wheel_mm - sign * ref["ycp_w_mm"],
            "d_delta_rad": ours.contact_angle_rad - sign * ref["delta_rad"],
            "d_roll_rad": table.roll_rad + ref["roll_rad"],
        }))
    return pd.concat(frames, ignore_index=True)


REGIMES = (("tread 0-4.5", 0.0, 4.5), ("root 5-6", 5.0, 6.0), ("flange 6.5-10", 6.5, 10.0))


def summary(deviations: pd.DataFrame) -> pd.DataFrame:
    """Max and RMS deviation per wheel, regime of the flanging wheel's contact and quantity.

    At 5.0 mm the flanging wheel is in two-point contact (tread and flange root within a few
    um of gap): with yaw our primary is the tread point and CONTACT's is the root point."""
    rows = []
    for wheel, group in deviations.groupby("wheel", sort=False):
        for regime, low, high in REGIMES:
            part = group[(group["y_ws_mm"] >= low) & (group["y_ws_mm"] <= high)]
            for quantity in ("d_y_wheel_mm", "d_delta_rad", "d_roll_rad"):
                values = part[quantity].to_numpy()
                rows.append({"wheel": wheel, "shifts": regime, "quantity": quantity[2:],
                             "max_abs": np.max(np.abs(values)),
                             "rms": np.sqrt(np.mean(values**2))})
    return pd.DataFrame(rows)


def main(reference: Path = DEFAULT_REFERENCE) -> None:
    bench = reference / "contact-benchmark"
    pd.set_option("display.width", 120)
    cases = (("analytic S1002 / 60E1 1:40", s1002_60e1()),
             ("MBench_S1002_v3.prw / MBench_UIC60_v3.prr", mbench_wheelset(bench)))
    for (label, wt), with_yaw in itertools.product(cases, (False, True)):
        deviations = compare(wt, bench, with_yaw)
        yaw_label = "with the case's yaw" if with_yaw else "yaw neglected (2D)"
        print(f"\n== {label}, {yaw_label}: wearcast - CONTACT, 21 shifts per wheel ==")
        print(summary(deviations).to_string(index=False, float_format=lambda v: f"{v:.5f}"))
    wt = s1002_60e1()
    contact_table(wt, [0.0])  # prepare the samples once
    start = time.perf_counter()
    repeats = 5
    for _ in range(repeats):
        contact_table(wt, np.linspace(-10.0, 10.0, 201))
    print(f"\ncontact_table, 201 shifts: {(time.perf_counter() - start) / repeats * 1e3:.0f} ms")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_REFERENCE)
