"""Import throughput: long-CSV files of many 400-point profiles into a fresh SQLite database.

    .venv/bin/python benchmarks/bench_import.py            # 10,000 and 100,000 profiles
    .venv/bin/python benchmarks/bench_import.py --quick    # 1,000 and 10,000 profiles
    .venv/bin/python benchmarks/bench_import.py --sizes 3000 \
        --postgres postgresql+psycopg://postgres@127.0.0.1:5432/test   # SQLite and PostgreSQL

For each size: writes the file under a temporary directory (streamed in chunks; 100,000 x 400
rows is ~3.5 GB), then imports it in a *fresh child process* through the service's import
function (``wearcast.service.importing.import_upload``, not HTTP) into a fresh SQLite
database — and with ``--postgres URL`` also into a throw-away database created on that
server (dropped afterwards) —, and prints profiles/s, points/s and the child's peak RSS
(``resource.getrusage(RUSAGE_SELF).ru_maxrss``), so each size's memory is measured alone.
``WEARCAST_IMPORT_WORKERS`` (default: one per CPU; 0 or 1: in the importing process) sets the
processing pool, as for the service; the header prints it and the machine's load average.

The profiles are the fleet twin's (``wearcast.statistics.generators.fleet_twin``): a pool of
realistic worn, noisy, misaligned profiles is generated once and repeated under new wheel ids.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

POINTS = 400
MILEAGES_PER_WHEEL = 6


def _pool(points: int) -> list[tuple[str, list[str]]]:
    """(metadata after wheel_id/vehicle_id, y,z lines) for a pool of twin measurements."""
    from wearcast.statistics.generators import fleet_twin

    config = fleet_twin.example_fleet_config(seed=1, points_per_profile=points)
    twin = fleet_twin.generate_fleet(config)
    pool = []
    for (_, _), g in twin.profiles.groupby(["wheel_id", "mileage_km"], sort=False):
        r = g.iloc[0]
        meta = (f"{r.bogie_type},{r.axle},{r.side},{r.mileage_km},")
        tail = f",{r.measured_on},{r.route_id},{r.running_mode},{r.instrument_id},{r.load_t}"
        yz = [f"{y:.3f},{z:.3f}" for y, z in zip(g.y_mm, g.z_mm, strict=True)]
        pool.append((meta, [line + tail for line in yz]))
    return pool


def write_csv(path: Path, n_profiles: int, points: int = POINTS) -> int:
    """Write ``n_profiles`` measurements (6 per wheel) to ``path``; returns bytes written."""
    pool = _pool(points)
    header = ("wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm,measured_on,"
              "route_id,running_mode,instrument_id,load_t\n")
    with path.open("w", buffering=1 << 22) as f:
        f.write(header)
        for i in range(n_profiles):
            wheel = i // MILEAGES_PER_WHEEL
            # same wheel position and mileage sequence as a pool wheel, under a new id
            meta, lines = pool[(wheel * MILEAGES_PER_WHEEL) % len(pool)
                               + i % MILEAGES_PER_WHEEL]
            prefix = f"W{wheel:07d},V{wheel // 8:06d},{meta}"
            f.write("\n".join(prefix + line for line in lines))
            f.write("\n")
    return path.stat().st_size


def import_once(csv_path: Path, work_dir: Path, database_url: str | None = None
                ) -> dict[str, float]:
    """Import one file into a fresh database (run in a child process)."""
    from wearcast.service import importing
    from wearcast.service.db import Database
    from wearcast.service.settings import Settings

    settings = Settings(data_dir=work_dir, database_url=database_url or None)
    database = Database(settings)
    database.migrate()
    start = time.perf_counter()
    with database.session_factory() as session, csv_path.open("rb") as stream:
        result = importing.import_upload(session, settings.raw_dir, stream, csv_path.name,
                                         chunk_size=settings.import_chunk_size)
    seconds = time.perf_counter() - start
    database.dispose()
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux
    return {"profiles": result.created, "points": result.points, "seconds": seconds,
            "peak_rss_mb": peak_kib / 1024.0}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="long-CSV import throughput")
    parser.add_argument("--quick", action="store_true", help="1,000 and 10,000 profiles")
    parser.add_argument("--sizes", type=int, nargs="*", help="explicit profile counts")
    parser.add_argument("--postgres", metavar="URL", default=None,
                        help="also import into a throw-away database on this PostgreSQL "
                             "server (SQLAlchemy URL of a database the user may CREATE in)")
    parser.add_argument("--child", nargs=3, metavar=("CSV", "DIR", "URL"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        print(json.dumps(import_once(Path(args.child[0]), Path(args.child[1]),
                                     args.child[2])))
        return
    sizes = args.sizes or ([1_000, 10_000] if args.quick else [10_000, 100_000])
    workers = os.environ.get("WEARCAST_IMPORT_WORKERS", "").strip() or f"{os.cpu_count()}"
    print(f"import workers: {workers}; {os.cpu_count()} CPUs; load average (1/5/15 min) "
          f"{'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"{'database':<10} {'profiles':>9} {'file MB':>9} {'write s':>8} {'import s':>9} "
          f"{'profiles/s':>11} {'points/s':>11} {'peak RSS MB':>12}")
    for n in sizes:
        with tempfile.TemporaryDirectory(prefix="wearcast-bench-") as tmp:
            csv_path = Path(tmp) / f"profiles_{n}.csv"
            t0 = time.perf_counter()
            size = write_csv(csv_path, n)
            write_s = time.perf_counter() - t0
            backends = [("sqlite", None)] + ([("postgresql", args.postgres)]
                                             if args.postgres else [])
            for name, server_url in backends:
                with _database(server_url) as url:
                    child = subprocess.run(
                        [sys.executable, __file__, "--child", str(csv_path),
                         str(Path(tmp) / f"data-{name}"), url],
                        capture_output=True, text=True, check=False)
                if child.returncode != 0:
                    sys.exit(f"import of {n} profiles into {name} failed:\n"
                             f"{child.stderr[-3000:]}")
                r = json.loads(child.stdout.strip().splitlines()[-1])
                assert r["profiles"] == n, r
                print(f"{name:<10} {n:>9,} {size / 1e6:>9.1f} {write_s:>8.1f} "
                      f"{r['seconds']:>9.1f} {n / r['seconds']:>11,.0f} "
                      f"{r['points'] / r['seconds']:>11,.0f} {r['peak_rss_mb']:>12.0f}",
                      flush=True)


@contextmanager
def _database(server_url: str | None) -> Iterator[str]:
    """``""`` (the default SQLite file) or a fresh database on ``server_url``, dropped
    afterwards."""
    if server_url is None:
        yield ""
        return
    from sqlalchemy import create_engine

    from wearcast.service.db import scratch_database

    with scratch_database(create_engine(server_url, isolation_level="AUTOCOMMIT"),
                          "wearcast_bench") as database_url:
        yield database_url


if __name__ == "__main__":
    main()
