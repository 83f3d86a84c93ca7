"""API latency under load: predict, reprofiling and the common GETs from concurrent clients.

    .venv/bin/python benchmarks/bench_api_latency.py            # 2,000 requests per endpoint
    .venv/bin/python benchmarks/bench_api_latency.py --quick    # 200 requests per endpoint
    .venv/bin/python benchmarks/bench_api_latency.py --workers 1
    .venv/bin/python benchmarks/bench_api_latency.py --quick --endpoints gets  # GETs only

Migrates a fresh SQLite database in a temporary directory, starts ``uvicorn`` on 127.0.0.1
(a free port) in a subprocess with ``--workers`` processes (default 2, one per core of the
2-core reference machine) running ``wearcast.service.cli:serve_app`` — what
``wearcast serve --workers N`` runs —, loads the bundled example fleet over HTTP, calibrates
a model on unit A's motor bogies, then per endpoint: sends ``--warmup`` untimed requests
(default 4 per client: the first request of each worker process reads and caches the model
and the table), and fires the timed requests from ``--clients`` concurrent
``httpx.AsyncClient`` workers (default 32) in a closed loop. Prints the latency of the first
(cold) request, p50/p99 latency and throughput per endpoint. The client runs on the same
machine and takes its share of the CPU. Every request computes its answer: only immutable
inputs (the model and its summary, the compiled table, the route) are cached by the service,
and a picture's drawing under the key of its inputs — which every picture request reads and
computes afresh (the prediction included).

The GET endpoints (``--endpoints gets``, or ``all``, the default): health, the route
list and one route, a model, a page of 20 measurements and one measurement, the job list,
and the wear-area picture — drawn once, then answered from the server's picture cache
(``picture``) and, with ``If-None-Match`` naming its ETag, with 304 (``picture-304``).

``--client raw`` (a minimal asyncio HTTP/1.1 client) spends far less CPU than httpx, so on a
small machine its figures measure the server rather than the client. The header names the
machine (CPU model and cores from ``/proc/cpuinfo``), the client, the workers and the
machine's load average, which every figure depends on.

Closed and open loop. The default run is a *closed loop*: each of the ``--clients`` clients
sends its next request as soon as its answer arrives, so the server is saturated and, by
Little's law, the mean latency is clients / throughput — with 32 clients a p50 under 5 ms
would need more than 6,400 answers per second, i.e. under 0.3 ms of CPU per request on two
cores for server and client together. ``--rate R`` adds an *open-loop* run per endpoint:
requests arrive at R per second in total (Poisson arrivals, seeded) over ``--clients``
kept-alive raw connections, and each latency is counted from the request's scheduled
arrival (a request that waits for a free connection or for the server is charged the wait),
so the figures are the response times 32 clients see at that offered load.

Before/after in one run. ``--baseline-python PY`` starts a second server with another
interpreter — e.g. ``/work/main/.venv/bin/python``, whose editable install serves another
checkout's code — on its own fresh database, and measures both servers endpoint by
endpoint, back to back (rows ``base`` and ``this``), so their ratio is measured under the
same machine load.

    .venv/bin/python benchmarks/bench_api_latency.py --quick --client raw --endpoints predict \
        --rate 200 --baseline-python ../../main/.venv/bin/python
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

import httpx
import numpy as np

ROUTES = ("aosta", "metro", "tangent")
#: The server's admin key for the run (sent on every request, as every client must); the
#: per-key rate limit is off so that the figures measure the server, not the limiter.
BENCH_KEY = "wc_benchmark-admin-key-0123456789"
AUTH = {"Authorization": f"Bearer {BENCH_KEY}"}
BOGIES = ("motor", "trailer")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start_server(data_dir: Path, port: int, workers: int, log: Path,
                 python: str = sys.executable) -> subprocess.Popen[bytes]:
    """Migrate the database, then serve it with ``workers`` uvicorn processes of the
    interpreter ``python`` (access log off: the figures measure the service, not its log)."""
    env = dict(os.environ, WEARCAST_DATA_DIR=str(data_dir), WEARCAST_API_KEY=BENCH_KEY,
               WEARCAST_RATE_LIMIT_PER_SECOND="0")
    env.pop("WEARCAST_DATABASE_URL", None)
    subprocess.run([python, "-m", "wearcast.service.cli", "migrate"], env=env,
                   check=True, stdout=subprocess.DEVNULL)
    with log.open("wb") as err:
        return subprocess.Popen(
            [python, "-m", "uvicorn", "wearcast.service.cli:serve_app", "--factory",
             "--host", "127.0.0.1", "--port", str(port), "--workers", str(workers),
             "--log-level", "warning", "--no-access-log"],
            env=env, stdout=subprocess.DEVNULL, stderr=err)


def wait_healthy(base: str, server: subprocess.Popen[bytes], log: Path,
                 timeout_s: float = 180.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if server.poll() is not None:
            raise RuntimeError(f"server exited: {log.read_text()[-2000:]}")
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

    with httpx.Client(base_url=base, timeout=300.0, headers=AUTH) as client:
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


class RawConnection:
    """A minimal HTTP/1.1 keep-alive client on one asyncio connection (``--client raw``).

    It only sends JSON POSTs and reads answers with a Content-Length; it spends a small
    fraction of httpx's CPU per request, so that on a small machine the figures measure the
    server rather than the client.
    """

    def __init__(self, host: str, port: int) -> None:
        self.host, self.port = host, port
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None

    async def post(self, path: str, payload: dict[str, object] | None,
                   extra: dict[str, str] | None = None) -> int:
        """POST ``payload`` as JSON, or GET ``path`` when it is None; the answer's status."""
        if self.writer is None:
            self.reader, self.writer = await asyncio.open_connection(self.host, self.port)
        assert self.reader is not None
        body = b"" if payload is None else json.dumps(payload).encode()
        head_lines = "".join(f"{k}: {v}\r\n" for k, v in (extra or {}).items())
        if payload is None:
            request = f"GET {path} HTTP/1.1\r\n"
        else:
            request = (f"POST {path} HTTP/1.1\r\nContent-Type: application/json\r\n"
                       f"Content-Length: {len(body)}\r\n")
        self.writer.write(
            f"{request}Host: {self.host}:{self.port}\r\n"
            f"Authorization: Bearer {BENCH_KEY}\r\n{head_lines}\r\n".encode() + body)
        head = await self.reader.readuntil(b"\r\n\r\n")
        lines = head.decode("latin-1").split("\r\n")
        status = int(lines[0].split()[1])
        headers = dict(line.split(":", 1) for line in lines[1:] if ":" in line)
        length = {k.strip().lower(): v.strip() for k, v in headers.items()}.get(
            "content-length", "0")
        await self.reader.readexactly(int(length))
        return status

    async def close(self) -> None:
        if self.writer is not None:
            self.writer.close()
            await self.writer.wait_closed()


