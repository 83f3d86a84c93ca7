"""Cost of ``POST /v1/contact`` per pose by normal-contact method and FASTSIM grid.

Runs the service's contact computation (``service.contact_store.compute_contact``, no HTTP)
for S1002 on 60E1 1:40 at seven lateral shifts (-4 ... 8 mm, 60 kN) with each
``normal_method`` and ``fastsim_grid`` 40 and 100, and prints the wall time per pose. The
figures set the ``max_fine_bem_poses`` limit (README, "Limits").

    .venv/bin/python benchmarks/contact_method_cost.py
"""

from __future__ import annotations

import platform
import time

from wearcast.service.contact_schemas import ContactIn
from wearcast.service.contact_store import compute_contact

SHIFTS_MM = (-4.0, -2.0, 0.0, 2.0, 4.0, 6.0, 8.0)
METHODS = ("hertz", "kp", "auto", "bem-coarse", "bem")


def main() -> None:
    poses = [{"shift_mm": s, "wheel_load_n": 60_000.0} for s in SHIFTS_MM]
    # warm-up: imports and compiled kernels
    compute_contact(None, ContactIn.model_validate({"poses": poses[:1],
                                                    "normal_method": "hertz"}))
    print(f"machine: {platform.processor() or platform.machine()}")
    print("method      grid  ms per pose")
    for method in METHODS:
        for grid in (40, 100):
            body = ContactIn.model_validate({"poses": poses, "normal_method": method,
                                             "fastsim_grid": grid})
            start = time.perf_counter()
            compute_contact(None, body)
            per_pose_ms = (time.perf_counter() - start) / len(poses) * 1000.0
            print(f"{method:<11} {grid:>4}  {per_pose_ms:8.1f}", flush=True)


if __name__ == "__main__":
    main()
