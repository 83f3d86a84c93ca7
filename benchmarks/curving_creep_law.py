"""Creep law of the curving equilibrium: FASTSIM (default) against the saturation law.

For the Manchester and Minuetto bogies over radii 150-5000 m (cant falling with the radius,
a_nc = 0.58 m/s^2) the equilibrium is solved with FASTSIM's forces (16 x 16, the default)
and with the Shen-Hedrick-Elkins law; printed: the largest change of the leading wheelset's
shift [mm] and yaw [mrad], of the creep forces [mu Fn] and of T-gamma and tau_max, and the
accuracy of the 16 x 16 grid against 40 x 40 at the equilibrium ([mu Fn]). Timing of both
solves on this machine (one run, ratio).

Run: ``.venv/bin/python benchmarks/curving_creep_law.py``
"""

from __future__ import annotations

import time

import numpy as np

from wearcast.physics import curving
from wearcast.physics.contact.fastsim import fastsim_forces
from wearcast.physics.vehicles import vehicle_preset


def main() -> None:
    radii = np.geomspace(150.0, 5000.0, 15)
    cant = np.interp(np.log(radii), np.log([150.0, 5000.0]), [150.0, 20.0])
    for preset in ("manchester", "minuetto"):
        vehicle = vehicle_preset(preset, "trailer")
        cases = [curving.curve_case(float(r), float(c), None, "left", 0.58)
                 for r, c in zip(radii, cant, strict=True)]
        curving.solve_curving_cases(vehicle, cases[:1])  # warm the caches
        t0 = time.perf_counter()
        fs = curving.solve_curving_cases(vehicle, cases)
        t_fs = time.perf_counter() - t0
        t0 = time.perf_counter()
        she = curving.solve_curving_cases(vehicle, cases, creep_grid=None)
        t_she = time.perf_counter() - t0
        d_shift = max(abs(a.wheelset_shift_mm[0] - b.wheelset_shift_mm[0])
                      for a, b in zip(fs, she, strict=True))
        d_yaw = max(abs(a.wheelset_yaw_rad[0] - b.wheelset_yaw_rad[0]) * 1e3
                    for a, b in zip(fs, she, strict=True))
        tg = [(a.t_gamma_n.sum(axis=-1), b.t_gamma_n.sum(axis=-1)) for a, b in zip(fs, she,
                                                                              strict=True)]
        rel_tg = max(float(np.max(np.abs(x - y) / np.maximum(np.abs(x), 1.0))) for x, y in tg)
        tau = [(a.tau_max_mpa.max(axis=-1), b.tau_max_mpa.max(axis=-1))
               for a, b in zip(fs, she, strict=True)]
        rel_tau = max(float(np.max(np.abs(x - y) / np.maximum(x, 1.0))) for x, y in tau)
        grid_err = 0.0
        for res in fs:
            on = res.in_contact
            args = (res.xi[on], res.eta[on], res.phi_per_mm[on], res.a_mm[on], res.b_mm[on],
                    res.normal_force_n[on], vehicle.friction)
            fine = fastsim_forces(*args, n_x=40, n_y=40)
            coarse = fastsim_forces(*args, n_x=curving.DEFAULT_CREEP_GRID,
                                    n_y=curving.DEFAULT_CREEP_GRID)
            mu_fn = vehicle.friction * res.normal_force_n[on]
            err = np.hypot(fine.fx_n - coarse.fx_n, fine.fy_n - coarse.fy_n) / mu_fn
            grid_err = max(grid_err, float(err.max()))
        print(f"{preset:<10s} {len(cases)} radii: FASTSIM vs saturation law: leading shift "
              f"{d_shift:.2f} mm, yaw {d_yaw:.2f} mrad, T-gamma per wheel {100 * rel_tg:.0f} %, "
              f"tau_max {100 * rel_tau:.0f} % (max)")
        print(f"{'':<10s} FASTSIM {curving.DEFAULT_CREEP_GRID}x{curving.DEFAULT_CREEP_GRID} vs "
              f"40x40 at the equilibrium: {grid_err:.3f} mu Fn (max); solve {t_fs:.2f} s vs "
              f"{t_she:.2f} s with the saturation law (x{t_fs / t_she:.1f})")


if __name__ == "__main__":
    main()