async def fire(base: str, path: str, payloads: list[dict[str, object] | None],
               clients: int, client_kind: str = "httpx", extra: dict[str, str] | None = None,
               expect: int = 200) -> tuple[np.ndarray, float, int]:
    """Latencies [s] of all requests (a None payload: a GET), wall time [s] and the number
    of answers other than ``expect``."""
    if client_kind == "raw":
        return await fire_raw(base, path, payloads, clients, extra, expect)
    queue: asyncio.Queue[dict[str, object] | None] = asyncio.Queue()
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
            if payload is None:
                response = await client.get(path, headers=extra)
            else:
                response = await client.post(path, json=payload, headers=extra)
            latencies.append(time.perf_counter() - t0)
            failures += response.status_code != expect

    async with httpx.AsyncClient(base_url=base, timeout=120.0, limits=limits,
                                 headers=AUTH) as client:
        start = time.perf_counter()
        await asyncio.gather(*(worker(client) for _ in range(clients)))
        wall = time.perf_counter() - start
    return np.asarray(latencies), wall, failures


async def fire_raw(base: str, path: str, payloads: list[dict[str, object] | None],
                   clients: int, extra: dict[str, str] | None = None,
                   expect: int = 200) -> tuple[np.ndarray, float, int]:
    """:func:`fire` with one :class:`RawConnection` per client."""
    url = httpx.URL(base)
    pending = list(reversed(payloads))
    latencies: list[float] = []
    failures = 0

    async def worker() -> None:
        nonlocal failures
        connection = RawConnection(url.host, int(url.port or 80))
        try:
            while pending:
                payload = pending.pop()
                t0 = time.perf_counter()
                status = await connection.post(path, payload, extra)
                latencies.append(time.perf_counter() - t0)
                failures += status != expect
        finally:
            await connection.close()

    start = time.perf_counter()
    await asyncio.gather(*(worker() for _ in range(clients)))
    return np.asarray(latencies), time.perf_counter() - start, failures


