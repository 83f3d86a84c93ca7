"""A physics model of the Minuetto on the Aosta line through the HTTP API, against seed 003
Table 2 (FT, FH, qR averaged over all wheels of each unit, as published).

Stores the example fleet's ``aosta`` route (39 curve classes), each unit's Table 2 rows as one
parameter measurement per mileage (``../shared/reference/published/aosta_measured_FH_FT_QR.csv``),
builds ``POST /v1/models`` ``kind: physics`` (minuetto, USFD, D_step as given) and prints the
build time, the fitted wear scale with its P10/P90, the errors per unit and quantity and the
reprofiling answer; with ``--diagnose`` also the physics diagnosis (eight loop runs: hours).

Run: ``.venv/bin/python benchmarks/physics_model_aosta.py [--step 0.8] [--diagnose]``
(about 20 min on 2 shared cores)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
from miniprof_walkthrough import in_process_client  # noqa: E402

TABLE2 = ROOT.parent / "shared" / "reference" / "published" / "aosta_measured_FH_FT_QR.csv"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--diagnose", action="store_true")
    args = parser.parse_args()
    client = in_process_client()
    routes = json.loads((ROOT / "service" / "example_fleet" / "routes.json").read_text())
    aosta = next(r for r in routes if r["name"] == "aosta")
    assert client.post("/v1/routes", json=aosta).status_code == 201
    measured = pd.read_csv(TABLE2, comment="#")
    for row in measured.itertuples():
        r = client.post("/v1/measurements", json={
            "wheel_id": f"{row.vehicle}-mean", "vehicle_id": row.vehicle, "bogie_type": "motor",
            "axle": 1, "side": "right", "mileage_km": float(row.distance_km),
            "sd_mm": row.FT_mm, "sh_mm": row.FH_mm, "qr_mm": row.QR_mm})
        assert r.status_code == 201, r.text
    start = time.perf_counter()
    r = client.post("/v1/models", json={"kind": "physics", "name": "aosta", "vehicle": "minuetto",
                                        "route_id": "aosta",
                                        "simulation": {"depth_per_step_mm": args.step}},
                    headers={"Prefer": "wait=7200"})
    print(f"build: {r.status_code} in {time.perf_counter() - start:.0f} s")
    model = r.json()
    if r.status_code != 201:
        print(model)
        return
    physics = model["physics"]
    print(json.dumps({k: physics[k] for k in ("wear_scale", "wear_scale_p10", "wear_scale_p90",
                                               "rms_mm", "at_reach", "spread")}, indent=1))
    print(json.dumps(physics["simulation"], indent=1))
    print(pd.DataFrame(physics["errors"]["per_vehicle"]).to_string())
    print(pd.DataFrame(physics["errors"]["overall"]).to_string())
    r = client.post(f"/v1/models/{model['id']}/reprofiling",
                    json={"bogie_type": "motor", "axle": 1, "side": "right"})
    print("reprofiling", r.status_code,
          {k: r.json()[k] for k in ("mileage_km", "governing_limit", "extrapolated")})
    if args.diagnose:
        start = time.perf_counter()
        r = client.post(f"/v1/models/{model['id']}/diagnose", json={},
                        headers={"Prefer": "wait=36000"})
        print(f"diagnose: {r.status_code} in {time.perf_counter() - start:.0f} s")
        d = r.json()
        print(f"verdict {d.get('verdict')}; runner-up {d.get('runner_up')}, margin "
              f"{d.get('margin')}, p {d.get('margin_p_value')}; skipped: {d.get('skipped')}")
        print(pd.DataFrame([{
            "cause": f["cause"], "value": f["extension"].get("value"),
            "wear_scale": f["extension"].get("wear_scale"),
            "error_before_mm2": f["gain"]["before_error"],
            "error_after_mm2": f["gain"]["after_error"], "gain": f["gain"]["relative"],
            "ci95": f"{f['gain']['ci95_low']:.3f}-{f['gain']['ci95_high']:.3f}",
            "p_holm": f["evidence"]["p_holm"], "significant": f["significant"]}
            for f in d.get("findings", [])]).to_string(index=False))


if __name__ == "__main__":
    main()
