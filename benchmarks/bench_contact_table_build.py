"""Benchmark: CPU time of one curving contact table build, masked against Gaussian gap smoothing.

Run: ``.venv/bin/python benchmarks/bench_contact_table_build.py [--repeats 7] [--profile]``

``curving_table.build_contact_table`` for S1002 on 60E1 at 1:40 and 1:20, and for a worn S1002
(synthetic: the tread hollowed by 0.8 mm, the flank thinned by 0.5 mm) at 1:40, with the
default ``masked`` gap smoothing and with the ``gaussian`` one (``gap_smoothing``), each the
median of ``--repeats`` builds' process CPU time [s] after one warm-up build (the numba
kernels compiled or loaded from their cache), and the masked / Gaussian ratio of the medians
measured in the same run (the machine may be shared: compare ratios). The table builds are
part of every wear step's contact update (issue 11/12). ``--profile`` prints the top of a
cProfile of the masked 1:40 S1002 build. Run with another checkout's interpreter
(``cd ../base && .venv/bin/python /path/to/this/benchmarks/bench_contact_table_build.py``) it
measures that checkout the same way.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

import argparse  # noqa: E402
import cProfile  # noqa: E402
import pstats  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from wearcast.physics.curving_table import build_contact_table  # noqa: E402
from wearcast.physics.profiles.s1002 import s1002_height_mm  # noqa: E402


def worn_s1002_mm(y_mm: NDArray[np.float64]) -> NDArray[np.float64]:
    """A synthetic worn S1002 height z(y) [mm]: a 0.8 mm tread hollow (12 mm wide, at the tape
    circle) and 0.5 mm off the flank (6 mm wide, 35 mm flange-wards)."""
    y = np.asarray(y_mm, dtype=float)
    return (s1002_height_mm(y) - 0.8 * np.exp(-(y / 12.0) ** 2)
            - 0.5 * np.exp(-((y + 35.0) / 6.0) ** 2))


CASES: tuple[tuple[str, Callable | None, float], ...] = (
    ("S1002 60E1 1:40", None, 1.0 / 40.0),
    ("S1002 60E1 1:20", None, 1.0 / 20.0),
    ("worn S1002 60E1 1:40", worn_s1002_mm, 1.0 / 40.0),
)


def cpu_seconds(wheel: Callable | None, inclination: float, method: str) -> float:
    t0 = time.process_time()
    build_contact_table(wheel, "60E1", inclination, gap_smoothing=method)
    return time.process_time() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    print(f"build_contact_table CPU time [s], median of {args.repeats} (one core)")
    for name, wheel, inclination in CASES:
        for method in ("masked", "gaussian"):
            cpu_seconds(wheel, inclination, method)  # warm-up
        # interleaved, so that a change of the machine's load hits both methods alike
        times: dict[str, list[float]] = {"masked": [], "gaussian": []}
        for _ in range(args.repeats):
            for method in times:
                times[method].append(cpu_seconds(wheel, inclination, method))
        median = {m: float(np.median(t)) for m, t in times.items()}
        print(f"  {name:<22s} masked {median['masked']:.3f}  gaussian "
              f"{median['gaussian']:.3f}  ratio {median['masked'] / median['gaussian']:.2f}")
    if args.profile:
        profile = cProfile.Profile()
        profile.enable()
        for _ in range(3):
            build_contact_table(None, "60E1", 1.0 / 40.0, gap_smoothing="masked")
        profile.disable()
        pstats.Stats(profile).sort_stats("cumulative").print_stats(25)


if __name__ == "__main__":
    main()