async def fire_open(base: str, path: str, payloads: list[dict[str, object] | None],
                    clients: int, rate_per_s: float, extra: dict[str, str] | None = None,
                    expect: int = 200) -> tuple[np.ndarray, float, int]:
    """Open loop: the requests arrive at ``rate_per_s`` in total (Poisson, seeded) and are
    sent on the first free of ``clients`` raw connections; each latency [s] runs from the
    request's scheduled arrival to its answer (waits for a connection included). Returns the
    latencies, the wall time [s] and the number of answers other than ``expect``."""
    url = httpx.URL(base)
    idle: asyncio.Queue[RawConnection] = asyncio.Queue()
    connections = [RawConnection(url.host, int(url.port or 80)) for _ in range(clients)]
    for connection in connections:
        idle.put_nowait(connection)
    gaps = np.random.default_rng(1).exponential(1.0 / rate_per_s, len(payloads))
    latencies: list[float] = []
    failures = 0

    async def one(payload: dict[str, object] | None, due: float) -> None:
        nonlocal failures
        connection = await idle.get()
        try:
            status = await connection.post(path, payload, extra)
        finally:
            idle.put_nowait(connection)
        latencies.append(time.perf_counter() - due)
        failures += status != expect

    loop = asyncio.get_running_loop()
    start = time.perf_counter()
    due = start
    tasks = []
    for payload, gap in zip(payloads, gaps, strict=True):
        due += float(gap)
        delay = due - time.perf_counter()
        if delay > 0:
            await asyncio.sleep(delay)
        tasks.append(loop.create_task(one(payload, due)))
    await asyncio.gather(*tasks)
    wall = time.perf_counter() - start
    for connection in connections:
        await connection.close()
    return np.asarray(latencies), wall, failures


def machine() -> str:
    """CPU model and logical cores (Linux /proc/cpuinfo), and the memory."""
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        kib = next(int(line.split()[1]) for line in
                   Path("/proc/meminfo").read_text().splitlines()
                   if line.startswith("MemTotal"))
        memory = f", {kib / 2**20:.0f} GiB"
    except (OSError, StopIteration, ValueError):
        memory = ""
    return f"{model}, {os.cpu_count()} logical cores{memory}"


