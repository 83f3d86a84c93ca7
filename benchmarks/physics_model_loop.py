"""Physics models on wheels the wear loop wore (metro B on a 3-class curvy route, USFD, 0.02 mm
noise, five vehicles of eight wheels measured at irregular mileages, worn 1.2x the loop's
rate): build time and fitted scale, then the whole physical catalogue's diagnosis, once on
effect-free wheels and once with a hidden friction level of 0.56 — through the HTTP API as in
``tests/service/test_physics_models_api.py`` (whose data helpers it uses).

Run: ``.venv/bin/python benchmarks/physics_model_loop.py`` (a few minutes on 2 shared cores)
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the test modules import each other as tests.service.*
import tests.conftest  # noqa: E402,F401  (the test suite's API key for the in-process client)
import tests.service.test_physics_models_api as api  # noqa: E402
from tests.service.conftest import sqlite_client  # noqa: E402


def main() -> None:
    for hidden in ({}, {"friction": 0.56}):
        client = sqlite_client(Path(tempfile.mkdtemp()))
        api._load(client, hidden, vehicles=5)
        start = time.perf_counter()
        model = client.post("/v1/models", json=api.MODEL).json()
        built = time.perf_counter() - start
        start = time.perf_counter()
        diagnosis = client.post(f"/v1/models/{model['id']}/diagnose", json={}).json()
        print(f"hidden {hidden or 'none'}: build {built:.1f} s, wear scale "
              f"{model['physics']['wear_scale']:.4f} (truth {api.SCALE}); diagnosis "
              f"{time.perf_counter() - start:.0f} s, verdict {diagnosis['verdict']}")
        for f in diagnosis["findings"]:
            print(f"    {f['cause']:26s} gain {f['gain']['relative']:+.3f} "
                  f"[{f['gain']['ci95_low']:+.3f}, {f['gain']['ci95_high']:+.3f}] value "
                  f"{f['extension']['value']}")


if __name__ == "__main__":
    main()
