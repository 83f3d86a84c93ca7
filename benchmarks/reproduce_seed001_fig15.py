"""Seed 001 Fig. 15: does 100 % tangent track raise the tread wear of a calibrated hybrid model?

Seed 001 §5 applies its calibrated model (same c_s) to a route of 100 % tangent track and finds
the flange wear gone and "a significant increase in tread wear". The hybrid model's rate of a
region is c_s times the route's weighted wear measure P = sum_i c_i P_i (seed 001 eqs. 2-3), so
c_s cancels in the ratio P_tread(tangent) / P_tread(curved route) — that ratio above 1 is the
seed's claim. It is computed here for three wear measures on the same curve-radius table:

* ``tau_max`` (FASTSIM's maximum surface shear traction, wearcast's default),
* ``t_gamma`` (frictional work per metre),
* ``tau_max`` as seed 001 eq. 5 prints it, p0 / mu_eff (``wear_measures.tau_max_p0_over_mu_eff``),
  which diverges as mu_eff -> 0; tangent track rolls nearly freely.

Vehicle: the Manchester preset (motor and trailer bogies; the seed's train is not described
beyond its bogies), S1002 on 60E1 1:40, friction 0.35 and class speeds from a_nc = 0.58 m/s^2 as
in seed 001 §4; curved routes: seed 003's Aosta line (Table 3) and seed 000's metro lines
(Table 1). Averages over bogie types, both axles and both sides, running mode ``mixed``.

Run: ``.venv/bin/python benchmarks/reproduce_seed001_fig15.py``
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pandas as pd

from wearcast.physics.vehicles import vehicle_preset
from wearcast.physics.wear_measures import tau_max_p0_over_mu_eff
from wearcast.physics.wear_tables import table_from_contacts, wear_table_for_route
from wearcast.statistics.generators.twin_routes import aosta_route, metro_route, tangent_route
from wearcast.statistics.route_measure import weighted_wear_measure
from wearcast.statistics.routes import Route

FRICTION = 0.35  # seed 001 §4
POSITIONS = [(b, axle, side) for b in ("motor", "trailer") for axle in (1, 2)
             for side in ("left", "right")]


def _tables(routes: list[Route]) -> dict[str, pd.DataFrame]:
    """One table over every class of ``routes`` (radius, cant; speeds from a_nc), and its
    eq. 5 variant built from the same contacts."""
    classes = {(c.radius_m, c.cant_mm) for r in routes for c in r.classes}
    radii = [r for r, _ in sorted(classes, key=lambda k: (k[0] or np.inf, k[1]))]
    cants = [c for _, c in sorted(classes, key=lambda k: (k[0] or np.inf, k[1]))]
    pair = tuple(dataclasses.replace(vehicle_preset("manchester", b), friction=FRICTION)
                 for b in ("motor", "trailer"))
    table, contacts = wear_table_for_route(pair, radii, cant_mm=cants,  # type: ignore[arg-type]
                                           with_contacts=True)
    eq5 = contacts.copy()
    eq5["tau_max_mpa"] = tau_max_p0_over_mu_eff(eq5["p0_mpa"], eq5["fx_n"], eq5["fy_n"],
                                                eq5["normal_force_n"])
    return {"fastsim": table, "eq5": table_from_contacts(eq5)}


def _mean_measure(route: Route, table: pd.DataFrame, region: str, measure: str) -> float:
    return float(np.mean([
        weighted_wear_measure(route, table, bogie_type=b, axle=axle, side=side,
                              running_mode="mixed", region=region, measure=measure)
        for b, axle, side in POSITIONS]))


def main() -> None:
    start = time.perf_counter()
    curved = [aosta_route(), metro_route()]
    tangent = tangent_route()
    tables = _tables([*curved, tangent])
    print(f"tables built in {time.perf_counter() - start:.1f} s (Manchester preset, "
          f"friction {FRICTION}, S1002 / 60E1 1:40)")
    rows = []
    for label, table_key, measure in (("tau_max (FASTSIM)", "fastsim", "tau_max"),
                                      ("T-gamma", "fastsim", "t_gamma"),
                                      ("tau_max = p0/mu_eff (eq. 5)", "eq5", "tau_max")):
        table = tables[table_key]
        tan_tread = _mean_measure(tangent, table, "tread", measure)
        tan_flange = _mean_measure(tangent, table, "flange", measure)
        for route in curved:
            tread = _mean_measure(route, table, "tread", measure)
            rows.append({"measure": label, "curved route": route.name,
                         "P tread curved": tread, "P tread tangent": tan_tread,
                         "tangent / curved": tan_tread / tread if tread > 0 else np.inf,
                         "P flange tangent": tan_flange})
    with pd.option_context("display.width", 160, "display.float_format", "{:.4g}".format):
        print(pd.DataFrame(rows).to_string(index=False))
    print("seed 001 Fig. 15: tread wear rises on 100 % tangent track (ratio > 1), flange "
          "wear vanishes (P flange tangent = 0)")


if __name__ == "__main__":
    main()
