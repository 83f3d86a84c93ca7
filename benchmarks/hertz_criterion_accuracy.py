"""The production normal-contact method's Hertz fast path against the boundary-element solution.

The production method ("auto", ``contact.normal_contact``) solves a patch by Hertz where its
criterion (``normal_contact.is_elliptic``) says the patch really is elliptic, else by the
coarse boundary-element method. This script measures the criterion's error where it picks
Hertz: for every case the wheel's patches carry the wheel load with "auto" and with the fine
BEM ("bem", CONTACT's 0.2 mm grid, the reference), and for every patch "auto" solved by Hertz
the BEM patch nearest it (pressure centre on the wheel) gives

- the contact position: |y_wheel(Hertz) - y_wheel(BEM)| of the pressure centres [mm],
- the normal force relative to the BEM's,
- the peak pressure relative to the BEM's,

printed per case set and over all cases as p95 (max), with the share of patches that took the
Hertz path (issue 11's goal where Hertz is chosen: position 0.5 mm, F_n 5 %, peak pressure
10 %, p95).

Cases: those of ``normal_contact_accuracy.py`` (S1002 on 60E1 1:40 and 1:20, the MiniProf
wheels of the reference data, raw points, on 60E1 1:40; shifts -4 ... 4 mm, roll solved, 10 and
60 kN) and the Manchester A-2.2 cases of ``manchester_profiles.py`` (CONTACT's
``MBench_S1002_v3.prw`` / ``MBench_UIC60_v3.prr``, both wheels, 21 shifts with the prescribed
yaw and roll, 10 kN). Normal contact only (no creep forces in the vertical balance).

Usage: ``.venv/bin/python benchmarks/hertz_criterion_accuracy.py [--quick] [path/to/reference]``
(about 3 min; it uses only the public API, so another checkout's interpreter runs it too).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from manchester_profiles import mbench_track  # noqa: E402
from normal_contact_accuracy import DEFAULT_REFERENCE, case_sets  # noqa: E402

from wearcast.physics.contact.locus import WheelLocus, wheel_locus  # noqa: E402
from wearcast.physics.contact.normal_contact import wheel_normal_contact  # noqa: E402


def compare(label: str, locus: WheelLocus, load_n: float, shifts: np.ndarray) -> pd.DataFrame:
    """Per patch of "auto": its method and, against the nearest fine-BEM patch, the errors."""
    t0 = time.perf_counter()
    fast = wheel_normal_contact(locus, load_n, method="auto")
    t_fast = (time.perf_counter() - t0) / shifts.size
    ref = wheel_normal_contact(locus, load_n, method="bem")
    rows = []
    for i, (f, r) in enumerate(zip(fast, ref, strict=True)):
        for pf in f.patches:
            pr = min(r.patches, key=lambda p, pf=pf: abs(p.centre_y_wheel_mm
                                                         - pf.centre_y_wheel_mm))
            rows.append({"case_set": label, "load_kN": load_n / 1e3, "shift_mm": shifts[i],
                         "method": pf.method,
                         "d_pos_mm": pf.centre_y_wheel_mm - pr.centre_y_wheel_mm,
                         "d_fn_rel": pf.normal_force_n / pr.normal_force_n - 1.0,
                         "d_pmax_rel": pf.peak_pressure_mpa / pr.peak_pressure_mpa - 1.0,
                         "t_auto_s": t_fast})
    return pd.DataFrame(rows)


def _p95_max(values: pd.Series) -> str:
    v = values.abs().to_numpy()
    if v.size == 0:
        return "        -        "
    return f"{np.quantile(v, 0.95):7.4f} ({v.max():7.4f})"


def summary(table: pd.DataFrame, title: str) -> None:
    hertz = table[table.method == "hertz"]
    print(f"\n== {title}: {len(table)} patches, Hertz in {len(hertz)} "
          f"({len(hertz) / max(len(table), 1):.0%}); where Hertz: p95 (max) ==")
    print(f"  position      {_p95_max(hertz.d_pos_mm)} mm   (goal 0.5 mm)")
    print(f"  Fn            {_p95_max(hertz.d_fn_rel)} rel  (goal 0.05)")
    print(f"  peak pressure {_p95_max(hertz.d_pmax_rel)} rel  (goal 0.10)")
    rest = table[table.method != "hertz"]
    print(f"  (the other {len(rest)} patches, coarse BEM: position {_p95_max(rest.d_pos_mm)} mm,"
          f" peak pressure {_p95_max(rest.d_pmax_rel)})")


def manchester(reference: Path) -> list[pd.DataFrame]:
    bench = reference / "contact-benchmark"
    wt = mbench_track(bench)
    frames = []
    for contact_wheel in ("right", "left"):
        ref = pd.read_csv(bench / f"mbench_a22_{contact_wheel}_ref.csv")
        side = "left" if contact_wheel == "right" else "right"
        shifts = ref["y_ws_mm"].to_numpy()
        # CONTACT's roll is positive when its left wheel rises: minus ours
        locus = wheel_locus(wt, shifts, side, yaw_rad=ref["yaw_rad"].to_numpy(),
                            roll_rad=-ref["roll_rad"].to_numpy())
        frames.append(compare(f"Manchester A-2.2, CONTACT {contact_wheel} wheel", locus,
                              10_000.0, shifts))
    return frames


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("reference", nargs="?", type=Path, default=DEFAULT_REFERENCE)
    parser.add_argument("--quick", action="store_true", help="fewer shifts and wheels")
    args = parser.parse_args()
    shifts = np.arange(-4.0, 4.01, 2.0 if args.quick else 1.0)
    frames = []
    for label, wt in case_sets(args.reference, args.quick):
        locus = wheel_locus(wt, shifts, "left")
        for load in (10_000.0, 60_000.0):
            frames.append(compare(label, locus, load, shifts))
    conformal = pd.concat(frames, ignore_index=True)
    mb = pd.concat(manchester(args.reference), ignore_index=True)
    for name, group in pd.concat([conformal, mb]).groupby(["case_set", "load_kN"], sort=False):
        hertz = group[group.method == "hertz"]
        print(f"{name[0]:44s} {name[1]:3.0f} kN: Hertz {len(hertz):2d}/{len(group):2d}"
              f"  pos max {hertz.d_pos_mm.abs().max() if len(hertz) else 0:.3f} mm"
              f"  pmax max {hertz.d_pmax_rel.abs().max() if len(hertz) else 0:.1%}"
              f"  auto {1e3 * group.t_auto_s.mean():5.1f} ms per case")
    summary(conformal, "conformal treads (normal_contact_accuracy's cases)")
    summary(mb, "Manchester A-2.2 (CONTACT's profile files)")
    summary(pd.concat([conformal, mb], ignore_index=True), "all cases")


if __name__ == "__main__":
    main()
