"""Kalker's 1982 FASTSIM in its original normalised form, and the map to our ``fastsim``.

Kalker, "A fast algorithm for the simplified theory of rolling contact", Vehicle System
Dynamics 11 (1982) 1-13, states FASTSIM on the unit disc: x' = x/a, y' = y/b (a in the
rolling direction), tractions P = p/(mu p0) with p0 = 2 Fn/(pi a b) the peak of the parabolic
pressure, so the traction bound is |P| <= 1 - x'^2 - y'^2. The creepages enter as four
numbers, the gradients of the adhesion traction along the rolling path (travelling from the
leading edge x' = +sqrt(1 - y'^2) towards -x'):

    dPx/d(-x') = -(ux - fix y'),    dPy/d(-x') = -(uy + fiy x').

Comparing with the dimensional simplified theory (``fastsim``: dpx = -dx (xi/L1 - phi y/L3),
dpy = -dx (eta/L2 + phi x/L3)) gives the normalisation

    ux = a xi / (L1 mu p0),   uy = a eta / (L2 mu p0),
    fix = a b phi / (L3 mu p0),   fiy = a^2 phi / (L3 mu p0)     (so fiy/fix = a/b),

and the outputs are Tx = Fx/(mu Fn), Ty = Fy/(mu Fn) = (2/pi) * sum(P dx' dy').
This was pinned down from the public C++ port of Kalker's routine and its tests
(github criogenox/C_Normal_Tangential_Railway_Contact, ``tang_fastsim``), read, not copied.

Two entry points:

* ``fastsim_normalised`` implements Kalker's *original discretisation*, which differs from
  CONTACT's (the one ``fastsim`` reproduces): the disc is cut into strips in y'; each strip
  gets its own step dx' = 2 sqrt(1 - y'^2)/mx (mx points per strip, at the centres of mx
  equal elements; the first step is the half element from the leading edge); the spin term of
  the lateral increment is taken at the midpoint of each step. In the small-creepage regime
  (|ux| <= |fix| and |uy| <= |fiy|) the strips of each half-disc end exactly on the line
  y' = ux/fix where the longitudinal creepage changes sign, about my/2 strips per unit of y',
  and the strip next to that line is bisected towards it until its half-width is <= tol;
  otherwise my equal strips cover [-1, 1]. This reproduces the paper's printed Tx, Ty.
* ``fastsim_normalised_on_grid`` maps the same normalised inputs onto ``fastsim`` (physical
  units, CONTACT's discretisation, textbook flexibilities). The two discretisations agree in
  the limit of fine grids, not element by element.

Sign: both return the project's (Kalker linear theory) sign, Fx = -G a b C11 xi, so ux > 0
gives Tx < 0. Kalker's printed table (as held in the port's tests) lists Tx with the opposite
sign (+0.5720 for ux = 1) while Ty keeps ours; the port flips Tx before comparing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.contact.fastsim import fastsim

#: Guard on the bisection of the strip next to y' = ux/fix (each halves the strip width).
MAX_STRIP_REFINEMENTS = 40
#: |fix| below this, or ||ux| - |fix|| below this, counts as singular: equal strips are used.
_SINGULAR = 1e-6


@dataclass(frozen=True)
class Kalker1982Result:
    """Normalised FASTSIM result (Kalker 1982 form).

    tx, ty : Fx/(mu Fn), Fy/(mu Fn) [-], project sign (ux > 0 gives tx < 0)
    strip_y : centres y' = y/b of the strips used [-], shape (n_strips,)
    strip_dy : widths of those strips in y' [-], shape (n_strips,)
    adaptive : True when the strips were aligned on y' = ux/fix (small-creepage regime)
    slip_fraction : share of the points whose traction sits on the bound [-]
    """

    tx: float
    ty: float
    strip_y: NDArray[np.float64]
    strip_dy: NDArray[np.float64]
    adaptive: bool
    slip_fraction: float


def kalker_strips(ux: float, uy: float, fix: float, fiy: float, my: int, tol: float
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], bool]:
    """Strip centres and widths in y' = y/b for Kalker's 1982 FASTSIM.

    Small-creepage regime (|ux| <= |fix| and |uy| <= |fiy|, fix not ~0, |ux| != |fix|): for
    each half-disc s = +1, -1 the band s y' in [r, 1], r = s ux/fix, is cut into
    n = floor((1 - r) my/2) + 1 equal strips; the strip touching s y' = r is bisected towards
    r while tol < (its width)/2, keeping the outer halves. Otherwise my equal strips on [-1, 1].
    Returns (centres, widths, adaptive).
    """
    if my < 1 or int(my) != my:
        raise ValueError("my must be a positive integer")
    if not tol > 0:
        raise ValueError("tol must be > 0")
    large = abs(ux) > abs(fix) or abs(uy) > abs(fiy)
    singular = abs(fix) < _SINGULAR or abs(abs(ux) - abs(fix)) < _SINGULAR
    if large or singular:
        # Same count rule with the split line on y' = 0 and no bisection: 2 (floor(my/2) + 1)
        # equal strips. Inferred: this reproduces the paper's case (1, -2, 2, 1) to all printed
        # digits, where my equal strips (the C++ port's reading) miss Ty by 1.5e-3.
        n = 2 * (int(my) // 2 + 1)
        dy = 2.0 / n
        centres = -1.0 + dy * (np.arange(n, dtype=np.float64) + 0.5)
        return centres, np.full(n, dy, dtype=np.float64), False
    ys: list[float] = []
    ws: list[float] = []
    for s in (1.0, -1.0):
        r = s * ux / fix
        n = int(np.floor((1.0 - r) * my / 2.0)) + 1
        h = (1.0 - r) / n
        # regular strips, outermost first: s y' in [r + k h, r + (k + 1) h], k = n-1 .. 1
        for k in range(n - 1, 0, -1):
            ys.append(s * (r + (k + 0.5) * h))
            ws.append(h)
        # the strip [r, r + h] next to the sign-change line, bisected towards r
        for _ in range(MAX_STRIP_REFINEMENTS):
            if not tol < h / 2.0:
                break
            h /= 2.0
            ys.append(s * (r + 1.5 * h))
            ws.append(h)
        ys.append(s * (r + 0.5 * h))
        ws.append(h)
    return np.asarray(ys), np.asarray(ws), True


def fastsim_normalised(ux: float, uy: float, fix: float, fiy: float, mx: int = 5,
                       my: int = 5, tol: float = 3.0) -> Kalker1982Result:
    """Kalker's 1982 FASTSIM on the unit disc, with his original discretisation.

    Parameters
    ----------
    ux, uy : normalised longitudinal and lateral creepage, a xi/(L1 mu p0), a eta/(L2 mu p0)
    fix, fiy : normalised spin, a b phi/(L3 mu p0) and a^2 phi/(L3 mu p0) (fiy/fix = a/b)
    mx : points per strip (each strip has its own step 2 sqrt(1 - y'^2)/mx)
    my : strip count parameter (see ``kalker_strips``)
    tol : half-width below which the strip next to y' = ux/fix is no longer bisected

    Returns
    -------
    Kalker1982Result with tx = Fx/(mu Fn), ty = Fy/(mu Fn) in the project's sign.

    Kalker 1982 (module docstring); parabolic traction bound 1 - x'^2 - y'^2. The march runs
    over the mx points, vectorised over all strips.
    """
    if mx < 1 or int(mx) != mx:
        raise ValueError("mx must be a positive integer")
    y, dy, adaptive = kalker_strips(ux, uy, fix, fiy, my, tol)
    half = np.sqrt(1.0 - y * y)  # leading edge x' of each strip
    dx = 2.0 * half / mx
    sx = ux - fix * y  # longitudinal adhesion gradient, constant along a strip
    px = np.zeros_like(y)
    py = np.zeros_like(y)
    sum_x = np.zeros_like(y)
    sum_y = np.zeros_like(y)
    n_slip = 0
    x_prev = half
    for k in range(int(mx)):
        x = half - (k + 0.5) * dx
        step = x_prev - x
        sy = uy + fiy * 0.5 * (x_prev + x)  # spin term at the middle of the step
        px = px - sx * step
        py = py - sy * step
        bound = 1.0 - y * y - x * x
        norm = np.hypot(px, py)
        over = norm > bound
        scale = np.where(over, bound / np.where(over, norm, 1.0), 1.0)
        px = px * scale
        py = py * scale
        n_slip += int(over.sum())
        sum_x += px
        sum_y += py
        x_prev = x
    area = dx * dy
    tx = 2.0 / np.pi * float(np.sum(area * sum_x))
    ty = 2.0 / np.pi * float(np.sum(area * sum_y))
    return Kalker1982Result(tx=tx, ty=ty, strip_y=y, strip_dy=dy, adaptive=adaptive,
                            slip_fraction=n_slip / (y.size * int(mx)))


@dataclass(frozen=True)
class PhysicalEquivalent:
    """A dimensional FASTSIM problem equivalent to a normalised one (inputs of ``fastsim``).

    xi, eta [-], phi_per_mm [1/mm], a_mm, b_mm [mm], normal_force_n [N], mu [-],
    flexibilities_mm_per_mpa (L1, L2, L3) [mm/MPa].
    """

    xi: float
    eta: float
    phi_per_mm: float
    a_mm: float
    b_mm: float
    normal_force_n: float
    mu: float
    flexibilities_mm_per_mpa: tuple[float, float, float]


def normalised_to_physical(ux: float, uy: float, fix: float, fiy: float, b_mm: float = 1.0
                           ) -> PhysicalEquivalent:
    """One dimensional problem with Kalker's normalised inputs (ux, uy, fix, fiy).

    Chooses L1 = L2 = L3 = 1 mm/MPa, mu = 1 and Fn = pi a b/2 N (so mu p0 = 1 MPa), b = b_mm
    and a = b fiy/fix (a = b when there is no spin); then xi = ux/a, eta = uy/a,
    phi = fix/(a b) [1/mm] (module docstring). Spin with fix = 0 but fiy != 0 (or opposite
    signs) has no such ellipse and is refused.
    """
    if fix == 0.0 and fiy == 0.0:
        a = b_mm
    elif fix != 0.0 and fiy / fix > 0.0:
        a = b_mm * fiy / fix
    else:
        raise ValueError("fix and fiy must both be zero or share a sign (fiy/fix = a/b > 0)")
    return PhysicalEquivalent(
        xi=ux / a, eta=uy / a, phi_per_mm=fix / (a * b_mm), a_mm=a, b_mm=b_mm,
        normal_force_n=np.pi * a * b_mm / 2.0, mu=1.0, flexibilities_mm_per_mpa=(1.0, 1.0, 1.0),
    )


def physical_to_normalised(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, mu,
                           flexibilities_mm_per_mpa):
    """Kalker's normalised inputs (ux, uy, fix, fiy) of a dimensional FASTSIM problem.

    p0 = 2 Fn/(pi a b); ux = a xi/(L1 mu p0), uy = a eta/(L2 mu p0),
    fix = a b phi/(L3 mu p0), fiy = a^2 phi/(L3 mu p0). Arrays broadcast.
    """
    l1, l2, l3 = (np.asarray(v, dtype=float) for v in flexibilities_mm_per_mpa)
    a = np.asarray(a_mm, dtype=float)
    b = np.asarray(b_mm, dtype=float)
    g = np.asarray(mu, dtype=float) * 2.0 * np.asarray(normal_force_n, dtype=float) / (
        np.pi * a * b)
    phi = np.asarray(phi_per_mm, dtype=float)
    return (a * np.asarray(xi, dtype=float) / (l1 * g), a * np.asarray(eta, dtype=float) / (l2 * g),
            a * b * phi / (l3 * g), a * a * phi / (l3 * g))


def fastsim_normalised_on_grid(ux: float, uy: float, fix: float, fiy: float, n_x: int = 40,
                               n_y: int = 40, spin_offset_fraction: float = 0.0
                               ) -> tuple[float, float]:
    """Kalker's normalised problem solved by our ``fastsim`` (CONTACT's grid discretisation).

    Maps (ux, uy, fix, fiy) with ``normalised_to_physical`` and returns
    (Fx/(mu Fn), Fy/(mu Fn)) in the project's sign. Parabolic bound, the given flexibilities
    (no combined-flexibility rule); spin evaluated at the element centre by default.
    """
    p = normalised_to_physical(ux, uy, fix, fiy)
    r = fastsim(p.xi, p.eta, p.phi_per_mm, p.a_mm, p.b_mm, p.normal_force_n, p.mu, n_x=n_x,
                n_y=n_y, bound="parabolic", flexibilities_mm_per_mpa=p.flexibilities_mm_per_mpa,
                spin_offset_fraction=spin_offset_fraction)
    mu_fn = p.mu * p.normal_force_n
    return float(r.fx_n) / mu_fn, float(r.fy_n) / mu_fn
