"""API latency under load: predict and reprofiling requests from concurrent clients.

    .venv/bin/python benchmarks/bench_api_latency.py            # 2,000 requests per endpoint
    .venv/bin/python benchmarks/bench_api_latency.py --quick    # 200 requests per endpoint

Starts ``uvicorn`` serving ``wearcast.service.app:create_app`` on 127.0.0.1 (a free port, a
fresh SQLite database in a temporary directory) in a subprocess, loads the bundled example
fleet over HTTP, calibrates a model on unit A's motor bogies, then fires the requests from
``--clients`` concurrent ``httpx.AsyncClient`` workers (default 32) and prints p50/p99
latency and throughput per endpoint. Stops the server at the end.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

ROUTES = ("aosta", "metro", "tangent")
BOGIES = ("motor", "trailer")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start_server(data_dir: Path, port: int) -> subprocess.Popen[bytes]:
    env = dict(os.environ, WEARCAST_DATA_DIR=str(data_dir))
    env.pop("WEARCAST_DATABASE_URL", None)
    return subprocess.Popen(
        [sys.executable, "-m", "uvicorn", "wearcast.service.app:create_app", "--factory",
         "--host", "127.0.0.1", "--port", str(port), "--log-level", "warning"],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def wait_healthy(base: str, server: subprocess.Popen[bytes], timeout_s: float = 60.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if server.poll() is not None:
            raise RuntimeError(f"server exited: {server.stderr.read().decode()[-2000:]}")
        try:
            if httpx.get(f"{base}/v1/health", timeout=2.0).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    raise RuntimeError("server did not become healthy in time")


def prepare(base: str) -> int:
    """Load the example and calibrate; returns the model id."""
    from wearcast.service.demo import load_example_fleet

    with httpx.Client(base_url=base, timeout=300.0) as client:
        ids = load_example_fleet(client)
        response = client.post("/v1/models", json={
            "name": "bench", "measure": "tau_max", "running_mode": "mixed",
            "wear_table_id": ids.wear_table_id,
            "calibration": {"route_id": "aosta",
                            "filter": {"route_id": "aosta", "bogie_type": "motor"}}})
        response.raise_for_status()
        return int(response.json()["id"])


def bodies(endpoint: str, n: int) -> list[dict[str, object]]:
    rng = np.random.default_rng(0)
    out = []
    for _ in range(n):
        body: dict[str, object] = {
            "route_id": str(rng.choice(ROUTES)), "bogie_type": str(rng.choice(BOGIES)),
            "axle": int(rng.integers(1, 3)), "side": str(rng.choice(["left", "right"]))}
        if endpoint == "predict":
            body["mileage_km"] = [50_000.0, 100_000.0, 200_000.0]
        out.append(body)
    return out


async def fire(base: str, path: str, payloads: list[dict[str, object]],
               clients: int) -> tuple[np.ndarray, float, int]:
    """Latencies [s] of all requests, wall time [s] and the number of non-200 answers."""
    queue: asyncio.Queue[dict[str, object]] = asyncio.Queue()
    for p in payloads:
        queue.put_nowait(p)
    latencies: list[float] = []
    failures = 0
    limits = httpx.Limits(max_connections=clients, max_keepalive_connections=clients)

    async def worker(client: httpx.AsyncClient) -> None:
        nonlocal failures
        while True:
            try:
                payload = queue.get_nowait()
            except asyncio.QueueEmpty:
                return
            t0 = time.perf_counter()
            response = await client.post(path, json=payload)
            latencies.append(time.perf_counter() - t0)
            failures += response.status_code != 200

    async with httpx.AsyncClient(base_url=base, timeout=120.0, limits=limits) as client:
        start = time.perf_counter()
        await asyncio.gather(*(worker(client) for _ in range(clients)))
        wall = time.perf_counter() - start
    return np.asarray(latencies), wall, failures


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="predict/reprofiling latency under load")
    parser.add_argument("--quick", action="store_true", help="200 requests per endpoint")
    parser.add_argument("--requests", type=int, default=None, help="requests per endpoint")
    parser.add_argument("--clients", type=int, default=32, help="concurrent clients")
    args = parser.parse_args(argv)
    n = args.requests or (200 if args.quick else 2_000)
    with tempfile.TemporaryDirectory(prefix="wearcast-bench-api-") as tmp:
        port = free_port()
        base = f"http://127.0.0.1:{port}"
        server = start_server(Path(tmp), port)
        try:
            wait_healthy(base, server)
            t0 = time.perf_counter()
            model_id = prepare(base)
            print(f"example loaded and model {model_id} calibrated in "
                  f"{time.perf_counter() - t0:.1f} s; {n} requests per endpoint, "
                  f"{args.clients} concurrent clients")
            print(f"{'endpoint':<12} {'p50 ms':>8} {'p99 ms':>8} {'req/s':>8} {'errors':>7}")
            for endpoint in ("predict", "reprofiling"):
                path = f"/v1/models/{model_id}/{endpoint}"
                latencies, wall, failures = asyncio.run(
                    fire(base, path, bodies(endpoint, n), args.clients))
                p50, p99 = np.percentile(latencies, [50, 99]) * 1e3
                print(f"{endpoint:<12} {p50:>8.1f} {p99:>8.1f} {n / wall:>8.1f} "
                      f"{failures:>7}", flush=True)
        finally:
            server.terminate()
            try:
                server.wait(timeout=10)
            except subprocess.TimeoutExpired:
                server.kill()


if __name__ == "__main__":
    main()
