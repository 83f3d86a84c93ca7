"""The curving model's contacts from the one contact pipeline, at the curving's wheelset poses.

The quasi-static curving (``curving``) finds its equilibrium with a fast tabulated contact model
(``curving_table``: the smoothed vertical gap, elastic approach taken vertically, Hertz). Its
reported contact state -- where the wheel touches the rail, the contact angle, the patches,
their normal and creep forces, creepages and the wear measures -- comes from the contact
pipeline of ``contact.pose_contact`` (the one checked against CONTACT's Manchester results:
locus -> patches merged or split by the interpenetration region -> non-Hertzian normal contact
-> FASTSIM) evaluated at the curving's pose of each wheel: the wheelset's centre shift, yaw,
roll, rolling ratio, the track curvature and the wheel's vertical load -- the table's
equilibrium pose, or the equilibrium of the pipeline's own forces
(``pipeline_equilibrium.pipeline_force_equilibrium``).
At the table's pose on a flange the table loads the gap minimum near the root (contact angle
30-50 deg) where the pipeline's patch lies up the flank (66-70 deg), and the pipeline's forces
do not balance the state; at the equilibrium of the pipeline's forces (a smaller roll) its
flange patch is centred on the root too, within 0.11-0.53 mm of the table's at 250-600 m
(``benchmarks/curving_flange_vs_geometry.py``); at 150 and 200 m, where Broyden's method did not
find that equilibrium, the homotopy of ``pipeline_force_equilibrium`` does: flange patch at
wheel y -35.4 to -36.0 mm, 47.7-50.8 deg (``tests/physics/test_pipeline_force_equilibrium.py``).

Conventions: the pipeline reports each wheel in its own frame with CONTACT's signs (forces on
the rail, creepages rail minus wheel, delta < 0 on tread and flange); the curving reports
forces on the wheel and creepages wheel minus rail, with the contact angle positive when it
pushes the wheel towards the track centre. So the curving's angle, creepages and creep forces
are the pipeline's negated; F_s (in the contact plane, towards the field side) is the
curving's F_y.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_equations import BogieContacts
from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.contact.pose_contact import Pose, PoseContact, contact_at_poses
from wearcast.physics.contact_candidates_kernel import N_SLOTS
from wearcast.physics.vocabulary import SIDES

#: Fields of :class:`PipelineContacts`, each (cases, 2 wheelsets, 2 sides, slots): the bogie
#: equations' per-contact quantities (``BogieContacts``) and the peak pressure.
PATCH_FIELDS = (*(f.name for f in fields(BogieContacts)), "peak_pressure_mpa")


class PipelineContactError(RuntimeError):
    """The contact pipeline failed at a curving pose (the wheel cannot touch its rail, more
    patches than slots, or the normal / tangential coupling did not settle)."""


@dataclass(frozen=True)
class PipelineContacts(BogieContacts):
    """Per-patch arrays (cases, 2 wheelsets, 2 sides (left, right), ``N_SLOTS``), field side
    first, unused slots zero (curving's signs, module docstring): normal force [N], contact
    angle [rad], patch centre on the wheel [mm] (pressure centre), on the rail (the curving
    table's rail frame) [mm], its distance from the track centre line [mm], rolling radius [m],
    creepages xi, eta [-], phi [1/mm], creep forces Fx, Fy [N], spin moment Mz [N mm],
    equivalent ellipse a, b [mm], peak pressure [MPa]; ``ok`` (cases,) whether every wheel of
    the case was solved; ``errors`` the message per failed case."""

    peak_pressure_mpa: NDArray
    ok: NDArray
    errors: dict[int, str]


def _fill(out: dict[str, NDArray], index: tuple[int, int, int], pc: PoseContact, sign: float,
          rail_origin_mm: float) -> None:
    patches = pc.loaded.patches
    if len(patches) > N_SLOTS:
        raise PipelineContactError(f"{len(patches)} patches on one wheel, more than the "
                                   f"{N_SLOTS} slots of the curving result")
    for k, p in enumerate(patches):
        n = p.normal
        lateral = sign * n.centre_y_track_mm
        values = {
            "normal_force_n": n.normal_force_n, "contact_angle_rad": -n.contact_angle_rad,
            "wheel_y_mm": n.centre_y_wheel_mm, "rail_y_mm": lateral - rail_origin_mm,
            "lateral_position_mm": lateral,
            "rolling_radius_m": n.region.rolling_radius_mm / 1000.0,
            "xi": -p.xi, "eta": -p.eta, "phi_per_mm": -p.phi_per_mm, "fx_n": -p.fx_n,
            "fy_n": -p.fs_n, "mz_nmm": -p.mz_nmm, "a_mm": n.a_mm, "b_mm": n.b_mm,
            "peak_pressure_mpa": n.peak_pressure_mpa,
        }
        for name, v in values.items():
            out[name][index + (k,)] = v


def pipeline_contacts(track: WheelsetTrack, rail_origin_mm: float | tuple[float, float],
                      shift_mm: NDArray,
                      yaw_rad: NDArray, roll_rad: NDArray, rolling_ratio: NDArray,
                      wheel_load_n: NDArray, curvature_per_m: NDArray, mu: float,
                      shear_modulus_mpa: float, creep_grid: int) -> PipelineContacts:
    """The pipeline's contacts of every wheel of every case at the curving's poses.

    Parameters
    ----------
    track : the wheelset on its track (``curving_table.ContactTable.track``)
    rail_origin_mm : distance of the curving table's rail-frame origin from the track centre
        [mm] (rail y = distance from the centre line - origin); a (left, right) pair when the
        two rails are profiles of their own (``ContactTable.side``)
    shift_mm, yaw_rad, roll_rad, rolling_ratio : (cases, 2 wheelsets) wheelset centre shift
        [mm] (+ left), yaw [rad] (+ nose left), roll [rad] (+ left wheel up), Omega r0 / V
    wheel_load_n : (cases, 2 wheelsets, 2 sides) vertical wheel loads [N]
    curvature_per_m : (cases,) track curvature [1/m], + to the left
    mu, shear_modulus_mpa : friction coefficient, G [MPa]
    creep_grid : FASTSIM grid n (n x n) of the pipeline's creep forces

    Returns
    -------
    PipelineContacts; a case whose pipeline fails at any of its wheels has ``ok`` False and
    its message in ``errors`` (never a silent substitute).
    """
    n_cases = shift_mm.shape[0]
    shape = (n_cases, 2, 2, N_SLOTS)
    out = {name: np.zeros(shape) for name in PATCH_FIELDS}
    ok = np.ones(n_cases, dtype=bool)
    errors: dict[int, str] = {}
    origins = ((rail_origin_mm, rail_origin_mm) if isinstance(rail_origin_mm, (int, float))
               else (float(rail_origin_mm[0]), float(rail_origin_mm[1])))
    for s_idx, side in enumerate(SIDES):
        sign = 1.0 if side == "left" else -1.0
        keys = [(c, w) for c in range(n_cases) for w in range(2)]
        poses = [Pose(float(shift_mm[c, w]), float(yaw_rad[c, w]), float(roll_rad[c, w]),
                      float(wheel_load_n[c, w, s_idx]), float(rolling_ratio[c, w]),
                      float(curvature_per_m[c])) for c, w in keys]

        def solve(ps: list[Pose], side: str = side) -> list[PoseContact]:
            # creepages are velocity ratios: V cancels with the rolling ratio and curvature
            return contact_at_poses(track, side, ps, speed_m_s=1.0, mu=mu,
                                    shear_modulus_mpa=shear_modulus_mpa, method="auto",
                                    n_grid=creep_grid, bound="parabolic")

        try:
            results: list[PoseContact | None] = list(solve(poses))
        except (ValueError, RuntimeError):
            # find the failing poses one by one; the others keep their contacts
            results = []
            for (c, _), pose in zip(keys, poses, strict=True):
                try:
                    results.append(solve([pose])[0])
                except (ValueError, RuntimeError) as err:
                    results.append(None)
                    ok[c] = False
                    errors.setdefault(c, f"{side} wheel: {err}")
        for (c, w), pc in zip(keys, results, strict=True):
            if pc is None:
                continue
            try:
                _fill(out, (c, w, s_idx), pc, sign, origins[s_idx])
            except PipelineContactError as err:
                ok[c] = False
                errors.setdefault(c, f"{side} wheel: {err}")
    return PipelineContacts(**out, ok=ok, errors=errors)
