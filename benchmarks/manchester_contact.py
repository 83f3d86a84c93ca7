"""Manchester contact benchmark A-2.2: wearcast's loaded contact against CONTACT.

For the 21 cases of ``reference/contact-benchmark/mbench_a22_{left,right}.inp`` (lateral
shift 0-10 mm with yaw 0-24 mrad, 10 kN vertical force per wheel, V = 2000 mm/s with the
case's prescribed pitch rate, G = 82 GPa, nu = 0.28, mu = 0.3) this runs the one contact
pipeline (``physics.contact.pose_contact.contact_at_poses``: locus with the roll solved ->
patches merged or split by the interpenetration region -> non-Hertzian normal contact, method
"auto" -> FASTSIM 40x40, parabolic bound, with the vertical equilibrium
F_n cos delta + F_s sin delta = W) and prints per wheel and per range of shifts (tread
0-4.5 mm, flange root 5-6 mm, flange 6.5-10 mm, by where CONTACT's right wheel touches) the max
and RMS deviation wearcast - CONTACT of the contact position, contact angle, F_n, xi, eta, phi,
F_x, F_s (lateral, in the contact plane), p_max and the lateral track force F_Y; forces also
relative (F_n, p_max to CONTACT's value; creep forces to mu F_n).  Both profile sources of
``manchester_geometry.py`` are run.

Conventions (:func:`in_contact_convention`): CONTACT's (unmirrored) right wheel is our left
wheel at shift +y_ws, yaw +psi, quantity by quantity; CONTACT prints its left wheel in the
track frame, i.e. our right wheel with y_w, delta, eta, phi, F_s and F_Y negated. Patch
quantities are those of the patch carrying the largest normal force (CONTACT reports one patch
per wheel in A-2.2), F_Y and F_Z sums over the patches.

Usage: ``.venv/bin/python benchmarks/manchester_contact.py [path/to/reference]``
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from manchester_geometry import mbench_wheelset  # noqa: E402

from wearcast.physics.contact.geometry import WheelsetTrack, s1002_60e1  # noqa: E402
from wearcast.physics.contact.pose_contact import Pose, PoseContact, contact_at_poses  # noqa: E402

DEFAULT_REFERENCE = Path(__file__).resolve().parents[1].parent / "shared" / "reference"

#: (label, CSV column, relative-to) — relative deviations to |CONTACT's value| ("self") or to
#: mu F_n of CONTACT ("muFn"); None = absolute only.
QUANTITIES = (
    ("y_w [mm]", "ycp_w_mm", None),
    ("delta [rad]", "delta_rad", None),
    ("Fn [N]", "Fn_N", "self"),
    ("xi [-]", "cksi", None),
    ("eta [-]", "ceta", None),
    ("phi [1/mm]", "cphi_per_mm", None),
    ("Fx [N]", "Fx_N", "muFn"),
    ("Fs [N]", "Fs_N", "muFn"),
    ("pmax [MPa]", "pmax_Nmm2", "self"),
    ("FY [N]", "FY_rail_N", "muFn"),
)
REGIMES = (("tread 0-4.5", 0.0, 4.5), ("root 5-6", 5.0, 6.0), ("flange 6.5-10", 6.5, 10.0))
MU = 0.3
#: Columns of :func:`in_contact_convention` (names as the A-2.2 reference CSVs).
CONTACT_COLUMNS = ("ycp_w_mm", "delta_rad", "cksi", "ceta", "cphi_per_mm", "Fn_N", "Fx_N",
                   "Fs_N", "pmax_Nmm2", "FY_rail_N", "FZ_rail_N")


def a22_contacts(wt: WheelsetTrack, shifts_mm: np.ndarray, yaws_rad: np.ndarray,
                 angular_velocity_rad_s: np.ndarray | float | None = None,
                 wheel_load_n: float = 10_000.0, speed_m_s: float = 2.0, mu: float = MU,
                 method: str = "auto") -> dict[str, list[PoseContact]]:
    """The pipeline's contacts of both wheels (``left``, ``right``: ours) at the A-2.2 poses,
    roll solved, the axle at the given angular velocity [rad/s] (default V / r0)."""
    shifts = np.asarray(shifts_mm, dtype=float)
    yaws = np.broadcast_to(np.asarray(yaws_rad, dtype=float), shifts.shape)
    nominal = speed_m_s * 1000.0 / wt.nominal_radius_mm
    omega = (np.full(shifts.shape, nominal) if angular_velocity_rad_s is None
             else np.broadcast_to(np.asarray(angular_velocity_rad_s, dtype=float), shifts.shape))
    poses = [Pose(float(y), float(p), None, wheel_load_n, float(w / nominal))
             for y, p, w in zip(shifts, yaws, omega, strict=True)]
    return {side: contact_at_poses(wt, side, poses, speed_m_s=speed_m_s, mu=mu, method=method)
            for side in ("left", "right")}


def in_contact_convention(contacts: dict[str, list[PoseContact]], contact_wheel: str
                          ) -> dict[str, np.ndarray]:
    """Results of one wheel as CONTACT prints them for a wheelset at y_ws = shift, yaw = yaw
    (module docstring); arrays (N,) keyed by ``CONTACT_COLUMNS``."""
    if contact_wheel not in ("left", "right"):
        raise ValueError(f"contact_wheel must be 'left' or 'right', not {contact_wheel!r}")
    ours = contacts["left"] if contact_wheel == "right" else contacts["right"]
    sign = 1.0 if contact_wheel == "right" else -1.0
    rows = []
    for pc in ours:
        p = pc.loaded.dominant
        rows.append((sign * p.normal.centre_y_wheel_mm, sign * p.contact_angle_rad, p.xi,
                     sign * p.eta, sign * p.phi_per_mm, p.normal_force_n, p.fx_n, sign * p.fs_n,
                     p.normal.peak_pressure_mpa, sign * pc.loaded.lateral_force_n,
                     pc.loaded.vertical_force_n))
    table = np.array(rows, dtype=float).reshape(len(rows), len(CONTACT_COLUMNS))
    return {name: table[:, k] for k, name in enumerate(CONTACT_COLUMNS)}


def pitch_rates(inp: Path) -> np.ndarray:
    """|VPITCH| [rad/s] of each case, read from the ``VS,VY,...`` lines of a CONTACT .inp."""
    rows = [line.split() for line in inp.read_text().splitlines() if "VS,VY" in line]
    return np.abs(np.array([float(r[5]) for r in rows]))


def deviations(wt: WheelsetTrack, bench: Path) -> pd.DataFrame:
    """Per case and wheel: CONTACT's value and wearcast - CONTACT for every quantity."""
    frames = []
    right = pd.read_csv(bench / "mbench_a22_right_ref.csv")
    omega = pitch_rates(bench / "mbench_a22_right.inp")
    if not np.allclose(omega, pitch_rates(bench / "mbench_a22_left.inp")):
        raise ValueError("left and right .inp prescribe different pitch rates")
    result = a22_contacts(wt, right["y_ws_mm"].to_numpy(), right["yaw_rad"].to_numpy(), omega)
    for wheel in ("right", "left"):
        ref = pd.read_csv(bench / f"mbench_a22_{wheel}_ref.csv")
        ours = in_contact_convention(result, wheel)
        for label, column, relative in QUANTITIES:
            diff = ours[column] - ref[column].to_numpy()
            if relative == "self":
                rel = diff / np.abs(ref[column].to_numpy())
            elif relative == "muFn":
                rel = diff / (MU * ref["Fn_N"].to_numpy())
            else:
                rel = np.full(diff.shape, np.nan)
            frames.append(pd.DataFrame({"wheel": f"CONTACT {wheel}", "y_ws_mm": ref["y_ws_mm"],
                                        "quantity": label, "ref": ref[column], "dev": diff,
                                        "rel": rel}))
    return pd.concat(frames, ignore_index=True)


