"""How long small writes wait behind a large import (issue 14 §5), against `wearcast serve`.

    .venv/bin/python benchmarks/bench_write_wait.py                     # 7,400 profiles
    .venv/bin/python benchmarks/bench_write_wait.py --profiles 3000 \
        --baseline-python /work/main/.venv/bin/python                  # base, then this

Starts the service as an operator does (``wearcast serve`` next to the interpreter, a fresh
SQLite data directory, the real uvicorn server with its thread pool and the import's
processing workers), posts one large long-CSV import over HTTP (``--profiles`` profiles of
400 points, the fleet twin's profiles as in ``bench_import.py``) and, while it runs, one small
write every ``--interval`` seconds, alternately a route (``POST /v1/routes``) and a small
import of one profile (``POST /v1/measurements/import``), each waiting for the previous one.
Prints the small writes' latency before the import (idle) and during it (median, p95, max;
their excess over the idle median is the time they waited for the database), any that
failed, and the import's duration and rate. ``--baseline-python PY`` first runs the same
with another checkout's interpreter (e.g. ``/work/main/.venv/bin/python``): before and after
under the same load, one after the other. The machine and its load average are printed.
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_import  # noqa: E402  (the long-CSV writer and the machine line)

API_KEY = "wc_bench-write-wait-admin-key"
ROUTE_CLASSES = [{"radius_m": None, "speed_kmh": 80, "share": 0.7},
                 {"radius_m": 400, "direction": "left", "cant_mm": 100, "speed_kmh": 70,
                  "share": 0.3}]
HEADER = ("wheel_id,vehicle_id,bogie_type,axle,side,mileage_km,y_mm,z_mm,measured_on,"
          "route_id,running_mode,instrument_id,load_t\n")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _small_csv(i: int, pool: list[tuple[str, list[str]]]) -> bytes:
    """One profile under a new wheel id (a new vehicle too): a small import."""
    meta, lines = pool[i % len(pool)]
    prefix = f"S{i:06d},SV{i:06d},{meta}"
    return (HEADER + "\n".join(prefix + line for line in lines) + "\n").encode()


class Server:
    """``wearcast serve`` of an interpreter's environment on a fresh SQLite data directory."""

    def __init__(self, python: str, data_dir: Path) -> None:
        self.port = _free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        env = dict(os.environ, WEARCAST_DATA_DIR=str(data_dir), WEARCAST_API_KEY=API_KEY,
                   WEARCAST_RATE_LIMIT_PER_SECOND="0",
                   WEARCAST_MAX_UPLOAD_BYTES=str(1 << 30))
        env.pop("WEARCAST_DATABASE_URL", None)
        wearcast = Path(python).parent / "wearcast"
        self.log = (data_dir.parent / f"{data_dir.name}.log").open("w")
        self.process = subprocess.Popen(
            [str(wearcast), "serve", "--host", "127.0.0.1", "--port", str(self.port)],
            env=env, stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)

    def wait_ready(self, client: Any, timeout_s: float = 120.0) -> None:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                sys.exit(f"server exited with {self.process.returncode}; see {self.log.name}")
            try:
                if client.get(f"{self.url}/v1/health").status_code == 200:
                    return
            except Exception:  # not listening yet
                pass
            time.sleep(0.2)
        sys.exit(f"server not ready after {timeout_s:.0f} s; see {self.log.name}")

    def stop(self) -> None:
        os.killpg(self.process.pid, signal.SIGTERM)
        try:
            self.process.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
        self.log.close()


