"""Normal contact of one wheel on its rail: non-Hertzian patches, BEM or fast, Hertz where valid.

This is the function the curving and wear models call per wheel: ``wheel_normal_contact``
takes a contact locus (``locus.wheel_locus``, roll solved or prescribed) and a vertical
wheel load and returns, per pose, the contact patches (``patches.patch_regions``: merged or
split by the interpenetration region as CONTACT does) with their pressure on a grid, normal
force, reference location, pressure centre, peak pressure and an equivalent ellipse.
``patch_normal_contact`` solves one patch for a given vertical approach.

API for the curving helper
--------------------------
``wheel_normal_contact(locus, wheel_load_n, method="auto", lateral_ratio=None, ...)``
  -> list (one per pose) of ``WheelNormalContact(approach_mm, patches: list[NormalPatch])``.
``NormalPatch`` fields: ``region`` (reference location: ``y_wheel_mm``, ``y_track_mm``,
``x_track_mm``, ``z_rail_mm``, ``contact_angle_rad``, ``rolling_radius_mm``),
``normal_force_n`` [N], ``pressure_mpa`` (n_s, n_x) on the grid ``x_mm`` (rolling, from the
reference) x ``s_mm`` (lateral in the contact plane, towards the wheel's field side, from the
reference), ``peak_pressure_mpa``, ``area_mm2``, ``centre_x_mm``/``centre_s_mm`` (pressure
centre) and ``centre_y_wheel_mm`` (its wheel position), ``a_mm``/``b_mm`` (equivalent
ellipse: b half the lateral extent, a = area / (pi b)), ``method`` used.
``method="auto"`` is the production method (Hertz / coarse BEM, below); "bem" the reference.
``lateral_ratio`` (optional, per pose a list of F_s/F_n per patch from a tangential solution)
enters the vertical equilibrium sum F_n (cos delta + (F_s/F_n) sin delta) = W.

Planar patch problem
--------------------
Each patch is solved in its contact plane (CONTACT's planar approach) on a grid of
``element_mm`` (CONTACT's 0.2 mm) elements: ``patch_plane`` (the gap h(x, s) along the plane
normal at vertical approach d, the grid, the patch's totals).

Methods
-------
"bem": ``normal_bem.solve_normal_bem`` on that grid (Kalker's NORM-type influence
  coefficients, FFT, Polonsky-Keer) with the approach prescribed; the exact solution of the
  half-space problem on the discretised geometry.
"kp": Kik & Piotrowski's fast method with Hertz-consistent virtual penetrations
  (``kik_piotrowski``).
"hertz": one ellipse from the curvatures at the deepest point of the patch
  (``hertz.hertz_contact``; A from the wheel radius, B from the normal gap's second
  derivative along the plane).
"bem-coarse": the BEM on a grid of at most ``COARSE_ELEMENTS`` (24) elements per direction
  over the rigid interpenetration region (never finer than ``element_mm``).
"auto" (the production method): Hertz where the patch really is elliptic, else
  "bem-coarse".  Criterion (``is_elliptic``, ``gap_fit_residual``): Hertz's theory assumes
  a quadratic gap over the patch, so the patch's normal gap over its rigid interpenetration
  region is fitted by a parabola in the lateral plane coordinate s (least squares, weighted
  by the penetration d - g), and the weighted RMS residual must be at most
  ``HERTZ_GAP_RESIDUAL`` = 3 % of the largest penetration (and B > 0 at the deepest point,
  where the ellipse takes its curvatures).  It replaced (stop 27) the relative spread of the
  lateral curvature B over the region (limit 0.25), which is a second derivative: on raw
  measured points it reads 0.6-0.7 where the gap is quadratic to 2 % and Hertz within 2 %
  of the BEM.  ``benchmarks/hertz_criterion_accuracy.py`` measures it where it picks Hertz,
  against the fine BEM: on the conformal-tread cases below Hertz takes 114 of 198 patches
  (58 %; the spread criterion took 32 %) at p95 (max) position 0.21 mm (0.31), F_n 0 %,
  peak pressure 2.6 % (22 %: ``whl_left_iter288``'s 0.2 mm wide flank patch, which the
  0.2 mm BEM grid does not resolve); on the Manchester A-2.2 cases (CONTACT's profile
  files) 34 of 42 at 0.16 mm (0.17), 0 %, 4.9 % (7.9 %, the flange).  The S1002 / 60E1 1:20
  treads (residual 4.5-8.5 %, Hertz 3-13 % off in peak pressure) and the centred 1:40 tread
  (13 %) stay with the BEM.

Measured against the fine BEM on conformal treads (``benchmarks/normal_contact_accuracy.py``;
S1002 on 60E1 1:40 and 1:20 and nine measured MiniProf wheels, 10 and 60 kN, 198 cases):
"auto" p95 (max) position 0.17 mm (0.31), F_n 0.00 %, peak pressure 2.8 % (22 %, the
``whl_left_iter288`` flank patch above), Hertz in 58 % of the cases (0.10 mm, 3.4 %, 32 % with
the curvature-spread criterion); "bem-coarse" alone (50-case subset) 0.005 mm, 0.01 %,
1.7 %; "kp" (as above) 0.06 mm (0.85), 0.01 %, 15.8 % (30 % on the centred S1002 / 60E1 1:40
tread), so it misses the 10 % goal and is not the default.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.hertz import (
    STEEL_POISSON,
    STEEL_YOUNG_MPA,
    HertzPatch,
    hertz_contact,
)
from wearcast.physics.contact.kik_piotrowski import kp_patch
from wearcast.physics.contact.locus import NoContactError, WheelLocus
from wearcast.physics.contact.normal_bem import solve_normal_bem
from wearcast.physics.contact.patch_plane import (
    NormalPatch,
    PlaneSamples,
    finish_patch,
    patch_grid,
    plane_samples,
)
from wearcast.physics.contact.patches import PatchRegion, patch_regions

_FloatArray = NDArray[np.float64]

#: Largest relative residual of the patch's gap from its quadratic fit for Hertz ("auto";
#: ``gap_fit_residual``), chosen from the errors of Hertz against the BEM (module docstring).
HERTZ_GAP_RESIDUAL = 0.03
#: Methods of ``patch_normal_contact``.
NormalMethod = Literal["auto", "bem", "bem-coarse", "kp", "hertz"]
METHODS: tuple[NormalMethod, ...] = get_args(NormalMethod)
#: Elements per direction of the "bem-coarse" grid (over the rigid interpenetration region).
COARSE_ELEMENTS = 24
#: Smallest approach [mm] the search for the approach carrying a wheel load starts from.
MIN_APPROACH_MM = 1e-12


@dataclass(frozen=True)
class WheelNormalContact:
    """All patches of one wheel at one pose, carrying the vertical load together.

    approach_mm : common rigid vertical approach d of wheel and rail [mm]
    patches : ``NormalPatch`` per patch, field side first
    load_residual_n : vertical force of the normal forces less the load [N]: 0 to the
        iteration's tolerance, except at a jump of the force-approach curve (patches merging)
        where no approach carries the load exactly
    """

    approach_mm: float
    patches: list[NormalPatch]
    load_residual_n: float = 0.0

    @property
    def vertical_force_n(self) -> float:
        """sum F_n cos(delta) [N] (normal forces only)."""
        return float(sum(p.normal_force_n * np.cos(p.contact_angle_rad) for p in self.patches))


def gap_fit_residual(ps: PlaneSamples, approach_mm: float) -> float:
    """How far the patch's gap is from Hertz's: the relative residual of a quadratic fit.

    Over the rigid interpenetration region (pen_k = d - g_k > 0) the normal gap at approach d,
    h_k = (g_k - d) c_k [mm] (``patch_plane``), is fitted by h(s) = c0 + c1 s + c2 s^2 in the
    least-squares sense with the weights pen_k (the samples near the edge, where the pressure
    vanishes, count little, and a sample entering the region enters with weight 0, so the
    measure is continuous in d). Returned: the weighted RMS residual over the largest normal
    penetration, sqrt(sum pen r^2 / sum pen) / max(-h) [-]; inf where fewer than 3 samples
    span the region or the fitted curvature c2 is not positive (not convex). Hertz's theory
    (Johnson 1985 §4.2) assumes exactly such a quadratic gap over the patch; the residual says
    how much of the penetration, which sets the pressure, it misses.
    """
    pen = approach_mm - ps.g
    inside = pen > 0
    if np.count_nonzero(inside) < 3:
        return float("inf")
    w = pen[inside]
    h = -w * ps.c[inside]  # (g - d) c
    s = ps.s[inside]
    # weighted least squares by its 3 x 3 normal equations (Cramer's rule; the pipeline asks
    # this for every patch and round, and lstsq's call overhead was 10 % of the pipeline), in
    # s centred on the weighted mean (s1 = 0: well conditioned)
    w0 = float(w.sum())
    s = s - float(np.dot(w, s)) / w0
    ws = w * s
    ws2 = ws * s
    m2, m3, m4 = float(ws2.sum()), float(np.dot(ws2, s)), float(np.dot(ws2, s * s))
    t0, t1, t2 = float(np.dot(w, h)), float(np.dot(ws, h)), float(np.dot(ws2, h))
    # | w0  0   m2 | |c0|   |t0|
    # | 0   m2  m3 | |c1| = |t1|
    # | m2  m3  m4 | |c2|   |t2|
    det = w0 * (m2 * m4 - m3 * m3) - m2 * m2 * m2
    if not det > 0:
        return float("inf")
    c2 = (w0 * (m2 * t2 - m3 * t1) - m2 * m2 * t0) / det
    if not c2 > 0:
        return float("inf")
    c1 = (t1 - m3 * c2) / m2
    c0 = (t0 - m2 * c2) / w0
    r = h - (c0 + s * (c1 + s * c2))
    return float(np.sqrt(np.dot(w, r * r) / w0) / np.max(-h))


def is_elliptic(ps: PlaneSamples, approach_mm: float) -> bool:
    """Hertz criterion ("auto", module docstring): the patch's gap is quadratic to
    ``HERTZ_GAP_RESIDUAL`` of its penetration (``gap_fit_residual``), and the lateral
    curvature B at its deepest point, the Hertz ellipse's, is positive (convex)."""
    return bool(gap_fit_residual(ps, approach_mm) <= HERTZ_GAP_RESIDUAL
                and float(ps.b[np.argmin(ps.g)]) > 0)


