"""Manchester contact benchmark A-2.2 from CONTACT's own profile files, case by case.

Reads the wheel and rail from ``MBench_S1002_v3.prw`` / ``MBench_UIC60_v3.prr``
(``physics.profiles.simpack``), and for both wheels and all 21 cases of
``mbench_a22_{left,right}.inp`` (shift 0-10 mm, yaw 1.2 mrad per 0.5 mm, the case's prescribed
roll and pitch rate, 10 kN vertical force per wheel, V = 2 m/s, G = 82 GPa, nu = 0.28,
mu = 0.3) runs ``physics.contact.wheel_rail.loaded_wheel_contact`` (contact locus with the
prescribed roll -> patches merged/split by the interpenetration region -> normal contact ->
FASTSIM on the equivalent ellipse) and prints, per case, wearcast - CONTACT for the contact
reference position on the wheel, the contact angle, F_n, F_x, F_s (creep forces relative to
mu F_n), p_max and the number of patches; then max and p95 per wheel.

Acceptance (issue 11): tread position within 0.5 mm, contact angle 0.01 rad, F_n 2 %, creep
forces 10 % (of mu F_n), the same number of patches in every case.

Usage: ``.venv/bin/python benchmarks/manchester_profiles.py [--method bem|kp|auto]
[path/to/reference]``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.contact.locus import wheel_locus
from wearcast.physics.contact.wheel_rail import loaded_wheel_contact
from wearcast.physics.profiles.simpack import rail_curve, read_simpack_profile, wheel_curve

DEFAULT_REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"
MU = 0.3


def mbench_track(bench: Path) -> WheelsetTrack:
    """Wheelset and track of A-2.2 from the benchmark's profile files (the rail file is
    already canted 1:40, so it is not inclined again)."""
    wheel = wheel_curve(read_simpack_profile(bench / "MBench_S1002_v3.prw"))
    rail = rail_curve(read_simpack_profile(bench / "MBench_UIC60_v3.prr"))
    return WheelsetTrack(wheel=wheel, rail=rail, rail_inclination=0.0)


def pitch_rates(inp: Path) -> np.ndarray:
    """|VPITCH| [rad/s] per case from the ``VS,VY,...`` lines of a CONTACT .inp file."""
    rows = [line.split() for line in inp.read_text().splitlines() if "VS,VY" in line]
    return np.abs(np.array([float(r[5]) for r in rows]))


def patch_counts(ref_out: Path) -> np.ndarray:
    """CONTACT's number of contact patches per case ("... WHEEL,  n CONTACT PATCH")."""
    counts = [int(line.split(",")[2].split()[0]) for line in ref_out.read_text().splitlines()
              if "WHEEL-RAIL CONTACT" in line and "CONTACT PATCH" in line]
    return np.array(counts)


def compare(bench: Path, contact_wheel: str, method: str = "bem",
            cases: list[int] | None = None) -> pd.DataFrame:
    """Per case: wearcast - CONTACT for one CONTACT wheel ("right" = our left wheel at shift
    +y_ws; "left" = our right wheel, lateral quantities negated)."""
    ref = pd.read_csv(bench / f"mbench_a22_{contact_wheel}_ref.csv")
    counts = patch_counts(bench / f"mbench_a22_{contact_wheel}.ref_out")
    omega = pitch_rates(bench / f"mbench_a22_{contact_wheel}.inp")
    rows = list(range(len(ref))) if cases is None else cases
    ref = ref.iloc[rows].reset_index(drop=True)
    our_side, sign = ("left", 1.0) if contact_wheel == "right" else ("right", -1.0)
    wt = mbench_track(bench)
    # CONTACT's roll is positive when its left wheel rises: minus ours
    locus = wheel_locus(wt, ref["y_ws_mm"].to_numpy(), our_side,
                        yaw_rad=ref["yaw_rad"].to_numpy(), roll_rad=-ref["roll_rad"].to_numpy())
    result = loaded_wheel_contact(locus, wt.nominal_radius_mm, 10_000.0, 2.0, omega[rows],
                                  mu=MU, method=method)
    out = []
    for i, wheel in enumerate(result):
        p = wheel.dominant
        mu_fn = MU * ref["Fn_N"][i]
        out.append({
            "wheel": f"CONTACT {contact_wheel}", "y_ws_mm": ref["y_ws_mm"][i],
            "patches": len(wheel.patches), "patches_ref": int(counts[rows[i]]),
            "d_y_w_mm": sign * p.normal.region.y_wheel_mm - ref["ycp_w_mm"][i],
            "d_delta_rad": sign * p.contact_angle_rad - ref["delta_rad"][i],
            "d_Fn_rel": p.normal_force_n / ref["Fn_N"][i] - 1.0,
            "d_Fx_muFn": (p.fx_n - ref["Fx_N"][i]) / mu_fn,
            "d_Fs_muFn": (sign * p.fs_n - ref["Fs_N"][i]) / mu_fn,
            "d_pmax_rel": p.normal.peak_pressure_mpa / ref["pmax_Nmm2"][i] - 1.0,
            "d_xi": p.xi - ref["cksi"][i],
            "method": p.normal.method,
        })
    return pd.DataFrame(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("reference", nargs="?", type=Path, default=DEFAULT_REFERENCE)
    parser.add_argument("--method", default="bem", choices=("bem", "kp", "auto", "hertz"))
    args = parser.parse_args()
    bench = args.reference / "contact-benchmark"
    pd.set_option("display.width", 160)
    frames = []
    for wheel in ("right", "left"):
        start = time.perf_counter()
        frame = compare(bench, wheel, args.method)
        elapsed = time.perf_counter() - start
        frames.append(frame)
        print(f"\n== CONTACT {wheel} wheel, method {args.method}: wearcast - CONTACT "
              f"({elapsed:.1f} s for 21 cases) ==")
        print(frame.drop(columns="wheel").to_string(index=False, float_format=lambda v:
                                                    f"{v:+.4f}"))
    table = pd.concat(frames, ignore_index=True)
    print("\n== summary over both wheels, 42 cases: max |dev| (p95 |dev|) ==")
    for column, label in (("d_y_w_mm", "position [mm]"), ("d_delta_rad", "angle [rad]"),
                          ("d_Fn_rel", "Fn [rel]"), ("d_Fx_muFn", "Fx [mu Fn]"),
                          ("d_Fs_muFn", "Fs [mu Fn]"), ("d_pmax_rel", "pmax [rel]")):
        values = np.abs(table[column].to_numpy())
        print(f"  {label:14s} {values.max():.4f} ({np.quantile(values, 0.95):.4f})")
    same = (table["patches"] == table["patches_ref"]).mean()
    print(f"  same number of patches in {same:.0%} of the cases")


if __name__ == "__main__":
    main()
