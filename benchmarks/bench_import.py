"""Import throughput: long-CSV files of many 400-point profiles into a fresh SQLite database.

    .venv/bin/python benchmarks/bench_import.py            # 10,000 and 100,000 profiles
    .venv/bin/python benchmarks/bench_import.py --quick    # 1,000 and 10,000 profiles
    .venv/bin/python benchmarks/bench_import.py --sizes 3000 \
        --postgres postgresql+psycopg://postgres@127.0.0.1:5432/test   # SQLite and PostgreSQL

For each size: writes the file under a temporary directory (streamed in chunks; 100,000 x 400
rows is ~3.5 GB), then imports it in a *fresh child process* through the service's import
function (``wearcast.service.importing.import_upload``, not HTTP) into a fresh SQLite
database — and with ``--postgres URL`` also into a throw-away database created on that
server (dropped afterwards) —, and prints profiles/s, points/s, the child's peak RSS
(``resource.getrusage(RUSAGE_SELF).ru_maxrss``, so each size's memory is measured alone) and
its processing workers' largest, and the CPU per profile of the child and of its workers.
Their sum bounds the rate: cores / CPU per profile is what the import would reach with the
machine to itself (on a shared machine the measured rate is lower by the others' share).
``--baseline-python PY`` imports each file also with another interpreter (another
checkout's venv, e.g. ``/work/main/.venv/bin/python``) right before this one's: before and
after under the same load.
``--warm`` imports a 1,000-profile file first in the same child, as a running service has
(the pool's workers started, numpy/pandas loaded): the workers' CPU is then that of the
measured import alone, without their start-up.
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
#: Profiles of the file a ``--warm`` child imports first (several read blocks and pool chunks)
WARM_PROFILES = 1_000


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


def import_once(csv_path: Path, work_dir: Path, database_url: str | None = None,
                warm_csv: Path | None = None) -> dict[str, float]:
    """Import one file into a fresh database (run in a child process).

    Besides the time: this process's peak RSS and CPU seconds, the largest peak RSS of its
    processing pool's workers, and their summed CPU seconds (the pool is shut down and waited
    for first, so that ``RUSAGE_CHILDREN`` holds them). With ``warm_csv`` that file is
    imported first (into another SQLite database), as by a service that has imported before:
    the pool is running and warm, and the workers' CPU is what they spent on this import
    (read from /proc)."""
    from wearcast.service import import_pool, importing
    from wearcast.service.db import Database
    from wearcast.service.settings import Settings

    if warm_csv is not None:
        warm = Settings(data_dir=work_dir / "warm-up", database_url=None)
        warm_db = Database(warm)
        warm_db.migrate()
        with warm_db.session_factory() as session, warm_csv.open("rb") as stream:
            importing.import_upload(session, warm.raw_dir, stream, warm_csv.name)
        warm_db.dispose()
    settings = Settings(data_dir=work_dir, database_url=database_url or None)
    database = Database(settings)
    database.migrate()
    warm_pids = list(getattr(getattr(import_pool, "_POOL", None), "_processes", None) or {})
    warm_cpu0 = sum(_proc_cpu(pid) for pid in warm_pids)
    own_cpu0 = _cpu(resource.RUSAGE_SELF)
    start = time.perf_counter()
    with database.session_factory() as session, csv_path.open("rb") as stream:
        result = importing.import_upload(session, settings.raw_dir, stream, csv_path.name,
                                         chunk_size=settings.import_chunk_size)
    seconds = time.perf_counter() - start
    own_cpu = _cpu(resource.RUSAGE_SELF) - own_cpu0
    database.dispose()
    pool = getattr(import_pool, "_POOL", None)
    worker_pids = list(getattr(pool, "_processes", None) or {})
    warm_cpu = (sum(_proc_cpu(pid) for pid in worker_pids) - warm_cpu0
                if warm_csv is not None and worker_pids == warm_pids else None)
    worker_peak_kib = max((_peak_rss_kib(pid) for pid in worker_pids), default=0)
    try:
        import_pool.discard_pool(wait=True)
    except TypeError:  # a --baseline-python checkout whose discard_pool cannot wait
        pool = getattr(import_pool, "_POOL", None)
        if pool is not None:
            pool.shutdown(wait=True)
    own = resource.getrusage(resource.RUSAGE_SELF)
    return {"profiles": result.created, "points": result.points, "seconds": seconds,
            "peak_rss_mb": own.ru_maxrss / 1024.0,  # KiB on Linux
            "worker_peak_rss_mb": worker_peak_kib / 1024.0,
            "own_cpu_s": own_cpu, "worker_cpu_s": (
                warm_cpu if warm_cpu is not None else _cpu(resource.RUSAGE_CHILDREN))}


def _proc_cpu(pid: int) -> float:
    """User + system CPU seconds of a live process (/proc/<pid>/stat; 0 if unknown)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return 0.0


