"""Fast normal-contact methods against the boundary-element solution, on conformal treads.

Cases: S1002 on 60E1 inclined 1:40 and 1:20, and the measured MiniProf wheels of the
reference data (``miniprof/*.whl``, raw points, smoothing 0.02 mm) on 60E1 1:40; wheelset
shifts -4 ... +4 mm (tread contact of the left wheel; two-point and flange cases beyond are
left out unless the sweep reaches them), yaw 0, roll solved; wheel loads 10 kN and 60 kN.
For each case the left wheel's patches carry the load with the boundary-element method
(``normal_contact`` method "bem", the reference) and with the production method ("auto":
Hertz where the patch is elliptic by the stated criterion, ``normal_contact.is_elliptic``,
else the coarse BEM), and the script prints, per case set, the p95 and max over cases of

- the contact position: pressure centre on the wheel, |y_wheel(method) - y_wheel(BEM)| [mm],
- the normal force of the dominant patch relative to BEM's (at the same wheel load),
- the peak pressure relative to BEM's,

plus the share of patches the production method gave to Hertz, and the time per case
(``hertz_criterion_accuracy.py``: the same errors over the Hertz patches alone, with the
Manchester cases).

Acceptance (issue 11): position 0.5 mm, F_n 5 %, peak pressure 10 % (p95 over cases).

Usage: ``.venv/bin/python benchmarks/normal_contact_accuracy.py [--method auto|kp|hertz|bem-coarse]
[--quick] [path/to/reference]``
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from wearcast.physics.contact.geometry import WheelsetTrack, s1002_60e1
from wearcast.physics.contact.locus import wheel_locus
from wearcast.physics.contact.normal_contact import wheel_normal_contact
from wearcast.physics.profiles.measured import ProfileCurve, rail_curve

DEFAULT_REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"


def measured_wheels(reference: Path) -> dict[str, ProfileCurve]:
    """The MiniProf wheels of the reference data as raw-point curves (smoothing 0.02 mm)."""
    from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame

    out = {}
    for path in sorted((reference / "miniprof").glob("*.whl")):
        y, z = to_wheel_frame(parse_miniprof(path.read_bytes(), path.name))
        out[path.stem] = ProfileCurve.from_points(y, z, smoothing_mm=0.02)
    return out


def case_sets(reference: Path, quick: bool) -> list[tuple[str, WheelsetTrack]]:
    sets = [("S1002 / 60E1 1:40", s1002_60e1(1.0 / 40.0)),
            ("S1002 / 60E1 1:20", s1002_60e1(1.0 / 20.0))]
    wheels = measured_wheels(reference) if (reference / "miniprof").is_dir() else {}
    for name, curve in list(wheels.items())[: 3 if quick else None]:
        sets.append((f"{name} / 60E1 1:40", WheelsetTrack(wheel=curve, rail=rail_curve("60E1"))))
    return sets


def compare(wt: WheelsetTrack, shifts: np.ndarray, load_n: float, method: str
            ) -> pd.DataFrame:
    """Per shift: production method vs BEM for the left wheel's dominant patch."""
    locus = wheel_locus(wt, shifts, "left")
    t0 = time.perf_counter()
    fast = wheel_normal_contact(locus, load_n, method=method)
    t_fast = (time.perf_counter() - t0) / shifts.size
    t0 = time.perf_counter()
    ref = wheel_normal_contact(locus, load_n, method="bem")
    t_bem = (time.perf_counter() - t0) / shifts.size
    rows = []
    for i, (f, r) in enumerate(zip(fast, ref, strict=True)):
        pr = max(r.patches, key=lambda p: p.normal_force_n)
        # the production patch nearest the BEM's dominant one
        pf = min(f.patches, key=lambda p: abs(p.centre_y_wheel_mm - pr.centre_y_wheel_mm))
        rows.append({"shift_mm": shifts[i], "patches": len(f.patches),
                     "patches_bem": len(r.patches),
                     "d_pos_mm": pf.centre_y_wheel_mm - pr.centre_y_wheel_mm,
                     "d_fn_rel": pf.normal_force_n / pr.normal_force_n - 1.0,
                     "d_pmax_rel": pf.peak_pressure_mpa / pr.peak_pressure_mpa - 1.0,
                     "hertz": pf.method == "hertz", "t_fast_s": t_fast, "t_bem_s": t_bem})
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("reference", nargs="?", type=Path, default=DEFAULT_REFERENCE)
    parser.add_argument("--method", default="auto", choices=("auto", "kp", "hertz", "bem-coarse"))
    parser.add_argument("--quick", action="store_true", help="fewer shifts and wheels")
    args = parser.parse_args()
    shifts = np.arange(-4.0, 4.01, 2.0 if args.quick else 1.0)
    frames = []
    for label, wt in case_sets(args.reference, args.quick):
        for load in (10_000.0, 60_000.0):
            try:
                frame = compare(wt, shifts, load, args.method)
            except Exception as exc:  # report, do not hide: a failing case set is a result
                print(f"{label:40s} {load / 1e3:4.0f} kN: FAILED {type(exc).__name__}: {exc}")
                continue
            frame.insert(0, "load_kN", load / 1e3)
            frame.insert(0, "case_set", label)
            frames.append(frame)
            print(f"{label:40s} {load / 1e3:4.0f} kN: pos max {frame.d_pos_mm.abs().max():.3f}"
                  f" mm, Fn max {frame.d_fn_rel.abs().max():.1%}, pmax max "
                  f"{frame.d_pmax_rel.abs().max():.1%}, hertz {frame.hertz.mean():.0%}, "
                  f"{frame.t_fast_s.mean() * 1e3:.0f} ms vs BEM "
                  f"{frame.t_bem_s.mean() * 1e3:.0f} ms per case")
    table = pd.concat(frames, ignore_index=True)
    print(f"\n== {args.method} vs BEM over {len(table)} cases: p95 (max) ==")
    for column, label, unit in (("d_pos_mm", "position", "mm"), ("d_fn_rel", "Fn", "rel"),
                                ("d_pmax_rel", "peak pressure", "rel")):
        values = table[column].abs().to_numpy()
        print(f"  {label:14s} {np.quantile(values, 0.95):.4f} ({values.max():.4f}) {unit}")
    same = (table.patches == table.patches_bem).mean()
    print(f"  same number of patches as BEM in {same:.0%} of the cases; Hertz used in "
          f"{table.hertz.mean():.0%}")


if __name__ == "__main__":
    main()
