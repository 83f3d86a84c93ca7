"""The numbers the profile processing gives for the real MiniProf wheels, to compare two trees.

Usage::

    .venv/bin/python benchmarks/processing_miniprof_numbers.py [DIR] > now.json
    .venv/bin/python benchmarks/processing_miniprof_numbers.py [DIR] --against before.json

DIR holds the MiniProf ``*.whl`` files (default ``../shared/reference/miniprof``). For every
wheel it records, to full precision, Sd/Sh/qR and the flange/tread wear areas of
:func:`wearcast.statistics.processing.process_profile` with the free fit and with the datum
placement, of the block path :func:`wearcast.statistics.processing_batch.process_profiles_free`
(all wheels in one block), and Sd/Sh/qR of the cleaned profile as measured (what the import
stores). With ``--against`` it prints the largest absolute difference to an earlier run's
JSON per quantity, instead of the JSON.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame
from wearcast.statistics.processing import ProcessedProfile, process_profile
from wearcast.statistics.processing_batch import flange_parameters_of, process_profiles_free

KEYS = ("sd_mm", "sh_mm", "qr_mm", "flange_mm2", "tread_mm2")


def _numbers(p: ProcessedProfile | ValueError) -> dict[str, float] | str:
    if isinstance(p, ValueError):
        return str(p)
    return {"sd_mm": p.parameters.sd_mm, "sh_mm": p.parameters.sh_mm,
            "qr_mm": p.parameters.qr_mm, "flange_mm2": p.areas.flange_mm2,
            "tread_mm2": p.areas.tread_mm2}


def collect(directory: Path) -> dict[str, dict[str, object]]:
    paths = sorted(directory.glob("*.whl"))
    raw = [to_wheel_frame(parse_miniprof(p.read_bytes(), p.name)) for p in paths]
    block = process_profiles_free(raw)
    out: dict[str, dict[str, object]] = {}
    for path, (y, z), b in zip(paths, raw, block, strict=True):
        row: dict[str, object] = {"block": _numbers(b)}
        for mode in ("free", "datum"):
            try:
                row[mode] = _numbers(process_profile(y, z, alignment=mode))  # type: ignore[arg-type]
            except ValueError as exc:
                row[mode] = str(exc)
        if isinstance(b, ProcessedProfile):
            fp = flange_parameters_of([(b.cleaned.y_mm, b.cleaned.z_mm)])[0]
            row["measured"] = {"sd_mm": fp.sd_mm, "sh_mm": fp.sh_mm, "qr_mm": fp.qr_mm}
        out[path.name] = row
    return out


def compare(now: dict, before: dict) -> None:
    worst: dict[tuple[str, str], float] = {}
    for name, row in before.items():
        for mode, values in row.items():
            other = now[name][mode]
            if isinstance(values, str) or isinstance(other, str):
                if values != other:
                    print(f"{name} {mode}: {values!r} -> {other!r}")
                continue
            for key, v in values.items():
                d = abs(other[key] - v) if v == v else (0.0 if other[key] != other[key] else 1.0)
                worst[(mode, key)] = max(worst.get((mode, key), 0.0), d)
    print(f"{len(before)} wheels; largest |after - before| per path and quantity:")
    for (mode, key), d in sorted(worst.items()):
        print(f"  {mode:<9s} {key:<11s} {d:.3g}")


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", nargs="?", default="../shared/reference/miniprof")
    parser.add_argument("--against", help="JSON of an earlier run to compare with")
    args = parser.parse_args(argv)
    now = collect(Path(args.directory))
    if args.against:
        compare(now, json.loads(Path(args.against).read_text()))
    else:
        print(json.dumps(now, indent=1))


if __name__ == "__main__":
    main(sys.argv[1:])
