"""The whole-vehicle wear loop against MEASURED wheels: the Minuetto on Aosta - Pre Saint Didier.

Run: .venv/bin/python benchmarks/validate_aosta_measured.py [--km 3600] [--first-step 0.8]
     [--halvings 2] [--patch-width hertz] [--gap-smoothing masked [--rail-edge-ramp-mm 3]]
     [--flange-wear-factor F --wear-scale C]

Seed 003 Table 2 (reference/published/aosta_measured_FH_FT_QR.csv) prints FH, FT and qR of
three ALn 501 Minuetto units (DM061, DM068, DM082), each AVERAGED OVER ALL ITS WHEELS, at
0-3,537 km after reprofiling. Like for like, the simulation covers the whole vehicle
(``physics.vehicle_wear_simulation``): two motor and two trailer bogies (seed 003 §3), every
axle and side, both running directions (the unit reverses at the termini: half the mileage
each way), averaged over all wheels. Route: seed 003's own statistical description (Table 3,
n_class = 7, reference/published/aosta_statistical_track_nclass7.csv, both curve directions
with half the share each); law: seed 003's USFD (eq. 1), wheel loses the full volume (seed 003
§4.2); S1002 new; the ``minuetto`` preset (seed 003 Table 1 masses, mu = 0.28; ASSUMED
stiffnesses). Step convergence (``physics.step_convergence``): D_step = --first-step, halved
up to --halvings times until FT and qR at --km change by < 2 % of their loss. Prints the time
of every run, the comparison per point, per vehicle and per quantity, and writes
docs/img/aosta_measured_vs_loop.png (the model as is only). ``--flange-wear-factor`` and
``--wear-scale`` run an extended model the same way, e.g. the physics diagnosis's verdict
(``benchmarks/diagnose_aosta_physics.py``). Needs ../shared/reference (skips when it is absent).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from wearcast.physics import gap_smoothing as gs  # noqa: E402
from wearcast.physics.step_convergence import converge_steps  # noqa: E402
from wearcast.physics.vehicle_wear_simulation import (  # noqa: E402
    VehicleWearOptions,
    simulate_vehicle_wear,
)
from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics.generators.scenarios import seed003_classes  # noqa: E402
from wearcast.statistics.physics_comparison import compare_with_measured  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: The default contact-table smoothing (``physics/gap_smoothing.py``), read before the options.
_DEFAULT_TABLE = (gs.GAP_SMOOTHING, gs.RAIL_EDGE_RAMP_MM)
REFERENCE = ROOT.parent / "shared" / "reference" / "published"
IMG = ROOT / "docs" / "img"


def aosta_classes(table: pd.DataFrame) -> list[CurveClass]:
    """Seed 003 Table 3 as loop classes (``scenarios.seed003_classes``)."""
    return seed003_classes(table)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--km", type=float, default=3600.0, help="simulated mileage [km]")
    parser.add_argument("--first-step", type=float, default=0.8, help="first D_step [mm]")
    parser.add_argument("--halvings", type=int, default=2, help="at most this many halvings")
    parser.add_argument("--patch-width", default="hertz")
    parser.add_argument("--flange-wear-factor", type=float, default=1.0,
                        help="factor on the wear of flange patches (VehicleWearOptions)")
    parser.add_argument("--wear-scale", type=float, default=1.0,
                        help="wear-coefficient scale (VehicleWearOptions)")
    parser.add_argument("--gap-smoothing", default=gs.GAP_SMOOTHING,
                        choices=gs.GAP_SMOOTHING_METHODS,
                        help="how the contact table's gap is smoothed (physics/gap_smoothing.py); "
                             "the picture is written only with the default")
    parser.add_argument("--rail-edge-ramp-mm", type=float, default=gs.RAIL_EDGE_RAMP_MM,
                        help="width of the masked smoothing's coverage ramp inside the rail's "
                             "ends [mm] (physics/gap_smoothing.py; 3: the loop-robust opt-in)")
    args = parser.parse_args()
    if not args.rail_edge_ramp_mm > 0:
        parser.error("--rail-edge-ramp-mm must be positive")
    gs.GAP_SMOOTHING = args.gap_smoothing
    gs.RAIL_EDGE_RAMP_MM = args.rail_edge_ramp_mm
    measured_csv = REFERENCE / "aosta_measured_FH_FT_QR.csv"
    track_csv = REFERENCE / "aosta_statistical_track_nclass7.csv"
    if not measured_csv.exists() or not track_csv.exists():
        print(f"skipped: {REFERENCE} not found (needs ../shared/reference beside the repo)")
        return
    measured = pd.read_csv(measured_csv, comment="#")
    classes = aosta_classes(pd.read_csv(track_csv, comment="#"))
    options = VehicleWearOptions(patch_width=args.patch_width,
                                 flange_wear_factor=args.flange_wear_factor,
                                 wear_scale=args.wear_scale)

    def run(step: float):
        t0 = time.perf_counter()
        sim = simulate_vehicle_wear("minuetto", classes, law="usfd", mileage_km=args.km,
                                    depth_per_step_mm=step, options=options)
        print(f"whole vehicle (8 wheel positions x 4 bogies, both directions), D_step {step:g} "
              f"mm: {len(sim.mileage_km) - 1} steps to {sim.mileage_km[-1]:.0f} km in "
              f"{time.perf_counter() - t0:.1f} s, {sim.contact_updates} bogie contact updates, "
              f"{sim.contact_fallbacks} class fallbacks; FT {sim.mean('sd_mm')[-1]:.3f}, "
              f"qR {sim.mean('qr_mm')[-1]:.3f}, FH {sim.mean('sh_mm')[-1]:.3f} mm", flush=True)
        overall = compare_with_measured(sim, measured).overall
        print(overall.to_string(index=False, float_format=lambda v: f"{v:.2f}"), flush=True)
        return sim

    sim, conv = converge_steps(
        run, lambda s: {"FT": float(s.mean("sd_mm")[-1]), "qR": float(s.mean("qr_mm")[-1])},
        {"FT": 32.502, "qR": 10.796}, args.first_step, max_halvings=args.halvings)
    print("step convergence:", conv.summary())
    comp = compare_with_measured(sim, measured)
    pd.set_option("display.width", 200)
    print("measured (seed 003 Table 2, all wheels averaged) vs simulated (all wheels averaged):")
    print(comp.points.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    print("per vehicle and quantity:")
    print(comp.per_vehicle.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    print("all vehicles:")
    print(comp.overall.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    for ax, (col, q, label) in zip(axes, (("FT_mm", "sd_mm", "FT (Sd)"),
                                          ("QR_mm", "qr_mm", "qR"),
                                          ("FH_mm", "sh_mm", "FH (Sh)")), strict=True):
        for vehicle, group in measured.groupby("vehicle"):
            ax.plot(group.distance_km, group[col], "o", label=f"measured {vehicle}")
        ax.plot(sim.mileage_km, sim.mean(q), "-", label=f"loop, all wheels, D_step "
                f"{conv.steps[-1]:g} mm")
        ax.set_xlabel("mileage since reprofiling [km]")
        ax.set_ylabel(f"{label} [mm]")
    axes[0].legend(fontsize=7)
    fig.suptitle("Minuetto on Aosta - Pre Saint Didier: seed 003 Table 2 (all wheels averaged) "
                 "vs the whole-vehicle loop (USFD, Table 3 classes)")
    fig.tight_layout()
    IMG.mkdir(parents=True, exist_ok=True)
    # the README's picture is the default contact table's and the model as is only
    if ((args.gap_smoothing, args.rail_edge_ramp_mm) == _DEFAULT_TABLE
            and args.flange_wear_factor == 1.0 and args.wear_scale == 1.0):
        fig.savefig(IMG / "aosta_measured_vs_loop.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
