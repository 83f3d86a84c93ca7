"""Is the bogie residual continuous in the wheelset shift? Worn treads with several gap minima.

Run: .venv/bin/python benchmarks/residual_continuity.py [--km 2000 4000 8000]
     [--forward-share 1.0] [--step 0.8]

The curving equilibrium fails where the residual jumps (README, stop 25: 0.27 wheel loads
when a loaded gap minimum lost its contact slot). For each wheel profile the script builds
the contact table, puts the bogie at its centred static state (``bogie_equations
.initial_state``), sweeps the leading wheelset's shift over -12 ... 12 mm (step 0.002 mm) with
the left wheel pressed 0, 0.1 and 0.3 mm beyond its static approach, and bisects the sweep's
steepest and most isolated steps down to 1e-12 mm (``largest_jump``): a discontinuity keeps
its size, a steep but continuous residual does not. Prints per profile the largest jump left
[wheel loads], the shift and the residual equation where it is, the most gap minima in one
row of the table, and the most loaded patches on the left leading wheel.

Profiles: two rippled S1002 treads (``rippled``: at most four and seven gap minima after the
table's smoothing) and the Minuetto's motor and trailer wheels worn by the whole-vehicle loop
(``vehicle_wear_simulation``, every trip forward with --forward-share 1.0, on the example
fleet's Aosta route, D_step --step) to each --km, the mean profile of each bogie type.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from wearcast.physics import curving as cv
from wearcast.physics import vehicle_wear_simulation as vehicle_wear
from wearcast.physics.bogie_equations import bogie_residual, compiled_residual, initial_state
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicles import vehicle_preset

ROOT = Path(__file__).resolve().parents[1]
#: The rippled treads: amplitude [mm], wavelength [mm], wheel y range [mm].
RIPPLED = {"rippled, 4 minima": (0.1, 7.0, 0.0, 40.0),
           "rippled, 7 minima": (0.3, 6.0, -20.0, 40.0)}
EQUATIONS = ("F_y lead", "M_z lead", "pitch lead", "Q_left lead", "Q_right lead", "F_y trail",
             "M_z trail", "pitch trail", "Q_left trail", "Q_right trail", "F_y bogie",
             "M_z bogie")


def rippled(amplitude_mm: float, wavelength_mm: float, lo_mm: float, hi_mm: float
            ) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """S1002 with a cosine ripple on wheel y lo..hi [mm] (3 mm ramps at both ends): after the
    contact table's 2 mm smoothing, a tread with several gap minima, like a loop-worn one."""
    def height(y: NDArray[np.float64]) -> NDArray[np.float64]:
        y = np.asarray(y, dtype=float)
        window = np.clip((y - lo_mm) / 3.0, 0.0, 1.0) * np.clip((hi_mm - y) / 3.0, 0.0, 1.0)
        return s1002_height_mm(y) + amplitude_mm * window * np.cos(
            2.0 * np.pi * (y - lo_mm) / wavelength_mm)
    return height


def largest_jump(f: Callable[[NDArray[np.float64]], NDArray[np.float64]], x0: float,
                 x1: float, n: int = 4001, candidates: int = 40) -> tuple[float, float, int]:
    """The largest increment of f (vector valued, (m,) -> (m, k)) left after bisecting the
    sweep's steepest and most isolated steps down to 1e-12, where it is and in which
    component: a discontinuity keeps its size, a continuous function's increment vanishes."""
    x = np.linspace(x0, x1, n)
    v = f(x)
    inc = np.max(np.abs(np.diff(v, axis=0)), axis=1)
    neighbours = np.array([np.median(inc[max(0, k - 5):k + 6]) for k in range(inc.size)])
    picks = set(np.argsort(inc)[-candidates:].tolist()) | set(
        np.argsort(inc / (neighbours + 1e-300))[-candidates:].tolist())
    worst = (0.0, float("nan"), -1)
    for k in sorted(picks):
        a, b, va, vb = x[k], x[k + 1], v[k], v[k + 1]
        while b - a > 1e-12:
            m = 0.5 * (a + b)
            vm = f(np.array([m]))[0]
            if np.max(np.abs(vm - va)) > np.max(np.abs(vb - vm)):
                b, vb = m, vm
            else:
                a, va = m, vm
        d = np.abs(vb - va)
        worst = max(worst, (float(np.max(d)), float(a), int(np.argmax(d))))
    return worst