@lru_cache(maxsize=64)
def _unit_hertz(a_curv: float, b_curv: float, young_mpa: float, poisson: float) -> HertzPatch:
    """``hertz_contact`` at a unit normal force, cached: the force-prescribed Hertz step of
    ``_single_patch_by_force`` and the patch it builds (``_hertz_patch``) take the ellipse of
    the same curvatures."""
    return hertz_contact(1.0, a_curv, b_curv, young_mpa, poisson)


def _hertz_patch(region: PatchRegion, ps: PlaneSamples, approach_mm: float,
                 young_mpa: float, poisson: float, element_mm: float) -> NormalPatch:
    k = int(np.argmin(ps.g))
    c_ref = float(ps.c[k])
    a_curv = float(ps.a[k]) * c_ref
    b_curv = float(ps.b[k])
    unit = _unit_hertz(a_curv, b_curv, young_mpa, poisson)
    delta_n = max(approach_mm - float(ps.g.min()), 0.0) * c_ref
    fn = float((delta_n / float(unit.approach_mm)) ** 1.5)
    # a, b and p0 grow as F^(1/3) for a fixed geometry (Johnson 1985 eqs. 4.39 ff.): the unit
    # force's ellipse scaled, not a second solve of the ellipse's shape
    scale = float(np.cbrt(fn))
    a, b = float(unit.a_mm) * scale, float(unit.b_mm) * scale
    p0 = float(unit.p0_mpa) * scale
    s0 = float(ps.s[np.argmin(ps.g)])
    x = np.arange(-a, a + element_mm, element_mm)
    s = s0 + np.arange(-b, b + element_mm, element_mm)
    if x.size < 3 or s.size < 3:
        x = np.linspace(-a, a, 5)
        s = s0 + np.linspace(-b, b, 5)
    rho = 1.0 - (x[None, :] / a) ** 2 - ((s[:, None] - s0) / b) ** 2 if fn > 0 else -np.ones(
        (s.size, x.size))
    p = p0 * np.sqrt(np.clip(rho, 0.0, None))
    if not fn > 0:
        return finish_patch(region, "hertz", ps, x, s, p)
    # exact Hertz totals instead of the sampled ones
    return NormalPatch(region, "hertz", fn, x, s, p, p0, float(np.pi * a * b),
                       0.0, s0, float(np.interp(s0, ps.s, ps.y_wheel)),
                       float(np.interp(s0, ps.s, ps.y_track)), a, b)


