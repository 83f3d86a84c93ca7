"""Walk-through on real MiniProf wheel files: import with a manifest, read the warnings, the
datum placement and the reference fit, give a reference, and ask for the reprofiling mileage
of a wheel measured past its qR limit.

Usage: ``.venv/bin/python examples/miniprof_walkthrough.py <folder with the .whl files>``

Runs the HTTP API in process (FastAPI's TestClient) on a temporary SQLite database; the
requests are the ones a client would send to ``wearcast serve``. The model used for the
reprofiling question is calibrated on the synthetic metro fleet of
``statistics.generators.fleet_twin`` (the real files carry no mileage history to calibrate on).
"""

from __future__ import annotations

import io
import secrets
import sys
import tempfile
import warnings
import zipfile
from pathlib import Path

from pydantic import SecretStr

from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.service.app import create_app
from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame
from wearcast.service.settings import Settings
from wearcast.statistics.cleaning import clean_profile
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes, twin_wear_table

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

#: file -> (wheel_id, side as a European spreadsheet spells it, mileage_km)
MANIFEST = {
    "Car7216_0001r.whl": ("C7216-R", "R", "12000"), "Car7358_0001r.whl": ("C7358-R", "R", "12000"),
    "Car7422_0001r.whl": ("C7422-R", "R", "12000"), "Car7813_0001r.whl": ("C7813-R", "R", "12000"),
    "avg_wheel.whl": ("AVG", "L", "50000"), "left-wheel-v1-pre-dry.whl": ("TAL-L", "links", "0"),
    "right-wheel-v1-pre-dry.whl": ("TAL-R", "rechts", "0"),
    "whl_left_iter288.whl": ("C1634-L3", "L", "120000,5"),
    "whl_left_iter795.whl": ("C291287-L2", "L", "95000"),
}


def in_process_client() -> TestClient:
    """The HTTP API in process on a temporary SQLite database, with the run's own admin key."""
    key = f"wc_example-{secrets.token_urlsafe(16)}"
    data_dir = Path(tempfile.mkdtemp())
    return TestClient(create_app(Settings(data_dir=data_dir, api_key=SecretStr(key),
                                          database_url=f"sqlite:///{data_dir / 'w.db'}")),
                      headers={"Authorization": f"Bearer {key}"})


def wheels_zip(folder: Path) -> tuple[bytes, str, list[str]]:
    """(zip of the nine wheel files, their manifest, the manifest's rows)."""
    rows = ["file;wheel_id;vehicle_id;bogie_type;axle;side;mileage_km;reference_profile"]
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, (wheel, side, km) in MANIFEST.items():
            archive.writestr(name, (folder / name).read_bytes())
            rows.append(f"{name};{wheel};V-{wheel};M;1;{side};{km};S1002")
    return buffer.getvalue(), "\n".join(rows) + "\n", rows


def main(folder: Path) -> None:
    client = in_process_client()
    data, manifest, rows = wheels_zip(folder)
    print("$ manifest.csv (';'-separated, sides L/R/links/rechts, bogie M, decimal comma)")
    print("\n".join(rows[:3]) + "\n...")
    print("\n$ POST /v1/measurements/import  file=miniprof.zip manifest=manifest.csv")
    answer = client.post("/v1/measurements/import", files={
        "file": ("miniprof.zip", data),
        "manifest": ("manifest.csv", manifest.encode())}).json()
    print({k: v for k, v in answer.items() if k != "warnings"})
    for w in answer["warnings"]:
        if w["level"] == "warning":
            print(f"  {w['file'].split(':')[-1]} (manifest line {w['line']}) "
                  f"[{w['code']}] {w['message'][:150]}…")

    print("\n$ GET /v1/measurements   (stored Sd/Sh/qR vs the file's raw points; wear alignment)")
    print(f"{'file':27s} {'Sd':>6s} {'Sh':>6s} {'qR':>6s}  {'dSd':>5s} {'dSh':>5s} {'dqR':>5s} "
          f"{'shift':>5s} {'rot':>5s} {'dz':>6s}  fits  flange/tread mm²")
    items = {i["source_file"].split(":")[-1]: i for i in
             client.get("/v1/measurements", params={"limit": 100}).json()["items"]}
    for name in MANIFEST:
        item = items[name]
        mp = parse_miniprof((folder / name).read_bytes(), name)
        cleaned = clean_profile(*to_wheel_frame(mp))
        raw = flange_parameters(cleaned.y_mm, cleaned.z_mm)
        areas = ("—" if item["flange_area_mm2"] is None else
                 f"{item['flange_area_mm2']:.1f}/{item['tread_area_mm2']:.1f}")
        print(f"{name:27s} {item['sd_mm']:6.2f} {item['sh_mm']:6.2f} {item['qr_mm']:6.2f}  "
              f"{item['sd_mm'] - raw.sd_mm:+5.2f} {item['sh_mm'] - raw.sh_mm:+5.2f} "
              f"{item['qr_mm'] - raw.qr_mm:+5.2f} {item['lateral_shift_mm']:5.2f} "
              f"{item['rotation_rad'] * 1e3:5.2f} {item['vertical_shift_mm']:+6.2f}  "
              f"{'yes' if item['reference_fits'] else 'NO ':4s}  {areas}")

    print("\n$ GET /v1/reference-profiles")
    for ref in client.get("/v1/reference-profiles").json():
        print(f"  {ref['name']:12s} Sd {ref['sd_mm']:.2f} Sh {ref['sh_mm']:.2f} "
              f"qR {ref['qr_mm']:.2f}  {ref['description']}")
    print('\n$ PUT /v1/wheels/TAL-L/reference {"reference_profile": "own"}')
    own = client.put("/v1/wheels/TAL-L/reference", json={"reference_profile": "own"}).json()
    m = own["measurements"][0]
    print(f"  reference {m['reference_profile']}, fits {m['reference_fits']}, areas "
          f"{m['flange_area_mm2']:.2f}/{m['tread_area_mm2']:.2f} mm²")

    fleet = ft.generate_fleet(ft.metro_calibration_config())
    client.post("/v1/measurements/import", files={"file": (
        "fleet.csv", fleet.profiles.to_csv(index=False).encode(), "text/csv")})
    client.post("/v1/routes", json=twin_routes.metro_route().to_json())
    table = client.post("/v1/wear-tables", files={"file": (
        "t.csv", twin_wear_table.synthetic_wear_table().to_csv(index=False).encode(),
        "text/csv")}).json()
    model = client.post("/v1/models", json={
        "name": "metro", "measure": "tau_max", "running_mode": "lead",
        "wear_table_id": table["id"],
        "calibration": {"route_id": "metro", "filter": {"route_id": "metro"}}}).json()
    for wheel in ("C1634-L3", "AVG"):
        print(f'\n$ POST /v1/models/{model["id"]}/reprofiling '
              f'{{"route_id": "metro", "wheel_id": "{wheel}"}}')
        r = client.post(f"/v1/models/{model['id']}/reprofiling",
                        json={"route_id": "metro", "wheel_id": wheel}).json()
        print({k: r[k] for k in ("start_mileage_km", "start_parameters_mm", "remaining_km",
                                 "governing_limit", "crossed_limits", "reason",
                                 "start_notes")})


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(Path(sys.argv[1]))
