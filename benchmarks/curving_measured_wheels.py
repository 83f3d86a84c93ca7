"""Curve-radius tables from the nine real MiniProf wheels (and one on a measured worn rail).

Imports the wheels of ``../shared/reference/miniprof`` through the HTTP API (in process,
temporary SQLite, the walk-through's manifest), then asks ``POST /v1/wear-tables/compute``
for a table of the Manchester vehicle over 12 radii (150-5000 m, tangent added) with each
wheel's ``measurement_id`` on 60E1 1:40, and once more on the measured rail ``avg_low2.ban``.
Prints per wheel the status, the time and the largest flange tau_max; a 422 prints its
reason (a profile that cannot make contact must say so, not raise).

Run: ``.venv/bin/python benchmarks/curving_measured_wheels.py [folder]``
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

with warnings.catch_warnings():
    warnings.simplefilter("ignore")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
from miniprof_walkthrough import MANIFEST, in_process_client, wheels_zip  # noqa: E402

RADII = [150, 200, 250, 300, 400, 500, 700, 1000, 1500, 2000, 3000, 5000]


def main(folder: Path) -> None:
    client = in_process_client()
    data, manifest, _ = wheels_zip(folder)
    r = client.post("/v1/measurements/import", files={
        "file": ("miniprof.zip", data), "manifest": ("manifest.csv", manifest.encode())})
    assert r.status_code == 200, r.text
    rail = client.post("/v1/rails/import", files={
        "file": ("avg_low2.ban", (folder / "avg_low2.ban").read_bytes())}).json()
    rail_id = rail["created"][0]["id"] if rail.get("created") else None
    request = {"vehicle": "manchester", "radii": [{"radius_m": r} for r in RADII]}
    print(f"Manchester vehicle, {len(RADII)} radii + tangent, a_nc 0.58 m/s^2")
    cases = [(wheel, None) for _, (wheel, _, _) in MANIFEST.items()]
    cases.append((MANIFEST["whl_left_iter288.whl"][0], rail_id))
    for wheel, rail_on in cases:
        listing = client.get("/v1/measurements", params={"wheel_id": wheel}).json()
        items = listing["items"] if isinstance(listing, dict) else listing
        body = {"name": wheel, **request, "measurement_id": items[0]["id"]}
        if rail_on is not None:
            body["rail_id"] = rail_on
        t0 = time.perf_counter()
        r = client.post("/v1/wear-tables/compute", json=body)
        dt = time.perf_counter() - t0
        where = f"{wheel} on {'avg_low2.ban' if rail_on else '60E1'}"
        if r.status_code != 201:
            print(f"  {where:<32s} {r.status_code} in {dt:5.2f} s {r.json().get('detail')}")
            continue
        table = r.json()
        tau = max((row["value"] for row in table["rows"] if row["region"] == "flange"
                   and row["measure"] == "tau_max"), default=0.0)
        print(f"  {where:<32s} 201 in {dt:5.2f} s, {table['n_rows']} rows, largest flange "
              f"tau_max {tau:6.1f} MPa")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else
         Path(__file__).resolve().parents[2] / "shared" / "reference" / "miniprof")