def warm_pressure(previous: NormalPatch | None, x: _FloatArray, s: _FloatArray
                  ) -> _FloatArray | None:
    """A start pressure on the grid (x, s) [mm] from a nearby solution ``previous`` (the same
    patch at a slightly different load or approach: an earlier round of the normal /
    tangential coupling or of the approach iteration): its pressure interpolated bilinearly
    onto the grid (0 outside it), or None when it carries no pressure."""
    if previous is None or not previous.normal_force_n > 0 or previous.x_mm.size < 2 or (
            previous.s_mm.size < 2):
        return None
    px, ps_ = previous.x_mm, previous.s_mm
    fx = (x - px[0]) / (px[1] - px[0])
    fs = (s - ps_[0]) / (ps_[1] - ps_[0])
    # (np.minimum / np.maximum: np.clip's numbers with less call overhead on small arrays)
    ix = np.minimum(np.maximum(np.floor(fx).astype(np.intp), 0), px.size - 2)
    js = np.minimum(np.maximum(np.floor(fs).astype(np.intp), 0), ps_.size - 2)
    tx = np.minimum(np.maximum(fx - ix, 0.0), 1.0)
    ts = np.minimum(np.maximum(fs - js, 0.0), 1.0)
    inside = ((fx >= 0) & (fx <= px.size - 1))[None, :] & ((fs >= 0) & (fs <= ps_.size - 1))[
        :, None]
    p = previous.pressure_mpa
    lower, upper = p[js], p[js + 1]  # the rows below and above each grid row
    rx, ux = (1 - tx)[None, :], tx[None, :]
    out = ((1 - ts)[:, None] * (rx * lower[:, ix] + ux * lower[:, ix + 1])
           + ts[:, None] * (rx * upper[:, ix] + ux * upper[:, ix + 1]))
    out = np.where(inside, out, 0.0)
    return out if out.sum() > 0 else None