def cpu_seconds(pid: int) -> float:
    """CPU time [s] of a process and its children (Linux /proc; NaN elsewhere)."""
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
        total = 0.0
        for p in [pid, *map(int, children)]:
            fields = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
            total += (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        return total
    except (OSError, ValueError, IndexError):
        return float("nan")


def own_cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _load() -> str:
    """The machine's load averages: other jobs on it take CPU from server and client."""
    try:
        return "/".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "unknown"


class Endpoint(NamedTuple):
    """One timed endpoint: a POST with generated bodies, or a GET (``body`` None)."""

    name: str
    path: str
    body: str | None = None  # "predict" / "reprofiling": the bodies to generate
    headers: dict[str, str] | None = None
    expect: int = 200


def endpoints(base: str, model_id: int, which: str) -> list[Endpoint]:
    """The timed endpoints; the GETs' ids (a measurement, the picture's ETag) are read
    first."""
    out: list[Endpoint] = []
    if which in ("all", "predict"):
        out += [Endpoint(e, f"/v1/models/{model_id}/{e}", e) for e in ("predict", "reprofiling")]
    if which in ("all", "gets"):
        picture = (f"/v1/models/{model_id}/pictures/wear-area?route_id=aosta"
                   "&bogie_type=motor&axle=1&side=left")
        with httpx.Client(base_url=base, timeout=120.0, headers=AUTH) as client:
            page = client.get("/v1/measurements", params={"limit": 1})
            page.raise_for_status()
            measurement_id = page.json()["items"][0]["id"]
            drawn = client.get(picture)  # drawn once, then served from the picture cache
            drawn.raise_for_status()
            etag = drawn.headers.get("etag")  # None from a server without picture ETags
        out += [Endpoint("health", "/v1/health"), Endpoint("routes", "/v1/routes"),
                Endpoint("route", "/v1/routes/aosta"),
                Endpoint("model", f"/v1/models/{model_id}"),
                Endpoint("measurements", "/v1/measurements?bogie_type=motor&limit=20"),
                Endpoint("measurement", f"/v1/measurements/{measurement_id}"),
                Endpoint("jobs", "/v1/jobs"),
                Endpoint("picture", picture)]
        if etag is not None:
            out.append(Endpoint("picture-304", picture, headers={"If-None-Match": etag},
                                expect=304))
    return out


class Server(NamedTuple):
    """One served checkout: its label, base URL, process and calibrated model."""

    label: str
    base: str
    process: subprocess.Popen[bytes]
    model_id: int


def run_endpoint(server: Server, e: Endpoint, n: int, warmup: int, args: argparse.Namespace
                 ) -> None:
    """Cold request, warm-up, the closed-loop run and (``--rate``) the open-loop run of one
    endpoint on one server; one printed row per run."""
    base = server.base

    def payloads(k: int) -> list[dict[str, object] | None]:
        return list(bodies(e.body, k)) if e.body else [None] * k

    first = payloads(1)[0]
    t_cold = time.perf_counter()
    if first is None:
        answer = httpx.get(base + e.path, timeout=120.0, headers={**AUTH, **(e.headers or {})})
    else:
        answer = httpx.post(base + e.path, json=first, timeout=120.0, headers=AUTH)
    assert answer.status_code == e.expect, (e.name, answer.status_code)
    cold = (time.perf_counter() - t_cold) * 1e3
    if warmup:
        asyncio.run(fire(base, e.path, payloads(warmup), args.clients, args.client,
                         e.headers, e.expect))
    runs: list[tuple[str, float | None]] = [("closed", None)]
    if args.rate:
        runs.append((f"{args.rate:g}/s", args.rate))
    for mode, rate in runs:
        server_cpu, client_cpu = cpu_seconds(server.process.pid), own_cpu_seconds()
        if rate is None:
            latencies, wall, failures = asyncio.run(
                fire(base, e.path, payloads(n), args.clients, args.client, e.headers, e.expect))
        else:
            latencies, wall, failures = asyncio.run(
                fire_open(base, e.path, payloads(n), args.clients, rate, e.headers, e.expect))
        server_cpu = (cpu_seconds(server.process.pid) - server_cpu) / n * 1e3
        client_cpu = (own_cpu_seconds() - client_cpu) / n * 1e3
        p50, p95, p99 = np.percentile(latencies, [50, 95, 99]) * 1e3
        print(f"{server.label:<5} {e.name:<13} {mode:>8} {cold:>8.1f} {p50:>8.1f} {p95:>8.1f} "
              f"{p99:>8.1f} {n / wall:>8.1f} {failures:>7} {server_cpu:>8.2f} "
              f"{client_cpu:>8.2f} {os.getloadavg()[0]:>6.2f}", flush=True)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="API latency under load")
    parser.add_argument("--quick", action="store_true", help="200 requests per endpoint")
    parser.add_argument("--requests", type=int, default=None, help="requests per endpoint")
    parser.add_argument("--clients", type=int, default=32, help="concurrent clients")
    parser.add_argument("--workers", type=int, default=2,
                        help="uvicorn worker processes (default 2: one per core)")
    parser.add_argument("--warmup", type=int, default=None,
                        help="untimed requests per endpoint first (default 4 per client)")
    parser.add_argument("--client", choices=("httpx", "raw"), default="httpx",
                        help="httpx.AsyncClient (default) or a minimal asyncio HTTP/1.1 client")
    parser.add_argument("--endpoints", choices=("all", "predict", "gets"), default="all",
                        help="predict and reprofiling, the common GETs, or both (default)")
    parser.add_argument("--rate", type=float, default=None,
                        help="also an open-loop run per endpoint: this many requests per "
                             "second in total over the clients' connections")
    parser.add_argument("--baseline-python", default=None, metavar="PY",
                        help="also serve with this interpreter (another checkout's venv) and "
                             "measure both, endpoint by endpoint")
    args = parser.parse_args(argv)
    n = args.requests or (200 if args.quick else 2_000)
    warmup = args.warmup if args.warmup is not None else 4 * args.clients
    pythons = [("this", sys.executable)]
    if args.baseline_python:
        pythons.insert(0, ("base", args.baseline_python))
    with tempfile.TemporaryDirectory(prefix="wearcast-bench-api-") as tmp:
        servers: list[Server] = []
        try:
            for label, python in pythons:
                port = free_port()
                base = f"http://127.0.0.1:{port}"
                log = Path(tmp) / f"server-{label}.log"
                process = start_server(Path(tmp) / label, port, args.workers, log, python)
                servers.append(Server(label, base, process, -1))
                wait_healthy(base, process, log)
                t0 = time.perf_counter()
                servers[-1] = servers[-1]._replace(model_id=prepare(base))
                print(f"{label}: {python}: example loaded and model {servers[-1].model_id} "
                      f"calibrated in {time.perf_counter() - t0:.1f} s")
            print(f"machine: {machine()}; server: {args.workers} uvicorn worker(s) sharing "
                  f"it with the client; {n} timed requests per endpoint after {warmup} "
                  f"untimed, {args.clients} concurrent clients")
            print(f"client: {args.client}; workers: {args.workers}; clients: {args.clients}; "
                  f"machine load average (1/5/15 min) at the start: {_load()}")
            print("mode: closed = each client sends its next request on its answer (latency = "
                  "clients / throughput, Little's law); N/s = open loop at N requests/s")
            print("CPU columns: milliseconds of CPU per request spent by the server processes "
                  "and by the client; load: 1-min load average after the endpoint's run")
            print(f"{'srv':<5} {'endpoint':<13} {'mode':>8} {'cold ms':>8} {'p50 ms':>8} "
                  f"{'p95 ms':>8} {'p99 ms':>8} {'req/s':>8} {'errors':>7} {'srv CPU':>8} "
                  f"{'cli CPU':>8} {'load':>6}")
            plans = [{e.name: e for e in endpoints(s.base, s.model_id, args.endpoints)}
                     for s in servers]
            for name in plans[-1]:
                for server, plan in zip(servers, plans, strict=True):
                    if name in plan:
                        run_endpoint(server, plan[name], n, warmup, args)
        finally:
            for server in servers:
                server.process.terminate()
                try:
                    server.process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    server.process.kill()


if __name__ == "__main__":
    main()
