"""Profile processing of this tree against another checkout, timed in one process, interleaved.

Usage::

    git worktree add --detach ../base main
    .venv/bin/python benchmarks/bench_processing_ab.py ../base [n_pairs]

On a shared, loaded machine two benchmark processes run minutes apart see different loads;
here both versions run in the same process, each timing of the baseline followed at once by
the same timing of this tree (``n_pairs`` times, default 9), and the median of the ratios is
printed. The baseline's ``physics`` and ``statistics`` packages are copied to a temporary
folder as the package ``wearcast_base`` (imports renamed) so both can be imported together.
Timed, on the profiles of ``bench_processing.synthetic_profiles`` (512 of 400 points, process
CPU time): ``process_profiles_free`` in blocks of 128, ``process_profile``,
``clean_profile`` and ``align_to_reference`` per profile.
"""

from __future__ import annotations

import argparse
import importlib
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_processing import synthetic_profiles  # noqa: E402


def _baseline_package(checkout: Path, into: Path) -> None:
    root = into / "wearcast_base"
    root.mkdir()
    for name in ("physics", "statistics"):
        shutil.copytree(checkout / name, root / name)
    for path in root.rglob("*.py"):
        text = path.read_text()
        path.write_text(re.sub(r"\bwearcast\.", "wearcast_base.", text))


def _cases(prefix: str, profiles: list, blocks: list) -> dict[str, Any]:
    batch = importlib.import_module(f"{prefix}.statistics.processing_batch")
    processing = importlib.import_module(f"{prefix}.statistics.processing")
    cleaning = importlib.import_module(f"{prefix}.statistics.cleaning")
    alignment = importlib.import_module(f"{prefix}.statistics.alignment")
    cleaned = [cleaning.clean_profile(y, z) for y, z in profiles]
    return {
        "process_profiles_free (blocks of 128)": (batch.process_profiles_free, blocks),
        "process_profile": (lambda p: processing.process_profile(*p), profiles),
        "clean_profile": (lambda p: cleaning.clean_profile(*p), profiles),
        "align_to_reference": (lambda c: alignment.align_to_reference(c.y_mm, c.z_mm),
                               cleaned),
    }


def _seconds(func: Any, items: list) -> float:
    start = time.process_time()
    for item in items:
        func(item)
    return time.process_time() - start


def interleaved(func_base: Any, func_this: Any, items: list, pairs: int, count: int,
                unit: str) -> str:
    """Time ``func_base`` and ``func_this`` over ``items`` ``pairs`` times, each baseline
    timing followed at once by this tree's; the median and range of the ratios and the
    baseline's median time per one of ``count`` ``unit`` [us], as a line of text."""
    ratios, base_us = [], []
    for _ in range(pairs):
        a = _seconds(func_base, items)
        b = _seconds(func_this, items)
        ratios.append(b / a)
        base_us.append(a / count * 1e6)
    ratios.sort()
    base_us.sort()
    return (f"this/baseline median {ratios[len(ratios) // 2]:.3f} (range {ratios[0]:.3f}-"
            f"{ratios[-1]:.3f}); baseline {base_us[len(base_us) // 2]:.1f} us/{unit}")


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("baseline", help="checkout of the baseline (has physics/, statistics/)")
    parser.add_argument("pairs", nargs="?", type=int, default=9)
    args = parser.parse_args(argv)
    profiles = synthetic_profiles(512)
    blocks = [profiles[i:i + 128] for i in range(0, len(profiles), 128)]
    with tempfile.TemporaryDirectory() as tmp:
        _baseline_package(Path(args.baseline), Path(tmp))
        sys.path.insert(0, tmp)
        base = _cases("wearcast_base", profiles, blocks)
        this = _cases("wearcast", profiles, blocks)
        print(f"{args.pairs} interleaved pairs, 512 profiles of 400 points, process CPU time")
        for name, (func_base, items) in base.items():
            print(f"  {name:<38s} "
                  + interleaved(func_base, this[name][0], items, args.pairs, 512, "profile"))


if __name__ == "__main__":
    main(sys.argv[1:])