def _peak_rss_kib(pid: int) -> int:
    """Peak RSS [KiB] of a live process (``VmHWM`` of /proc/<pid>/status; 0 if unknown).

    Not ``RUSAGE_CHILDREN``: a spawned worker is forked first, and Linux carries the parent's
    peak RSS at the fork into the child's ``ru_maxrss`` across its exec."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def _cpu(who: int) -> float:
    """User + system CPU seconds of this process or of its waited-for children."""
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="long-CSV import throughput")
    parser.add_argument("--quick", action="store_true", help="1,000 and 10,000 profiles")
    parser.add_argument("--sizes", type=int, nargs="*", help="explicit profile counts")
    parser.add_argument("--postgres", metavar="URL", default=None,
                        help="also import into a throw-away database on this PostgreSQL "
                             "server (SQLAlchemy URL of a database the user may CREATE in)")
    parser.add_argument("--baseline-python", default=None, metavar="PY",
                        help="also import each file with this interpreter (another "
                             "checkout's venv), right before this one's")
    parser.add_argument("--warm", action="store_true",
                        help="import a 1,000-profile file first in the same process, as a "
                             "service that has imported before (pool running and warm); the "
                             "workers' CPU is then that of the measured import alone")
    parser.add_argument("--child", nargs=3, metavar=("CSV", "DIR", "URL"),
                        help=argparse.SUPPRESS)
    parser.add_argument("--warm-csv", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        print(json.dumps(import_once(Path(args.child[0]), Path(args.child[1]),
                                     args.child[2],
                                     Path(args.warm_csv) if args.warm_csv else None)))
        return
    sizes = args.sizes or ([1_000, 10_000] if args.quick else [10_000, 100_000])
    workers = os.environ.get("WEARCAST_IMPORT_WORKERS", "").strip() or f"{os.cpu_count()}"
    cores = os.cpu_count() or 1
    print(f"machine: {_machine()}; import workers: {workers}; load average (1/5/15 min) "
          f"{'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    print("peak RSS: the importing process / the largest processing worker; CPU ms/profile: "
          "the importing process + the workers (their start-up included); bound: "
          f"{cores} cores / that CPU, the rate if the import had the machine to itself")
    print(f"{'code':<5} {'database':<10} {'profiles':>9} {'file MB':>8} {'import s':>9} "
          f"{'profiles/s':>11} {'points/s':>11} {'RSS MB':>7} {'wrk MB':>7} "
          f"{'CPU ms':>7} {'wrk ms':>7} {'bound/s':>8}")
    pythons = ([("base", args.baseline_python)] if args.baseline_python else []) + [
        ("this", sys.executable)]
    for n in sizes:
        with tempfile.TemporaryDirectory(prefix="wearcast-bench-") as tmp:
            csv_path = Path(tmp) / f"profiles_{n}.csv"
            size = write_csv(csv_path, n)
            warm_args = []
            if args.warm:
                warm_path = Path(tmp) / "warm_up.csv"
                write_csv(warm_path, WARM_PROFILES)
                warm_args = ["--warm-csv", str(warm_path)]
            backends = [("sqlite", None)] + ([("postgresql", args.postgres)]
                                             if args.postgres else [])
            for name, server_url in backends:
                for label, python in pythons:
                    with _database(server_url) as url:
                        child = subprocess.run(
                            [python, __file__, "--child", str(csv_path),
                             str(Path(tmp) / f"data-{name}-{label}"), url, *warm_args],
                            capture_output=True, text=True, check=False)
                    if child.returncode != 0:
                        sys.exit(f"import of {n} profiles into {name} ({label}) failed:\n"
                                 f"{child.stderr[-3000:]}")
                    r = json.loads(child.stdout.strip().splitlines()[-1])
                    assert r["profiles"] == n, r
                    own_ms = r["own_cpu_s"] / n * 1e3
                    worker_ms = r["worker_cpu_s"] / n * 1e3
                    print(f"{label:<5} {name:<10} {n:>9,} {size / 1e6:>8.1f} "
                          f"{r['seconds']:>9.1f} {n / r['seconds']:>11,.0f} "
                          f"{r['points'] / r['seconds']:>11,.0f} {r['peak_rss_mb']:>7.0f} "
                          f"{r['worker_peak_rss_mb']:>7.0f} {own_ms:>7.2f} {worker_ms:>7.2f} "
                          f"{cores / (own_ms + worker_ms) * 1e3:>8,.0f}", flush=True)


def _machine() -> str:
    """CPU model and logical cores (Linux /proc/cpuinfo)."""
    try:
        model = next(line.split(":", 1)[1].strip() for line in
                     Path("/proc/cpuinfo").read_text().splitlines()
                     if line.startswith("model name"))
    except (OSError, StopIteration):
        model = "unknown CPU"
    return f"{model}, {os.cpu_count()} logical cores"


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