def patch_normal_contact(locus: WheelLocus, row: int, region: PatchRegion, approach_mm: float,
                         method: str = "auto", young_mpa: float = STEEL_YOUNG_MPA,
                         poisson: float = STEEL_POISSON, element_mm: float = 0.2,
                         margin_mm: float = 0.6, warm: NormalPatch | None = None
                         ) -> NormalPatch:
    """Normal contact of one patch at vertical approach d [mm] (module docstring).

    Parameters
    ----------
    locus, row : contact locus and pose index
    region : the patch (``patches.patch_regions`` at the same approach)
    approach_mm : rigid vertical approach d [mm] (the gap of the locus is 0 at first touch)
    method : "bem", "kp", "hertz" or "auto"
    element_mm : element size of the grid [mm] (CONTACT's DX = DS = 0.2 mm)
    margin_mm : grid margin around the interpenetration region [mm]
    warm : optional nearby solution of the same patch to start the BEM from
        (``warm_pressure``; the same solution to the solver's tolerance, fewer iterations)
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, not {method!r}")
    ps = plane_samples(locus, row, region, extend_mm=margin_mm + 2.0 * element_mm)
    if method == "auto":
        method = "hertz" if is_elliptic(ps, approach_mm) else "bem-coarse"
    if method == "hertz" and float(ps.b[np.argmin(ps.g)]) <= 0:
        raise ValueError("Hertz needs a convex patch (B > 0); use 'kp' or 'bem' here")
    if method == "hertz":
        return _hertz_patch(region, ps, approach_mm, young_mpa, poisson, element_mm)
    if method == "kp":
        return kp_patch(region, ps, approach_mm, young_mpa, poisson, element_mm, margin_mm)
    coarse = method == "bem-coarse"
    h, x, s = patch_grid(ps, approach_mm, element_mm, margin_mm,
                    COARSE_ELEMENTS if coarse else None)
    res = solve_normal_bem(h, x, s, approach_mm=0.0, young_mpa=young_mpa, poisson=poisson,
                           tol=1e-6 if coarse else 1e-7,
                           initial_pressure_mpa=warm_pressure(warm, x, s))
    return finish_patch(region, method, ps, x, s, res.pressure_mpa)


def _single_patch_by_force(locus: WheelLocus, row: int, load_n: float, ratio: float,
                           approach_mm: float, method: str, young_mpa: float, poisson: float,
                           element_mm: float, margin_mm: float = 0.6,
                           warm: NormalPatch | None = None
                           ) -> tuple[float, NormalPatch] | None:
    """Fast path of ``wheel_normal_contact`` for a single patch: its normal force is known
    from the load, F_n = W / (cos delta + r sin delta), so the BEM (or Hertz) is solved with
    the force prescribed and returns the approach; the patch is re-identified at that
    approach until it settles (2-3 solves instead of a bracketing iteration).  None when
    there is not exactly one patch or the method has no force-prescribed form ("kp").
    ``warm``: a nearby solution to start the BEM from (``warm_pressure``); each re-solve
    starts from the previous one."""
    d = approach_mm
    for _ in range(6):
        regions = patch_regions(locus, row, d)
        if len(regions) != 1:
            return None
        region = regions[0]
        fn = load_n / max(np.cos(region.contact_angle_rad)
                          + ratio * np.sin(region.contact_angle_rad), 0.05)
        ps = plane_samples(locus, row, region, extend_mm=margin_mm + 2.0 * element_mm)
        chosen = method
        if chosen == "auto":
            chosen = "hertz" if is_elliptic(ps, d) else "bem-coarse"
        k = int(np.argmin(ps.g))
        c_min = float(ps.c[k])
        if chosen == "hertz":
            if float(ps.b[k]) <= 0:
                return None
            unit = _unit_hertz(float(ps.a[k]) * c_min, float(ps.b[k]), young_mpa, poisson)
            d_new = float(ps.g[k]) + float(unit.approach_mm) * fn ** (2.0 / 3.0) / c_min
            patch = _hertz_patch(region, ps, d_new, young_mpa, poisson, element_mm)
        elif chosen in ("bem", "bem-coarse"):
            coarse = chosen == "bem-coarse"
            h, x, s = patch_grid(ps, d, element_mm, margin_mm, COARSE_ELEMENTS if coarse else None)
            res = solve_normal_bem(h, x, s, normal_force_n=fn, young_mpa=young_mpa,
                                   poisson=poisson, tol=1e-6 if coarse else 1e-7,
                                   initial_pressure_mpa=warm_pressure(warm, x, s))
            border = np.concatenate([res.pressure_mpa[0], res.pressure_mpa[-1],
                                     res.pressure_mpa[:, 0], res.pressure_mpa[:, -1]])
            d_new = d + res.approach_mm / c_min
            patch = finish_patch(region, chosen, ps, x, s, res.pressure_mpa)
            warm = patch
            if np.any(border > 0):  # the grid was too small: grow it and solve again
                d = max(d_new, 1.2 * d)
                continue
        else:
            return None
        if abs(d_new - d) <= 1e-3 * abs(d_new):
            return d_new, patch
        d = d_new
    return None


def wheel_normal_contact(locus: WheelLocus, wheel_load_n: float | NDArray[np.float64],
                         method: str = "auto", lateral_ratio: list[list[float]] | None = None,
                         young_mpa: float = STEEL_YOUNG_MPA, poisson: float = STEEL_POISSON,
                         element_mm: float = 0.2, rtol: float = 1e-4,
                         approach_guess_mm: ArrayLike | None = None,
                         patch_guess: Sequence[Sequence[NormalPatch]] | None = None
                         ) -> list[WheelNormalContact]:
    """Patches of one wheel carrying its vertical load W, for every pose of the locus.

    The common vertical approach d solves sum_i F_n,i(d) (cos delta_i + r_i sin delta_i) = W
    (r_i = F_s/F_n from ``lateral_ratio``, default 0) by bracketing and the Illinois
    (regula falsi) iteration to ``rtol`` of W; the patches are re-identified at every d
    (``patches.patch_regions``), so merging and splitting follow the load.  A single patch
    takes a fast path: its force is known, so it is solved with the force prescribed and the
    approach follows (``_single_patch_by_force``).  ``approach_guess_mm`` (per pose,
    optional) starts either iteration near a known solution; ``patch_guess`` (per pose, the
    patches of a nearby solution, e.g. the previous round of the normal / tangential
    coupling) starts the BEM solves from their pressures (``warm_pressure``).

    Returns one ``WheelNormalContact`` per pose; module docstring for the patch fields.
    """
    n = locus.gap_mm.shape[0]
    loads = np.broadcast_to(np.asarray(wheel_load_n, dtype=float), (n,))
    if np.any(loads <= 0):
        raise ValueError("wheel_load_n must be positive")
    out = []
    for row in range(n):
        ratios = lateral_ratio[row] if lateral_ratio is not None else None
        guesses: list[NormalPatch] = list(patch_guess[row]) if patch_guess is not None else []

        def solve(d: float, row: int = row, ratios: list[float] | None = ratios,
                  guesses: list[NormalPatch] = guesses) -> tuple[float, list[NormalPatch]]:
            regions = patch_regions(locus, row, d)
            warm = guesses if len(guesses) == len(regions) else []
            patches = [patch_normal_contact(locus, row, reg, d, method, young_mpa, poisson,
                                            element_mm, warm=warm[k] if warm else None)
                       for k, reg in enumerate(regions)]
            guesses[:] = patches
            total = 0.0
            for k, p in enumerate(patches):
                r = ratios[k] if ratios is not None and k < len(ratios) else 0.0
                total += p.normal_force_n * max(np.cos(p.contact_angle_rad)
                                                + r * np.sin(p.contact_angle_rad), 0.05)
            return total, patches

        load = float(loads[row])
        if approach_guess_mm is not None:
            start = float(np.broadcast_to(np.asarray(approach_guess_mm, dtype=float), (n,))[row])
        else:
            start = 0.03 * (load / 1e4) ** (2.0 / 3.0)
        fast = _single_patch_by_force(locus, row, load, ratios[0] if ratios else 0.0, start,
                                      method, young_mpa, poisson, element_mm,
                                      warm=guesses[0] if len(guesses) == 1 else None)
        if fast is not None:
            out.append(WheelNormalContact(approach_mm=fast[0], patches=[fast[1]]))
            continue
        lo, f_lo = 0.0, -load
        if approach_guess_mm is not None:
            guess = float(np.broadcast_to(np.asarray(approach_guess_mm, dtype=float), (n,))[row])
            f_g, patches = solve(0.98 * guess)
            if f_g - load < 0:
                lo, f_lo = 0.98 * guess, f_g - load
            hi = 1.02 * guess if f_g - load < 0 else 0.98 * guess
        else:
            # Hertz-like first guess from a 10 kN wheel on a tread: d ~ 0.03 mm (W/10 kN)^(2/3)
            hi = 0.03 * (load / 1e4) ** (2.0 / 3.0)
        # a first guess that underflowed to 0 (a load near the smallest float) would be
        # doubled for ever: start the doubling from the smallest approach tried
        hi = max(hi, MIN_APPROACH_MM)
        f_hi, patches = solve(hi)
        f_hi -= load
        while f_hi < 0:
            lo, f_lo = hi, f_hi
            hi *= 2.0
            f_hi, patches = solve(hi)
            f_hi -= load
            if hi > 5.0:
                raise NoContactError("wheel", "no approach up to 5 mm carries the wheel load: "
                                     "the wheel does not reach its rail")
        side = 0
        d = hi
        best = (np.inf, d, patches)  # (|residual|, approach, patches)
        for _ in range(60):
            d = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
            f, patches = solve(d)
            f -= load
            if abs(f) < best[0]:
                best = (abs(f), d, patches)
            if abs(f) < rtol * load or hi - lo < 1e-7 * hi:
                break
            if f > 0:
                hi, f_hi = d, f
                if side == 1:
                    f_lo *= 0.5
                side = 1
            else:
                lo, f_lo = d, f
                if side == -1:
                    f_hi *= 0.5
                side = -1
        else:
            raise RuntimeError("normal contact: the approach iteration did not converge")
        residual = 0.0
        if best[0] >= rtol * load:
            # the bracket closed on a jump of the force-approach curve: where two patches
            # merge (or a patch's region changes) no approach carries exactly the load; the
            # side nearer it is taken and the difference reported (``load_residual_n``)
            d, patches = best[1], best[2]
            residual = float(sum(p.normal_force_n * np.cos(p.contact_angle_rad)
                                 for p in patches)) - load
        out.append(WheelNormalContact(approach_mm=float(d), patches=patches,
                                      load_residual_n=residual))
    return out
