"""Robustness of the wheel-rail contact pipeline on raw measured wheels.

Every MiniProf wheel of the reference data (``miniprof/*.whl``; raw points as measured,
through ``to_wheel_frame`` only, no cleaning; the profile curve with ``--smoothing`` mm of
expected scatter, default 0.02, or 0 = interpolating the raw points) on 60E1 rails 1:40
(both wheels of the wheelset the same measured wheel) is swept over lateral shifts
-8 ... 10 mm, yaw -10, 0, +10 mrad and roll solved or prescribed (solved + 2 mrad), and each
pose runs the whole pipeline for the left wheel: contact locus -> patches -> normal contact
("auto") -> creepages -> FASTSIM (``wheel_rail.loaded_wheel_contact``, 10 kN).  With
``--rail FILE.ban`` the rails are that measured MiniProf rail head instead (a worn wheel on a
worn rail; placed by its gauge point as ``contact.track_profiles`` places stored rails).  The script
prints, per wheel, the number of poses, the failures by exception type (a ``NoContactError``
is the expected, typed answer for a wheel that cannot touch its rail, and is counted
apart), and the number of patches seen.

Usage: ``.venv/bin/python benchmarks/contact_robustness.py [--smoothing 0.02] [--quick]
[--rail path/to/rail.ban] [path/to/reference]``
"""

from __future__ import annotations

import argparse
import collections
import itertools
import time
from pathlib import Path

import numpy as np

from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.contact.locus import NoContactError, wheel_locus
from wearcast.physics.contact.track_profiles import wheelset_track
from wearcast.physics.contact.wheel_rail import loaded_wheel_contact
from wearcast.physics.profiles.measured import ProfileCurve, rail_curve
from wearcast.physics.profiles.measured_rail import MeasuredRail

DEFAULT_REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"


def raw_wheels(reference: Path, smoothing_mm: float) -> dict[str, ProfileCurve]:
    from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame

    out = {}
    for path in sorted((reference / "miniprof").glob("*.whl")):
        y, z = to_wheel_frame(parse_miniprof(path.read_bytes(), path.name))
        out[path.stem] = ProfileCurve.from_points(y, z, smoothing_mm=smoothing_mm)
    return out


def measured_rail(path: Path) -> MeasuredRail:
    """The first rail head of a MiniProf rail file, in its rail frame."""
    from wearcast.service.readers.miniprof_rail import read_rail_file

    part = read_rail_file(path.read_bytes(), path.name).parts[0]
    return MeasuredRail(path.name, *part.rail_frame())


def sweep(wheel: ProfileCurve, shifts: np.ndarray, yaws: tuple[float, ...],
          roll_offsets: tuple[float | None, ...], rail: MeasuredRail | None = None
          ) -> tuple[int, collections.Counter, list[str], collections.Counter]:
    """(poses, failures by type, first messages, patch-count histogram)."""
    if rail is None:
        wt = WheelsetTrack(wheel=wheel, rail=rail_curve("60E1"))
    else:
        wt = wheelset_track(wheel, rail, 1.0 / 40.0, 460.0)
    failures: collections.Counter = collections.Counter()
    patches: collections.Counter = collections.Counter()
    messages: list[str] = []
    poses = 0
    for yaw, offset in itertools.product(yaws, roll_offsets):
        for shift in shifts:
            poses += 1
            try:
                roll = None
                if offset is not None:
                    roll = wheel_locus(wt, [shift], "left", yaw_rad=yaw).roll_rad + offset
                locus = wheel_locus(wt, [shift], "left", yaw_rad=yaw, roll_rad=roll)
                result = loaded_wheel_contact(locus, wt.nominal_radius_mm, 10_000.0)
                patches[len(result[0].patches)] += 1
            except NoContactError:
                failures["NoContactError (typed)"] += 1
            except Exception as exc:  # counted and shown, never hidden
                failures[type(exc).__name__] += 1
                if len(messages) < 3:
                    messages.append(f"shift {shift:+.1f} yaw {yaw:+.3f} roll+{offset}: "
                                    f"{type(exc).__name__}: {exc}")
    return poses, failures, messages, patches


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("reference", nargs="?", type=Path, default=DEFAULT_REFERENCE)
    parser.add_argument("--smoothing", type=float, default=0.02)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--rail", type=Path, default=None,
                        help="a MiniProf rail file (.ban) for both rails instead of 60E1")
    args = parser.parse_args()
    rail = None if args.rail is None else measured_rail(args.rail)
    shifts = np.arange(-8.0, 10.01, 3.0 if args.quick else 1.0)
    yaws = (0.0, 0.01) if args.quick else (-0.01, 0.0, 0.01)
    rolls = (None, 0.002)
    total = collections.Counter()
    n_total = 0
    for name, curve in raw_wheels(args.reference, args.smoothing).items():
        start = time.perf_counter()
        poses, failures, messages, patches = sweep(curve, shifts, yaws, rolls, rail)
        n_total += poses
        total.update(failures)
        print(f"{name:28s} {poses:4d} poses, failures {dict(failures) or 0}, patches "
              f"{dict(sorted(patches.items()))}, {time.perf_counter() - start:.0f} s")
        for message in messages:
            print(f"    {message}")
    untyped = sum(v for k, v in total.items() if not k.startswith("NoContactError"))
    print(f"\nall wheels: {n_total} poses, {untyped} untyped exceptions, "
          f"{total['NoContactError (typed)']} typed NoContactError")


if __name__ == "__main__":
    main()
