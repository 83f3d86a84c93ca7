"""Boundary-element solution of the frictionless normal contact problem on a grid.

Two elastic half-spaces of the same steel touch where their undeformed gap h(x, y) [mm] is
closed by the rigid approach delta [mm] and the surface displacement u [mm]:

    h + u - delta >= 0,   p >= 0,   p (h + u - delta) = 0   everywhere,
    u(x_i) = sum_j C_ij p_j,        F_n = dA sum_j p_j,

with p [MPa] piecewise constant on a uniform grid of rectangular elements dx x dy (Kalker's
NORM discretisation: Kalker, "Three-dimensional elastic bodies in rolling contact", 1990,
ch. 5; influence coefficients from Love's closed form for a uniform pressure on a rectangle,
Love 1929 / Johnson, Contact Mechanics 1985 eq. 3.25):

    C_ij = 1 / (pi E*) [f(X+a, Y+b) - f(X+a, Y-b) - f(X-a, Y+b) + f(X-a, Y-b)],
    f(X, Y) = X ln(Y + sqrt(X^2 + Y^2)) + Y ln(X + sqrt(X^2 + Y^2)),

X, Y the offset of collocation point i from element centre j, a = dx/2, b = dy/2,
1/E* = 2 (1 - nu^2) / E (both bodies).  C depends on the offset only, so u = C p is a
convolution, done by FFT on a grid padded to twice the size (exact, no periodic images).

Solver: the conjugate-gradient active-set method of Polonsky & Keer (Wear 231 (1999) 206-219)
for a prescribed normal force (delta follows) or, with ``approach_mm`` given, for a
prescribed approach; pressures are kept non-negative, elements that open or close move
between the sets, and the iteration stops when the pressure changes by less than ``tol``
(relative, L1).  Typical wheel-rail patches (0.2 mm elements, 2 000-10 000 elements) converge
in 20-80 iterations, a few milliseconds to 0.1 s.  Grids of at most
``normal_bem_kernel.DIRECT_MAX_ELEMENTS`` elements (the production method's coarse grids)
run the same iteration compiled, with the dense influence matrix instead of the FFT
(``normal_bem_kernel``; same solution to rounding, 5-8x faster on 22-26 elements per
direction, ``benchmarks/bench_normal_bem.py``); a start pressure from a nearby solution
(``initial_pressure_mpa``) saves iterations.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.hertz import STEEL_POISSON, STEEL_YOUNG_MPA, effective_modulus_mpa
from wearcast.physics.contact.normal_bem_kernel import (
    DIRECT_MAX_ELEMENTS,
    dense_influence_into,
    polonsky_keer,
)

_FloatArray = NDArray[np.float64]


def _love_f(x: _FloatArray, y: _FloatArray) -> _FloatArray:
    """f(X, Y) = X ln(Y + R) + Y ln(X + R), R = sqrt(X^2 + Y^2), evaluated without 0 * log 0
    (for Y + R -> 0, i.e. Y < 0 and X -> 0, use Y + R = X^2 / (R - Y))."""
    r = np.hypot(x, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        y_r = np.where(y >= 0, y + r, x * x / (r - y))
        x_r = np.where(x >= 0, x + r, y * y / (r - x))
        t1 = np.where(x == 0, 0.0, x * np.log(y_r))
        t2 = np.where(y == 0, 0.0, y * np.log(x_r))
    return t1 + t2


def influence_coefficients(nx: int, ny: int, dx_mm: float, dy_mm: float,
                           e_star_mpa: float) -> _FloatArray:
    """Normal displacement [mm per MPa] at offsets (j dy, i dx), i in (-nx, nx), j in
    (-ny, ny), of a unit pressure on one dx x dy element; shape (2 ny - 1, 2 nx - 1),
    centre [ny - 1, nx - 1] (module docstring, Love's formula)."""
    ox = np.arange(-nx + 1, nx) * dx_mm
    oy = np.arange(-ny + 1, ny) * dy_mm
    x, y = np.meshgrid(ox, oy)
    a, b = 0.5 * dx_mm, 0.5 * dy_mm
    value = (_love_f(x + a, y + b) - _love_f(x + a, y - b) - _love_f(x - a, y + b)
             + _love_f(x - a, y - b))
    return value / (np.pi * e_star_mpa)


#: Half-width (elements) of the offset kernels cached per element size (``_offsets``): the
#: kernel of any grid up to this many elements per direction is a window of it (the coarse
#: grids have at most ``normal_contact.COARSE_ELEMENTS`` + 2 per direction).
_KERNEL_HALF_WIDTH = 28


@lru_cache(maxsize=256)
def _offsets(dx_mm: float, dy_mm: float, e_star_mpa: float) -> _FloatArray:
    """``influence_coefficients`` of a ``_KERNEL_HALF_WIDTH``-square grid of dx x dy elements,
    cached per element size: the coefficient at an offset does not depend on the grid, so
    a smaller grid's kernel is the centred window of this one (the same numbers; the coarse
    grids' element sizes come from a short ladder, ``patch_plane.patch_grid``, while their
    element counts vary from grid to grid)."""
    c = influence_coefficients(_KERNEL_HALF_WIDTH, _KERNEL_HALF_WIDTH, dx_mm, dy_mm,
                               e_star_mpa)
    c.setflags(write=False)
    return c


#: Dense influence matrices kept per thread (``_dense``): 16 coarse grids of up to 26 x 26
#: elements, ~60 MB.
_DENSE_CACHE_SIZE = 16


class _DenseCache(threading.local):
    """The dense matrices of ``_dense``, one LRU per thread: a buffer is recycled only by the
    thread that solves with it (the service's job threads must not overwrite a matrix
    another thread is about to use)."""

    def __init__(self) -> None:
        self.entries: OrderedDict[tuple[int, int, float, float, float], _FloatArray] = (
            OrderedDict())


_dense_cache = _DenseCache()


def _dense(nx: int, ny: int, dx_mm: float, dy_mm: float, e_star_mpa: float) -> _FloatArray:
    """The dense influence matrix (``normal_bem_kernel.dense_influence``) of a grid, cached,
    least recently used first out (the rounds of one wheel's normal / tangential coupling
    reuse their grids); a new matrix is written into the buffer of the one it evicts when
    that is large enough (a fresh 3 MB array costs more in page faults than filling it)."""
    key = (nx, ny, dx_mm, dy_mm, e_star_mpa)
    cache = _dense_cache.entries
    hit = cache.get(key)
    if hit is not None:
        cache.move_to_end(key)
        return hit
    if max(nx, ny) <= _KERNEL_HALF_WIDTH:
        centre = _KERNEL_HALF_WIDTH - 1
        kernel = np.ascontiguousarray(_offsets(dx_mm, dy_mm, e_star_mpa)[
            centre - ny + 1:centre + ny, centre - nx + 1:centre + nx])
    else:
        kernel = influence_coefficients(nx, ny, dx_mm, dy_mm, e_star_mpa)
    n = nx * ny
    buffer = None
    if len(cache) >= _DENSE_CACHE_SIZE:
        _, old = cache.popitem(last=False)
        base = old.base if isinstance(old.base, np.ndarray) else old
        if base.size >= n * n:
            buffer = base
    if buffer is None:
        buffer = np.empty(n * n)
    d = buffer[:n * n].reshape(n, n)
    dense_influence_into(kernel, ny, nx, d)
    d.setflags(write=False)
    cache[key] = d
    return d


@lru_cache(maxsize=32)
def _kernel_fft(nx: int, ny: int, dx_mm: float, dy_mm: float, e_star_mpa: float
                ) -> NDArray[np.complex128]:
    c = influence_coefficients(nx, ny, dx_mm, dy_mm, e_star_mpa)
    padded = np.zeros((2 * ny, 2 * nx))
    # circular layout: offset k at index k (k >= 0) and 2n + k (k < 0)
    iy = np.arange(-ny + 1, ny) % (2 * ny)
    ix = np.arange(-nx + 1, nx) % (2 * nx)
    padded[np.ix_(iy, ix)] = c
    return np.fft.rfft2(padded)


class _Convolution:
    """u = C p for pressures on an (ny, nx) grid, by zero-padded FFT."""

    def __init__(self, ny: int, nx: int, dx_mm: float, dy_mm: float, e_star_mpa: float):
        self.shape = (ny, nx)
        self.kernel = _kernel_fft(nx, ny, float(dx_mm), float(dy_mm), float(e_star_mpa))

    def __call__(self, p: _FloatArray) -> _FloatArray:
        ny, nx = self.shape
        spectrum = np.fft.rfft2(p, s=(2 * ny, 2 * nx)) * self.kernel
        return np.fft.irfft2(spectrum, s=(2 * ny, 2 * nx))[:ny, :nx]


@dataclass(frozen=True)
class NormalBemResult:
    """Solution of the normal problem on the grid.

    pressure_mpa : p [MPa], shape (ny, nx), row j at y_mm[j], column i at x_mm[i]
    displacement_mm : u = C p [mm], shape (ny, nx)
    approach_mm : rigid approach delta [mm]
    normal_force_n : F_n = dA sum p [N]
    x_mm, y_mm : element centres [mm]
    iterations : CG iterations used
    converged : the relative pressure change fell below the tolerance
    """

    pressure_mpa: _FloatArray
    displacement_mm: _FloatArray
    approach_mm: float
    normal_force_n: float
    x_mm: _FloatArray
    y_mm: _FloatArray
    iterations: int
    converged: bool

    @property
    def in_contact(self) -> NDArray[np.bool_]:
        """Elements carrying pressure."""
        return self.pressure_mpa > 0.0

    @property
    def area_mm2(self) -> float:
        """Contact area [mm^2]."""
        dx = self.x_mm[1] - self.x_mm[0] if self.x_mm.size > 1 else 0.0
        dy = self.y_mm[1] - self.y_mm[0] if self.y_mm.size > 1 else 0.0
        return float(np.count_nonzero(self.in_contact) * dx * dy)

    @property
    def peak_pressure_mpa(self) -> float:
        """max p [MPa]."""
        return float(self.pressure_mpa.max())

    @property
    def centre_mm(self) -> tuple[float, float]:
        """Pressure centre (x, y) [mm]: the point of action of F_n."""
        p = self.pressure_mpa
        total = p.sum()
        return (float((p.sum(axis=0) * self.x_mm).sum() / total),
                float((p.sum(axis=1) * self.y_mm).sum() / total))


def solve_normal_bem(gap_mm: ArrayLike, x_mm: ArrayLike, y_mm: ArrayLike,
                     normal_force_n: float | None = None, approach_mm: float | None = None,
                     young_mpa: float = STEEL_YOUNG_MPA, poisson: float = STEEL_POISSON,
                     tol: float = 1e-8, max_iter: int = 2000,
                     initial_pressure_mpa: ArrayLike | None = None,
                     compiled: bool | None = None) -> NormalBemResult:
    """Frictionless normal contact of two half-spaces with the undeformed gap h on a grid.

    Parameters
    ----------
    gap_mm : undeformed gap h [mm] at the element centres, shape (ny, nx); the grid must
        cover the whole contact area (the result's pressure must vanish on its border,
        check ``pressure_mpa`` there if unsure)
    x_mm, y_mm : element centres [mm], uniform spacing, shapes (nx,), (ny,)
    normal_force_n : prescribed F_n [N] (> 0), or
    approach_mm : prescribed rigid approach delta [mm] (exactly one of the two)
    young_mpa, poisson : Young's modulus [MPa] and Poisson's ratio of both bodies
    tol : convergence on sum |p_new - p_old| / sum p
    max_iter : iteration limit; RuntimeError if reached without convergence
    initial_pressure_mpa : optional start pressure (ny, nx) [MPa], e.g. the solution of a
        nearby problem on the same grid (a warm start: fewer iterations, the same solution
        to ``tol``); default sqrt of the rigid interpenetration. A warm start that loses
        every element in contact, or does not converge, is solved again from the default
        start (the iteration, not the problem, failed: e.g. a nearby patch that no longer
        overlaps the interpenetration)
    compiled : run the compiled direct iteration (``normal_bem_kernel``) instead of the FFT
        one; default: compiled when numba is there and the grid has at most
        ``DIRECT_MAX_ELEMENTS`` elements (the two agree to rounding)

    Returns
    -------
    NormalBemResult; Polonsky & Keer 1999 CG with Kalker/Love influence coefficients
    (module docstring).
    """
    if initial_pressure_mpa is not None:
        try:
            return _solve(gap_mm, x_mm, y_mm, normal_force_n, approach_mm, young_mpa, poisson,
                          tol, max_iter, initial_pressure_mpa, compiled)
        except RuntimeError:
            pass  # the warm iteration failed: solved again from the default start
    return _solve(gap_mm, x_mm, y_mm, normal_force_n, approach_mm, young_mpa, poisson, tol,
                  max_iter, None, compiled)


def _solve(gap_mm: ArrayLike, x_mm: ArrayLike, y_mm: ArrayLike, normal_force_n: float | None,
           approach_mm: float | None, young_mpa: float, poisson: float, tol: float,
           max_iter: int, initial_pressure_mpa: ArrayLike | None, compiled: bool | None
           ) -> NormalBemResult:
    """:func:`solve_normal_bem` from one start."""
    h = np.asarray(gap_mm, dtype=float)
    x = np.asarray(x_mm, dtype=float)
    y = np.asarray(y_mm, dtype=float)
    if h.ndim != 2 or h.shape != (y.size, x.size):
        raise ValueError("gap_mm must have shape (len(y_mm), len(x_mm))")
    if (normal_force_n is None) == (approach_mm is None):
        raise ValueError("give exactly one of normal_force_n and approach_mm")
    if not np.all(np.isfinite(h)):
        raise ValueError("gap_mm must be finite (use a large gap outside the bodies)")
    dx = float(x[1] - x[0]) if x.size > 1 else 1.0
    dy = float(y[1] - y[0]) if y.size > 1 else 1.0
    if dx <= 0 or dy <= 0:
        raise ValueError("x_mm and y_mm must be increasing")
    area = dx * dy
    force_mode = normal_force_n is not None
    if force_mode:
        load = float(normal_force_n)  # type: ignore[arg-type]
        if load <= 0:
            raise ValueError("normal_force_n must be positive")
    else:
        delta = float(approach_mm)  # type: ignore[arg-type]
        if delta <= float(h.min()):
            zero = np.zeros_like(h)
            return NormalBemResult(zero, zero, delta, 0.0, x, y, 0, True)

    warm = None
    if initial_pressure_mpa is not None:
        warm = np.maximum(np.asarray(initial_pressure_mpa, dtype=float), 0.0)
        if warm.shape != h.shape:
            raise ValueError("initial_pressure_mpa must have the shape of gap_mm")
        if not warm.sum() > 0:
            warm = None
    if warm is not None:
        p = warm.copy()
        if force_mode:
            p *= load / (area * p.sum())
    else:
        # start: pressure where the rigid interpenetration is positive, shaped like sqrt(pen)
        if force_mode:
            pen = np.maximum(np.quantile(h, 0.02) - h + 1e-12, 0.0)
        else:
            pen = np.maximum(delta - h, 0.0)
        p = np.sqrt(pen)
        if force_mode:
            p *= load / (area * p.sum())
        else:
            p *= 0.25 * np.pi * effective_modulus_mpa(young_mpa, poisson) * pen.max() / (
                p.max() * max(np.sqrt(area * np.count_nonzero(pen) / np.pi), dx))
    if compiled is None:
        compiled = polonsky_keer is not None and h.size <= DIRECT_MAX_ELEMENTS
    if compiled:
        if polonsky_keer is None:  # pragma: no cover - exercised only without numba
            raise ValueError("compiled: numba is not installed")
        dense = _dense(h.shape[1], h.shape[0], dx, dy,
                       effective_modulus_mpa(young_mpa, poisson))
        p, u, iterations, change, status = polonsky_keer(
            dense, h.ravel().copy(), p.ravel().copy(), load if force_mode else 0.0,
            0.0 if force_mode else delta, force_mode, area, tol, max_iter)
        p, u = p.reshape(h.shape), u.reshape(h.shape)
        if status == 2:
            raise RuntimeError("normal BEM: no element in contact")
        if status == 3:
            raise RuntimeError("normal BEM: pressure vanished")
        if status != 0:
            raise RuntimeError(f"normal BEM did not converge in {max_iter} iterations "
                               f"(last change {change:.2e})")
        approach = float(np.mean((u + h)[p > 0])) if force_mode else delta
        return NormalBemResult(p, u, approach, float(area * p.sum()), x, y, iterations, True)
    conv = _Convolution(h.shape[0], h.shape[1], dx, dy, effective_modulus_mpa(young_mpa, poisson))
    t = np.zeros_like(h)
    g_old = 1.0
    reset = True
    converged = False
    mean_gap = 0.0
    iterations = 0
    change = np.inf
    while iterations < max_iter:
        iterations += 1
        u = conv(p)
        g = u + h
        active = p > 0
        if not np.any(active):
            raise RuntimeError("normal BEM: no element in contact")
        if force_mode:
            mean_gap = float(g[active].mean())
            g -= mean_gap
        else:
            g -= delta
        g_norm = float(np.sum(g[active] ** 2))
        beta = 0.0 if reset else g_norm / g_old
        t = np.where(active, g + beta * t, 0.0)
        g_old = g_norm
        r = conv(t)
        if force_mode:
            r -= r[active].mean()
        denom = float(np.sum(r[active] * t[active]))
        step = float(np.sum(g[active] * t[active])) / denom if denom != 0 else 0.0
        p_old = p
        p = p - step * t
        p = np.where(p > 0, p, 0.0)
        closing = (p == 0) & (g < 0)
        reset = bool(np.any(closing))
        if reset:
            p = np.where(closing, p - step * g, p)
        if force_mode:
            total = p.sum()
            if total <= 0:
                raise RuntimeError("normal BEM: pressure vanished")
            p *= load / (area * total)
        change = float(np.abs(p - p_old).sum() / max(p.sum(), 1e-300))
        if change < tol:
            converged = True
            break
    if not converged:
        raise RuntimeError(f"normal BEM did not converge in {max_iter} iterations "
                           f"(last change {change:.2e})")
    u = conv(p)
    approach = float(np.mean((u + h)[p > 0])) if force_mode else delta
    return NormalBemResult(p, u, approach, float(area * p.sum()), x, y, iterations, converged)
