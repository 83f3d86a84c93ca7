"""Hand-written hostile pass over the physics requests and their rail fields (issue 14).

    .venv/bin/python benchmarks/hostile_rail_fields.py                    # SQLite
    .venv/bin/python benchmarks/hostile_rail_fields.py postgresql+psycopg://postgres@127.0.0.1:5432/db

On an in-process app (admin key, rate limit off) with the reference rail ``avg_low2.ban`` and
the roller ``left-roller-v1-pre-dry.ban`` stored (``../shared/reference/miniprof``), sends to
``POST /v1/wear-tables/compute``, ``/v1/wear-tables/jobs``, ``/v1/simulations`` and
``/v1/contact``: every rail field (``rail_id``, ``high_rail_id``, ``low_rail_id``) set to 0,
negative, beyond 62 and 64 bits, strings, fractions, booleans, lists, objects and ids not
stored; NaN/Infinity literals; the same rail on both sides; a roller as the high rail; unknown
fields; JSON nested 1,000 and 100,000 deep; bodies of 3 MB; wrong content types; bytes that
are not UTF-8; NUL bytes; no key, a wrong key, a read-scoped key and a cross-site origin.
Then the rail routes with ids and ``rail:<id>`` references out of range, and rail imports
with bad references and inclinations.

Prints one line per request (status, fields named, detail), the answers by status, the
peak resident memory of the process and the requests that failed a rule: a 5xx, an error
that is not problem details naming a field, or an unexpected status. A body whose JSON
cannot be read, or that is not an object, names ``body``: the body is the field at fault.
"""

from __future__ import annotations

import collections
import json
import resource
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service.app import create_app
from wearcast.service.settings import Settings

MINIPROF = Path(__file__).resolve().parents[1].parent / "shared" / "reference" / "miniprof"
KEY = "wc_hostile-pass-admin-key"
BASES: dict[str, dict[str, Any]] = {
    "/v1/wear-tables/compute": {"name": "t", "vehicle": "manchester",
                                "radii": [{"radius_m": 1000}]},
    "/v1/wear-tables/jobs": {"name": "t", "vehicle": "manchester",
                             "radii": [{"radius_m": 1000}]},
    "/v1/simulations": {"vehicle": "metro_b", "classes": [
        {"radius_m": None, "speed_kmh": 70, "share": 1.0}],
        "steps": {"mode": "adaptive", "count": 1, "depth_per_step_mm": 0.1}},
    "/v1/contact": {"poses": [{"shift_mm": 0}]},
}
#: Not a stored rail's id (``1.0`` would be: JSON Schema counts it an integer).
BAD_IDS: list[Any] = [0, -1, -2**63, 2**62 + 1, 2**63 - 1, 2**63, 2**64, 10**30, "1", "abc",
                      "", 1.5, 1e308, True, False, [1], {"id": 1}, 999]
OK = {200, 201, 202}


class Pass:
    """The requests sent, their statuses and the ones that broke a rule."""

    def __init__(self) -> None:
        self.statuses: collections.Counter[int] = collections.Counter()
        self.failures: list[str] = []

    def check(self, label: str, r: Any, expect: set[int]) -> None:
        self.statuses[r.status_code] += 1
        problem = r.headers.get("content-type", "").startswith("application/problem+json")
        body = r.json() if problem else None
        fields = [e.get("field") for e in body.get("errors", [])] if body else []
        bad = (r.status_code >= 500 or r.status_code not in expect
               or (r.status_code >= 400 and not (problem and fields and "request" not in fields)))
        detail = body.get("detail", "")[:140] if body else ""
        line = f"{'!!' if bad else 'ok'} {r.status_code} {label[:110]} {fields} {detail}"
        print(line)
        if bad:
            self.failures.append(line)


