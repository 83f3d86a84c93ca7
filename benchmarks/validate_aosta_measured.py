"""The wear loop against MEASURED wheels: the Minuetto on the Aosta - Pre Saint Didier line.

Run: .venv/bin/python benchmarks/validate_aosta_measured.py [--km 3600] [--step-km 100]

Seed 003 Table 2 (reference/published/aosta_measured_FH_FT_QR.csv) prints the flange height FH,
flange thickness FT and qR of three ALn 501 Minuetto units (DM061, DM068, DM082), averaged over
all their wheels, at 0-3,537 km after reprofiling: FT and qR fall almost linearly, FH stays at
28 mm. The loop runs the ``minuetto`` preset (seed 003 Table 1 masses, mu = 0.28, UIC60 at 1:20;
ASSUMED stiffnesses) on seed 003's own statistical description of the line (Table 3, n_class =
7, reference/published/aosta_statistical_track_nclass7.csv, both curve directions with half the
share each) with seed 003's wear law (USFD, eq. 1), S1002 new, right wheel of the leading axle,
steps of ``--step-km`` up to ``--km`` (past the last measurement, 3,537 km), each cut into
sub-steps of at most 0.2 mm (seed 003's D_step; at most 5 sub-steps), Sd/Sh/qR per step.
Two patch models (``wear_loop.class_contacts``): ``hertz`` (the curving model's ellipse)
and ``kik_piotrowski`` (lateral semi-axis from the unsmoothed gap: the conformal flange-root
patches widen). Prints simulated vs measured FT/qR/FH at the measured mileages,
the FT and qR loss rates (least squares through the origin, mm per 1,000 km) and writes
docs/img/aosta_measured_vs_loop.png. Needs ../shared/reference (skips when it is absent).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from wearcast.physics.wear_loop import LoopClass, WearSteps, simulate_wear  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT.parent / "shared" / "reference" / "published"
IMG = ROOT / "docs" / "img"


def aosta_classes(table: pd.DataFrame) -> list[LoopClass]:
    """Seed 003 Table 3 as loop classes: each curve class in both directions (half the share)."""
    out = []
    for r in table.itertuples():
        if not np.isfinite(r.R_c_m):
            out.append(LoopClass(None, 0.0, float(r.V_kmh), share=r.p_k_pct / 100.0))
            continue
        for direction in ("left", "right"):
            out.append(LoopClass(float(r.R_c_m), float(r.H_mm), float(r.V_kmh), direction,
                                 r.p_k_pct / 200.0))
    return out


def loss_rate_per_1000_km(km: np.ndarray, loss_mm: np.ndarray) -> float:
    """Least-squares slope through the origin [mm per 1,000 km]."""
    return float(np.sum(km * loss_mm) / np.sum(km * km) * 1000.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--km", type=float, default=3600.0, help="simulated mileage [km]")
    parser.add_argument("--step-km", type=float, default=100.0, help="step [km]")
    args = parser.parse_args()
    measured_csv = REFERENCE / "aosta_measured_FH_FT_QR.csv"
    track_csv = REFERENCE / "aosta_statistical_track_nclass7.csv"
    if not measured_csv.exists() or not track_csv.exists():
        print(f"skipped: {REFERENCE} not found (needs ../shared/reference beside the repo)")
        return
    measured = pd.read_csv(measured_csv, comment="#")
    classes = aosta_classes(pd.read_csv(track_csv, comment="#"))
    n = int(round(args.km / args.step_km))
    steps = WearSteps(mode="fixed", n_steps=n, step_km=args.step_km, max_depth_per_step_mm=0.2,
                      max_substeps=5)
    sims = {}
    for patch in ("hertz", "kik_piotrowski"):
        t0 = time.perf_counter()
        sims[patch] = simulate_wear("minuetto", classes, law="usfd", steps=steps,
                                    patch_width=patch)
        s = sims[patch]
        print(f"{patch}: {n} steps to {s.mileage_km[-1]:.0f} km in "
              f"{time.perf_counter() - t0:.1f} s,"
              f" {s.contact_updates} contact updates, {s.contact_fallbacks} fallbacks; max depth "
              f"{s.wear_mm[-1].max():.2f} mm at y = {s.y_mm[np.argmax(s.wear_mm[-1])]:.1f} mm")
    km = measured.distance_km.to_numpy(float)
    reach = min(float(s.mileage_km[-1]) for s in sims.values())
    if reach < km.max():
        print(f"note: the runs reach {reach:.0f} km; measured points beyond are compared with "
              "the last simulated value (more --steps to cover them)")
    rows = measured.copy()
    for patch, s in sims.items():
        for col, series in (("FT", s.sd_mm), ("QR", s.qr_mm), ("FH", s.sh_mm)):
            rows[f"{col}_{patch}"] = np.interp(km, s.mileage_km, series)
    pd.set_option("display.width", 200)
    print("measured (seed 003 Table 2) vs simulated at the measured mileages [mm]:")
    cols = ["vehicle", "distance_km", "FT_mm", "FT_hertz", "FT_kik_piotrowski", "QR_mm",
            "QR_hertz", "QR_kik_piotrowski", "FH_mm", "FH_hertz", "FH_kik_piotrowski"]
    print(rows[cols].to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    moving = (km > 0) & (km <= reach)
    for col, nominal in (("FT", 32.5), ("QR", 10.8)):
        meas = loss_rate_per_1000_km(km[moving], nominal - rows[f"{col}_mm"].to_numpy()[moving])
        sim = {p: loss_rate_per_1000_km(km[moving], nominal - rows[f"{col}_{p}"].to_numpy()[
            moving]) for p in sims}
        print(f"{col} loss rate [mm/1000 km]: measured {meas:.2f}; hertz {sim['hertz']:.2f}; "
              f"kik_piotrowski {sim['kik_piotrowski']:.2f}")
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    for ax, (col, sim_attr, label) in zip(axes, (("FT_mm", "sd_mm", "FT (Sd)"),
                                                 ("QR_mm", "qr_mm", "qR"),
                                                 ("FH_mm", "sh_mm", "FH (Sh)")), strict=True):
        for vehicle, group in measured.groupby("vehicle"):
            ax.plot(group.distance_km, group[col], "o", label=f"measured {vehicle}")
        for patch, style in (("hertz", "--"), ("kik_piotrowski", "-")):
            ax.plot(sims[patch].mileage_km, getattr(sims[patch], sim_attr), style,
                    label=f"loop, {patch}")
        ax.set_xlabel("mileage since reprofiling [km]")
        ax.set_ylabel(f"{label} [mm]")
    axes[0].legend(fontsize=7)
    fig.suptitle("Minuetto on Aosta - Pre Saint Didier: seed 003 Table 2 measurements vs the "
                 "wear loop (USFD law, seed 003 Table 3 classes)")
    fig.tight_layout()
    IMG.mkdir(parents=True, exist_ok=True)
    fig.savefig(IMG / "aosta_measured_vs_loop.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