def minima_per_row(table: cv.ContactTable) -> int:
    """The most interior minima in one row of the table's gap."""
    g = table.gap_mm
    inner = g[:, 1:-1]
    return int(np.max(np.sum((inner < g[:, :-2]) & (inner <= g[:, 2:]), axis=1)))


def sweep(kind: str, height: Callable[[NDArray[np.float64]], NDArray[np.float64]]
          ) -> list[tuple[float, float, float, str, int, int]]:
    """Per left-wheel approach offset: (offset, jump, shift, equation, minima, loaded)."""
    vehicle = vehicle_preset("minuetto", kind)
    table = cv.build_contact_table(height, vehicle.rail_profile, vehicle.rail_inclination,
                                   vehicle.wheel_radius_m)
    q0 = initial_state(vehicle, table)
    n_min = minima_per_row(table)
    rows = []
    for offset in (0.0, 0.1, 0.3):
        def states(y: NDArray[np.float64], offset: float = offset) -> NDArray[np.float64]:
            q = np.repeat(q0[None], np.size(y), axis=0)
            q[:, 0] = y
            q[:, 3] += offset
            return q

        def residual(y: NDArray[np.float64], states=states) -> NDArray[np.float64]:
            return compiled_residual(states(y), vehicle, table, 0.0, 0.0, 0.0)

        jump, where, eq = largest_jump(residual, -12.0, 12.0, n=12001)
        _, c = bogie_residual(states(np.linspace(-12.0, 12.0, 1201)), vehicle, table, 0.0,
                              0.0, 0.0, return_contacts=True)
        loaded = int(np.max(np.sum(c.normal_force_n[:, 0, 0] > 0, axis=-1)))
        rows.append((offset, jump, where, EQUATIONS[eq] if eq >= 0 else "-", n_min, loaded))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--km", type=float, nargs="*", default=[2000.0, 4000.0, 8000.0],
                        help="loop mileages [km] (none: rippled treads only)")
    parser.add_argument("--forward-share", type=float, default=1.0)
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    args = parser.parse_args()
    profiles: list[tuple[str, str, Callable]] = [
        (name, "trailer", rippled(*p)) for name, p in RIPPLED.items()]
    if args.km:
        routes = json.loads((ROOT / "service" / "example_fleet" / "routes.json").read_text())
        classes = next(r for r in routes if r["name"] == "aosta")["classes"]
        options = vehicle_wear.VehicleWearOptions(forward_share=args.forward_share)
        sim = None
        for km in sorted(args.km):
            t0 = time.process_time()
            sim = vehicle_wear.simulate_vehicle_wear("minuetto", classes, mileage_km=km,
                                                     depth_per_step_mm=args.step,
                                                     options=options, continue_from=sim)
            print(f"loop to {km:,.0f} km (forward share {args.forward_share:g}, D_step "
                  f"{args.step:g} mm): {sim.contact_fallbacks} class fallbacks, "
                  f"{time.process_time() - t0:.1f} s CPU")
            for b, label in enumerate(sim.wheels[::4]):
                kind = "motor" if label.startswith("motor") else "trailer"
                z = sim.profiles_mm[4 * b:4 * b + 4].mean(axis=0)

                def height(y, y_mm=sim.y_mm, z=z):
                    return np.interp(y, y_mm, z)
                profiles.append((f"loop {km:,.0f} km, {kind}", kind, height))
    print(f"{'profile':<26s} {'offset mm':>9s} {'jump (wheel loads)':>18s} {'at y mm':>9s} "
          f"{'equation':<13s} {'minima':>6s} {'loaded':>6s}")
    for name, kind, height in profiles:
        for offset, jump, where, eq, n_min, loaded in sweep(kind, height):
            print(f"{name:<26s} {offset:9.1f} {jump:18.2e} {where:9.4f} {eq:<13s} "
                  f"{n_min:6d} {loaded:6d}")


if __name__ == "__main__":
    main()