def main(database_url: str | None) -> int:
    data_dir = Path(tempfile.mkdtemp(prefix="wearcast-hostile-"))
    app = create_app(Settings(data_dir=data_dir, database_url=database_url, api_key=KEY,
                              job_workers=1, job_quota_per_key=1000, rate_limit_per_second=0))
    admin = {"Authorization": f"Bearer {KEY}"}
    c = TestClient(app, raise_server_exceptions=False)
    ban = (MINIPROF / "avg_low2.ban").read_bytes()
    rail = c.post("/v1/rails/import", files={"file": ("avg_low2.ban", ban)},
                  headers=admin).json()["created"][0]["id"]
    roller = c.post("/v1/rails/import", files={"file": (
        "roller.ban", (MINIPROF / "left-roller-v1-pre-dry.ban").read_bytes())},
        headers=admin).json()["created"][0]["id"]
    reader = c.post("/v1/admin/api-keys", json={"name": "reader", "scopes": ["read"]},
                    headers=admin).json()["key"]
    read = {"Authorization": f"Bearer {reader}"}
    p = Pass()
    json_type = {**admin, "content-type": "application/json"}
    for path, base in BASES.items():
        written = OK if path != "/v1/contact" else {200}
        fields = ("rail_id", "high_rail_id", "low_rail_id")
        for field in fields:
            allowed = {422} if (path == "/v1/contact" and field != "rail_id") else {404, 422}
            for value in BAD_IDS:
                p.check(f"{path} {field}={value!r}", c.post(path, json={**base, field: value},
                                                             headers=admin), allowed)
        for literal in ("NaN", "Infinity", "-Infinity", "1e999", "01", "0x10"):
            raw = json.dumps(base)[:-1] + f', "high_rail_id": {literal}}}'
            p.check(f"{path} high_rail_id={literal}", c.post(path, content=raw,
                                                             headers=json_type), {422})
        raw = json.dumps(base).replace("1000", "NaN").replace("70", "NaN").replace(
            '"shift_mm": 0', '"shift_mm": NaN')
        p.check(f"{path} NaN in numbers", c.post(path, content=raw, headers=json_type), {422})
        if path != "/v1/contact":
            for extra in ({"high_rail_id": rail, "low_rail_id": rail},
                          {"high_rail_id": rail, "low_rail_id": rail, "rail_id": rail},
                          {"high_rail_id": roller, "low_rail_id": rail}):
                p.check(f"{path} {extra}", c.post(path, json={**base, **extra},
                                                  headers=admin), written)
            p.check(f"{path} low_rail_id unknown", c.post(path, json={
                **base, "high_rail_id": rail, "low_rail_id": 999}, headers=admin), {404})
        p.check(f"{path} unknown field", c.post(path, json={**base, "high_rail": rail},
                                                headers=admin), {422})
        for depth in (1000, 100_000):
            raw = '{"high_rail_id": ' + "[" * depth + "]" * depth + "}"
            p.check(f"{path} JSON {depth} deep", c.post(path, content=raw, headers=json_type),
                    {400, 413})
        big = json.dumps({**base, "name": "x" * (3 * 1024 * 1024)})
        p.check(f"{path} 3 MB body", c.post(path, content=big, headers=json_type), {413})
        for ctype in ("text/plain", "application/x-www-form-urlencoded", "multipart/form-data",
                      "application/xml"):
            p.check(f"{path} content-type {ctype}", c.post(path, content=json.dumps(base),
                    headers={**admin, "content-type": ctype}), {400, 415, 422})
        for label, raw_bytes in (("not UTF-8", b'{"name": "\xff\xfe"}'),
                                 ("lone surrogate", b'{"name": "\\ud800"}'),
                                 ("NUL in name", b'{"name": "a\\u0000b"}'),
                                 ("empty", b""), ("trailing garbage", b"{}x"),
                                 ("array", b"[]")):
            p.check(f"{path} body {label}", c.post(path, content=raw_bytes,
                                                   headers=json_type), {400, 422})
        p.check(f"{path} no key", c.post(path, json=base), {401})
        p.check(f"{path} wrong key", c.post(path, json=base,
                                            headers={"Authorization": "Bearer nope"}), {401})
        # a read key may POST only what stores nothing and is cheap (predict, reprofiling)
        p.check(f"{path} read key", c.post(path, json=base, headers=read), {403})
        p.check(f"{path} cross-site", c.post(path, json=base, headers={
            **admin, "Origin": "https://evil.example", "Sec-Fetch-Site": "cross-site"}), {403})
    for url in ("/v1/rails/0", "/v1/rails/-1", "/v1/rails/abc", f"/v1/rails/{2**63}",
                f"/v1/rails/{2**63 - 1}", f"/v1/rails/{rail}?reference=rail:{2**63}",
                f"/v1/rails/{rail}?reference=rail:" + "9" * 40, "/v1/rails?reference=rail:999",
                f"/v1/rails/{rail}?reference=rail:0", f"/v1/rails/{rail}?reference=%00",
                f"/v1/rails?offset={2**63}", f"/v1/rails/{rail}?include_points=maybe"):
        p.check(f"GET {url}", c.get(url, headers=admin), {404, 422})
    for ref in (f"rail:{2**63}", "rail:" + "9" * 40, "rail:-1", "rail:999", "S49"):
        p.check(f"import reference={ref}", c.post("/v1/rails/import", files={
            "file": ("x.ban", ban + b"\n")}, data={"reference": ref}, headers=admin),
            {404, 422})
    for inclination in ("1/0", "nan", "inf", "-1/40", "0.025e999", "1/40" * 1000):
        p.check(f"import inclination={inclination[:20]}", c.post("/v1/rails/import", files={
            "file": ("y.ban", ban + b"\n\n")}, data={"inclination": inclination},
            headers=admin), {422})
    p.check("import read key", c.post("/v1/rails/import", files={"file": ("z.ban", ban)},
                                      headers=read), {403})
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\n{sum(p.statuses.values())} requests on {app.state.database.engine.dialect.name}:"
          f" {dict(sorted(p.statuses.items()))}; peak RSS {peak_mib:.0f} MiB; "
          f"{len(p.failures)} broke a rule")
    for line in p.failures:
        print(line)
    return 1 if p.failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else None))