def run_once(python: str, csv_path: Path, work: Path, interval_s: float,
             pool: list[tuple[str, list[str]]], label: str) -> dict[str, Any]:
    """One server, one large import, small writes meanwhile; the measured figures."""
    import httpx

    data_dir = work / f"data-{label}"
    server = Server(python, data_dir)
    headers = {"Authorization": f"Bearer {API_KEY}"}
    counter = iter(range(10**9))
    try:
        with httpx.Client(headers=headers, timeout=None) as client:
            server.wait_ready(client)

            def small_write() -> tuple[float, int, str]:
                i = next(counter)
                start = time.perf_counter()
                if i % 2 == 0:
                    answer = client.post(f"{server.url}/v1/routes",
                                         json={"name": f"bench-{label}-{i}",
                                               "classes": ROUTE_CLASSES})
                    kind = "route"
                else:
                    answer = client.post(f"{server.url}/v1/measurements/import", files={
                        "file": (f"small-{i}.csv", _small_csv(i, pool), "text/csv")})
                    kind = "import"
                return time.perf_counter() - start, answer.status_code, kind

            idle = [small_write() for _ in range(10)]
            big: dict[str, Any] = {}

            def import_big() -> None:
                start = time.perf_counter()
                with httpx.Client(headers=headers, timeout=None) as own, \
                        csv_path.open("rb") as stream:
                    answer = own.post(f"{server.url}/v1/measurements/import",
                                      files={"file": (csv_path.name, stream, "text/csv")})
                big["seconds"] = time.perf_counter() - start
                big["status"] = answer.status_code
                big["body"] = answer.json() if answer.status_code == 200 else answer.text

            thread = threading.Thread(target=import_big)
            thread.start()
            during = []
            while thread.is_alive():
                issued = time.perf_counter()
                during.append(small_write())
                time.sleep(max(0.0, interval_s - (time.perf_counter() - issued)))
            thread.join()
    finally:
        server.stop()
    if big.get("status") != 200:
        sys.exit(f"{label}: the large import failed: {big.get('status')} "
                 f"{str(big.get('body'))[:2000]}")
    return {"idle": idle, "during": during, "import_s": big["seconds"],
            "created": big["body"]["created"]}


def _quantile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(q * (len(ordered) - 1))))]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="small-write latency during a large import")
    parser.add_argument("--profiles", type=int, default=7400, help="profiles in the import")
    parser.add_argument("--interval", type=float, default=0.2,
                        help="seconds between small writes")
    parser.add_argument("--baseline-python", default=None, metavar="PY",
                        help="first run the same with this interpreter (another checkout)")
    args = parser.parse_args(argv)
    print(f"machine: {bench_import._machine()}; load average (1/5/15 min) "
          f"{'/'.join(f'{v:.2f}' for v in os.getloadavg())}")
    pool = bench_import._pool(bench_import.POINTS)
    pythons = ([("base", args.baseline_python)] if args.baseline_python else []) + [
        ("this", sys.executable)]
    print("small writes: a route or a one-profile import, every "
          f"{args.interval:g} s while a {args.profiles:,}-profile import runs; latency [s]")
    print(f"{'code':<5} {'import s':>9} {'profiles/s':>11} {'idle p50':>9} {'writes':>7} "
          f"{'p50':>7} {'p95':>7} {'max':>7} {'max route':>10} {'max import':>11} "
          f"{'failed':>7}")
    with tempfile.TemporaryDirectory(prefix="wearcast-bench-wait-") as tmp:
        work = Path(tmp)
        csv_path = work / f"profiles_{args.profiles}.csv"
        bench_import.write_csv(csv_path, args.profiles)
        for label, python in pythons:
            r = run_once(python, csv_path, work, args.interval, pool, label)
            assert r["created"] == args.profiles, r["created"]
            idle = [t for t, status, _ in r["idle"] if status < 300]
            ok = [(t, kind) for t, status, kind in r["during"] if status < 300]
            failed = [(status, kind) for _, status, kind in r["during"] if status >= 300]
            times = [t for t, _ in ok]
            by_kind = {k: max((t for t, kind in ok if kind == k), default=float("nan"))
                       for k in ("route", "import")}
            print(f"{label:<5} {r['import_s']:>9.1f} {args.profiles / r['import_s']:>11,.0f} "
                  f"{float(np.median(idle)):>9.3f} {len(r['during']):>7} "
                  f"{float(np.median(times)):>7.3f} {_quantile(times, 0.95):>7.3f} "
                  f"{max(times):>7.3f} {by_kind['route']:>10.3f} {by_kind['import']:>11.3f} "
                  f"{len(failed):>7}", flush=True)
            if failed:
                print(f"      failed: {failed[:10]}")
    print(f"load average after (1/5/15 min) {'/'.join(f'{v:.2f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
