"""Loaded contact of one wheel at given poses, from any wheel and rail: the contact API.

What a user of CONTACT's wheel-rail module asks for: a wheel profile and a rail profile (named,
measured, or read from SIMPACK ``.prw``/``.prr`` files), the rail inclination, and per pose
the wheelset's lateral shift, yaw, roll (prescribed, or solved so that both wheels touch) and
the vertical wheel load; the answer is every contact patch with its reference location,
contact angle, normal and creep forces, creepages, peak pressure and size. The pipeline is
``contact.wheel_rail.loaded_wheel_contact`` (locus -> patches merged or split by the
interpenetration region -> non-Hertzian normal contact -> FASTSIM), the one checked against
CONTACT's Manchester A-2.2 results (README, "Physics core").

Frames and signs: docs/conventions.md and ``contact.wheel_rail`` (per wheel in its own frame,
forces on the rail, F_s towards the wheel's field side).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from wearcast.physics.contact.fastsim import Bound
from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.contact.hertz import STEEL_SHEAR_MODULUS_MPA
from wearcast.physics.contact.locus import wheel_locus
from wearcast.physics.contact.wheel_rail import LoadedWheel, loaded_wheel_contact
from wearcast.physics.vocabulary import check_side


@dataclass(frozen=True)
class Pose:
    """One wheelset pose and load.

    shift_mm : lateral shift of the wheelset [mm], positive towards the left rail
    yaw_rad : yaw [rad], positive turning the front to the left
    roll_rad : roll [rad], positive when the left wheel rises; None solves it (both wheels
        touching their rails)
    wheel_load_n : vertical force of the wheel on its rail [N]
    rolling_ratio : axle angular velocity over V / r0 (1: rolling at the nominal radius)
    track_curvature_per_m : curvature of the track [1/m], + to the left (0: tangent track;
        the creepages of a quasi-statically curving wheelset, ``creepages``)
    """

    shift_mm: float
    yaw_rad: float = 0.0
    roll_rad: float | None = None
    wheel_load_n: float = 10_000.0
    rolling_ratio: float = 1.0
    track_curvature_per_m: float = 0.0


@dataclass(frozen=True)
class PoseContact:
    """The loaded contact of one wheel at one pose (``loaded``), with the roll it was solved at
    (``roll_rad``; ``roll_solved`` says whether it was solved or given)."""

    pose: Pose
    roll_rad: float
    roll_solved: bool
    loaded: LoadedWheel

    def to_dict(self) -> dict[str, Any]:
        """Plain numbers per pose and patch (units in the names), field side first."""
        patches = []
        for p in self.loaded.patches:
            n = p.normal
            patches.append({
                "y_wheel_mm": float(n.centre_y_wheel_mm),
                "y_track_mm": float(n.centre_y_track_mm),
                "contact_angle_rad": float(n.contact_angle_rad),
                "normal_force_n": float(n.normal_force_n),
                "fx_n": float(p.fx_n), "fs_n": float(p.fs_n), "mz_nmm": float(p.mz_nmm),
                "xi": float(p.xi), "eta": float(p.eta), "phi_per_mm": float(p.phi_per_mm),
                "peak_pressure_mpa": float(n.peak_pressure_mpa),
                "area_mm2": float(n.area_mm2), "a_mm": float(n.a_mm), "b_mm": float(n.b_mm),
                "normal_method": n.method,
            })
        return {"shift_mm": self.pose.shift_mm, "yaw_rad": self.pose.yaw_rad,
                "roll_rad": self.roll_rad, "roll_solved": self.roll_solved,
                "wheel_load_n": self.pose.wheel_load_n,
                "approach_mm": float(self.loaded.approach_mm),
                "vertical_force_n": self.loaded.vertical_force_n,
                "lateral_force_n": self.loaded.lateral_force_n,
                "n_patches": len(patches), "patches": patches}


def contact_at_poses(track: WheelsetTrack, side: str, poses: Sequence[Pose], *,
                     speed_m_s: float = 2.0, mu: float = 0.3,
                     shear_modulus_mpa: float = STEEL_SHEAR_MODULUS_MPA,
                     poisson: float = 0.28, method: str = "auto", n_grid: int = 40,
                     bound: Bound = "parabolic") -> list[PoseContact]:
    """Loaded contact of the ``side`` wheel of ``track`` at each pose (module docstring).

    Poses with a prescribed roll lower the wheel onto its own rail at that roll (as CONTACT
    treats the wheels one at a time); the others solve the roll with both wheels touching.
    The axle turns at ``rolling_ratio`` V / r0 of each pose (1: no pitch-rate creepage beyond
    the rolling radius difference); the creepages, velocity ratios, do not depend on V.

    Raises ``NoContactError`` (a ``ValueError`` "field: reason") when the wheel cannot touch
    its rail at some pose, ``ValueError`` for bad arguments.
    """
    check_side(side)
    if not poses:
        raise ValueError("poses: at least one pose is needed")
    out: list[PoseContact | None] = [None] * len(poses)
    for solved in (True, False):
        rows = [k for k, p in enumerate(poses) if (p.roll_rad is None) == solved]
        if not rows:
            continue
        shifts = [poses[k].shift_mm for k in rows]
        yaws = np.array([poses[k].yaw_rad for k in rows], dtype=float)
        rolls = None if solved else np.array([poses[k].roll_rad for k in rows], dtype=float)
        locus = wheel_locus(track, shifts, side, yaw_rad=yaws, roll_rad=rolls)
        loads = np.array([poses[k].wheel_load_n for k in rows], dtype=float)
        omegas = (np.array([poses[k].rolling_ratio for k in rows], dtype=float)
                  * speed_m_s * 1000.0 / track.nominal_radius_mm)
        kappas = np.array([poses[k].track_curvature_per_m for k in rows], dtype=float)
        loaded = loaded_wheel_contact(locus, track.nominal_radius_mm, wheel_load_n=loads,
                                      speed_m_s=speed_m_s, angular_velocity_rad_s=omegas,
                                      track_curvature_per_m=kappas, mu=mu,
                                      shear_modulus_mpa=shear_modulus_mpa, poisson=poisson,
                                      method=method, n_grid=n_grid, bound=bound)
        for j, k in enumerate(rows):
            out[k] = PoseContact(poses[k], float(locus.roll_rad[j]), solved, loaded[j])
    return [p for p in out if p is not None]
