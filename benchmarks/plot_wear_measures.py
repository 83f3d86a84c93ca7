"""Pictures of the curving model and the seed findings it reproduces, written to docs/img/.

Run: ``.venv/bin/python benchmarks/plot_wear_measures.py``

* ``curving_wheelsets.png``: wheelset shifts and yaw angles over the radius (Manchester
  vehicle, trailer bogie, cant 100 mm, a_nc = 0.58 m/s^2) and the flange-contact radius.
* ``wear_measures_seed001_fig10.png``: tau_max and T-gamma of the leading wheelset over the
  signed curvature (negative: wheel on the high rail, positive: low rail), tread and flange,
  motor and trailer bogies, like seed 001 Fig. 10.
* ``wear_measures_seed004_fig6.png``: Krause-Poll and KTH/Archard wear rates of the leading
  high-rail wheel over radii 200-2000 m with speeds from an unbalanced-acceleration limit
  (0.8 m/s^2, cant 150 mm, 200 km/h), and the wear regimes, like seed 004 Fig. 6.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from wearcast.physics import curving  # noqa: E402
from wearcast.physics.vehicles import vehicle_preset  # noqa: E402
from wearcast.physics.wear_tables import wear_table_for_route  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "docs" / "img"


def _save(fig: Any, name: str) -> Path:
    """Lay out, write ``OUT / name`` (120 dpi) and close the figure; the file's path."""
    fig.tight_layout()
    path = OUT / name
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_curving() -> Path:
    vehicle = vehicle_preset("manchester", "trailer")
    radii = np.geomspace(150.0, 5000.0, 30)
    cases = [curving.curve_case(float(r), 100.0) for r in radii]
    results = curving.solve_curving_cases(vehicle, cases, fastsim_grid=4)
    shift = np.array([r.wheelset_shift_mm for r in results])
    yaw = np.array([r.wheelset_yaw_rad for r in results]) * 1e3
    r_flange = curving.flange_contact_radius_m(vehicle, cant_mm=100.0)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for k, label in enumerate(("axle 1 (leading)", "axle 2 (trailing)")):
        axes[0].semilogx(radii, shift[:, k], label=label)
        axes[1].semilogx(radii, yaw[:, k], label=label)
    for ax in axes:
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xticks([200, 500, 1000, 2000, 5000])
        ax.axvline(r_flange, color="grey", ls=":", label=f"flange contact below {r_flange:.0f} m")
        ax.set_xlabel("curve radius [m] (left curve)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("lateral shift [mm] (+ left, towards the low rail)")
    axes[1].set_ylabel("yaw relative to the track [mrad]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Quasi-static curving, Manchester vehicle (trailer bogie), S1002/60E1 1:40, "
                 "cant 100 mm, a_nc 0.58 m/s²", fontsize=9)
    return _save(fig, "curving_wheelsets.png")


def plot_fig10() -> Path:
    radii = [None, 200.0, 300.0, 500.0, 700.0, 1000.0, 1500.0, 2500.0, 4000.0]
    cant = [0.0] + [float(min(150.0, 30_000.0 / r)) for r in radii[1:]]
    table = wear_table_for_route("manchester", radii, cant_mm=cant)
    lead = table[table.wheelset == "leading"]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for col, measure in enumerate(("tau_max", "t_gamma")):
        for row, region in enumerate(("tread", "flange")):
            ax = axes[row, col]
            for bogie, marker in (("motor", "o"), ("trailer", "s")):
                part = lead[(lead.bogie_type == bogie) & (lead.region == region)
                            & (lead.measure == measure)]
                curv = np.where(part.rail == "high", -1e3 / part.radius_m,
                                np.where(part.rail == "low", 1e3 / part.radius_m, 0.0))
                order = np.argsort(curv)
                ax.plot(curv[order], part["value"].to_numpy()[order], marker=marker,
                        label=bogie)
            ax.set_title(f"{region}: {measure}", fontsize=9)
            ax.grid(True, alpha=0.3)
            ax.set_ylabel("MPa" if measure == "tau_max" else "N")
    for ax in axes[1]:
        ax.set_xlabel("curvature 1000/R [1/km]  (- high rail, + low rail, 0 tangent)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Leading wheelset wear measures over curvature (cf. seed 001 Fig. 10): "
                 "flange measures vanish on tangent track and grow as the radius falls",
                 fontsize=9)
    return _save(fig, "wear_measures_seed001_fig10.png")


def plot_fig6() -> Path:
    radii = list(np.arange(200.0, 2001.0, 100.0))
    _, contacts = wear_table_for_route("manchester", radii, cant_mm=150.0, max_speed_kmh=200.0,
                                       unbalanced_acceleration_m_s2=0.8, with_contacts=True)
    wheel = contacts[(contacts.bogie_type == "trailer") & (contacts.wheelset == "leading")
                     & (contacts.rail == "high") & contacts.in_contact]
    per = wheel.groupby(["radius_m", "region"]).agg(
        kp=("krause_poll_wear_rate_mm3_per_m", "sum"),
        archard=("archard_wear_rate_mm3_per_m", "sum"), zone=("archard_zone", "max"),
        kp_severe=("krause_poll_regime", lambda s: bool((s == "severe").any())),
        speed=("speed_kmh", "first")).reset_index()
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for col, (law, label) in enumerate((("archard", "KTH/Archard"), ("kp", "Krause-Poll"))):
        for region, marker in (("flange", "o"), ("tread", "s")):
            part = per[per.region == region]
            axes[0, col].plot(part.radius_m, part[law], marker=marker, ls="", label=region)
            regime = part.zone if law == "archard" else np.where(part.kp_severe, 2, 1)
            axes[1, col].plot(part.radius_m, regime, marker=marker, ls="", label=region)
        axes[0, col].set_title(f"{label} wear rate, leading high-rail wheel", fontsize=9)
        axes[0, col].set_ylabel("worn volume [mm³/m]")
        axes[1, col].set_yticks([1, 2, 3, 4] if law == "archard" else [1, 2])
        axes[1, col].set_yticklabels(["mild 1", "severe", "mild 2", "seizure"]
                                     if law == "archard" else ["mild", "severe"])
        axes[1, col].set_xlabel("curve radius [m]")
        for ax in axes[:, col]:
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8)
    fig.suptitle("Wear rate and regime over the radius, speeds from a_nc = 0.8 m/s², cant "
                 "150 mm, max 200 km/h (cf. seed 004 Fig. 6)", fontsize=9)
    return _save(fig, "wear_measures_seed004_fig6.png")


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for make in (plot_curving, plot_fig10, plot_fig6):
        print(make())


if __name__ == "__main__":
    main()