def summary(dev: pd.DataFrame) -> pd.DataFrame:
    """Max |dev|, RMS dev and max |relative dev| per wheel, range of shifts and quantity."""
    rows = []
    for (wheel, quantity), group in dev.groupby(["wheel", "quantity"], sort=False):
        for regime, low, high in REGIMES:
            part = group[(group["y_ws_mm"] >= low) & (group["y_ws_mm"] <= high)]
            d, r = part["dev"].to_numpy(), part["rel"].to_numpy()
            rows.append({"wheel": wheel, "quantity": quantity, "shifts": regime,
                         "max_abs": np.max(np.abs(d)), "rms": np.sqrt(np.mean(d**2)),
                         "max_rel": np.nan if np.all(np.isnan(r)) else np.nanmax(np.abs(r))})
    return pd.DataFrame(rows)


def _fmt(v: float) -> str:
    return "-" if not np.isfinite(v) else f"{v:.3g}"


def main(reference: Path = DEFAULT_REFERENCE) -> None:
    bench = reference / "contact-benchmark"
    pd.set_option("display.width", 140)
    cases = (("analytic S1002 / 60E1 1:40", s1002_60e1()),
             ("MBench_S1002_v3.prw / MBench_UIC60_v3.prr", mbench_wheelset(bench)))
    for label, wt in cases:
        table = summary(deviations(wt, bench))
        print(f"\n== {label}: wearcast - CONTACT, A-2.2, 21 cases per wheel ==")
        print("   cells: max |dev| / RMS dev [/ max |rel dev|: Fn, pmax to CONTACT's value; "
              "Fx, Fs, FY to mu Fn]")
        for wheel, part in table.groupby("wheel", sort=False):
            cells = part.assign(cell=[
                f"{_fmt(r.max_abs)} / {_fmt(r.rms)}"
                + ("" if not np.isfinite(r.max_rel) else f" / {r.max_rel:.1%}")
                for r in part.itertuples()])
            grid = cells.pivot(index="quantity", columns="shifts", values="cell")
            grid = grid.loc[[q[0] for q in QUANTITIES], [r[0] for r in REGIMES]]
            print(f"\n-- {wheel} wheel --")
            print(grid.to_string())
    wt = s1002_60e1()
    shifts = np.linspace(-10.0, 10.0, 21)
    a22_contacts(wt, [0.0], [0.0])
    start = time.perf_counter()
    a22_contacts(wt, shifts, 0.0024 * shifts)
    elapsed = time.perf_counter() - start
    print(f"\ncontact pipeline, 21 shifts x 2 wheels: {elapsed * 1e3:.0f} ms")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_REFERENCE)
