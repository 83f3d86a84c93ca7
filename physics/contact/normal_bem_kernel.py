"""The normal boundary-element solve of ``normal_bem`` compiled for small grids (numba).

``polonsky_keer(kernel, h, p, load_n, approach_mm, force_mode, area_mm2, tol, max_iter)``
runs the same conjugate-gradient active-set iteration as ``normal_bem.solve_normal_bem``
(Polonsky & Keer, Wear 231 (1999) 206-219) step for step, but computes the
surface displacement u = C p directly from the influence coefficients (Kalker's NORM / Love's
formula, ``normal_bem.influence_coefficients``: C depends on the offset between elements only)
instead of by zero-padded FFT: with the dense influence matrix of the grid
(``dense_influence``, built once per grid and cached by the caller), u = sum_j D[j] p_j over
the elements j in contact only, each row contiguous.  One product per iteration: u = C p is
kept up to date from the conjugate direction's product r = C t (the pressure moves by
-step t, so u by -step r), with the product of the few elements whose pressure was cut to 0
or that closed added, and scaled with p in force mode (C is linear): the same iteration as
recomputing u = C p every step, to rounding (the FFT solver recomputes it; the two agree to
rounding, ``benchmarks/bench_normal_bem.py`` prints the largest difference).  On the coarse
grids of the production method ("bem-coarse", at most ~26 x 26 elements) one product costs
(elements in contact) x (elements) multiply-adds, ~0.2 M, about half a numpy FFT product of
the same grid with its per-call overhead, and the whole iteration runs without returning to
Python
(``benchmarks/bench_normal_bem.py`` prints both solvers' times).  The
numpy FFT solver stays the reference and the path for large grids (the fine 0.2 mm grids);
the two agree to rounding (tests/physics/test_normal_bem.py).

Compiled with numba (a dependency); without numba ``polonsky_keer`` is None and
``solve_normal_bem`` always takes the FFT path.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

try:  # numba is a declared dependency; the numpy FFT solver is the fallback
    from numba import njit
    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    HAVE_NUMBA = False

#: Largest grid (elements) solved by the compiled direct product: above it the FFT's
#: O(N log N) wins over the direct product's O(N_contact N) (and the dense matrix, 8 N^2
#: bytes, 11.5 MB at this size, grows too large).
DIRECT_MAX_ELEMENTS = 1200


def _dense_influence_py(kernel: NDArray[np.float64], ny: int, nx: int
                        ) -> NDArray[np.float64]:
    """The influence matrix D (ny nx, ny nx) of an (ny, nx) grid from the offset kernel
    (2 ny - 1, 2 nx - 1) of ``normal_bem.influence_coefficients`` (centre [ny - 1, nx - 1]):
    D[j, i] = displacement at element i of a unit pressure on element j (symmetric), rows
    contiguous so that u = sum_j D[j] p_j runs over long contiguous rows."""
    n = ny * nx
    d = np.empty((n, n))
    _dense_influence_into(kernel, ny, nx, d)
    return d


def _dense_influence_into_py(kernel: NDArray[np.float64], ny: int, nx: int,
                             out: NDArray[np.float64]) -> None:
    """``dense_influence`` written into ``out`` (ny nx, ny nx), e.g. a recycled buffer (a
    fresh one costs a page fault per 4 kB, more than filling it)."""
    n = ny * nx
    for j in range(n):
        jy = j // nx
        jx = j - jy * nx
        dj = out[j]
        for iy in range(ny):
            # a contiguous run of the kernel's row (views: the copy vectorises)
            dj[iy * nx:(iy + 1) * nx] = kernel[iy - jy + ny - 1, nx - 1 - jx:2 * nx - 1 - jx]


def _convolve_py(d: NDArray[np.float64], p: NDArray[np.float64],
                 out: NDArray[np.float64]) -> None:
    """out = C p (flat, ny nx) with the dense influence matrix; elements with p = 0 are
    skipped (outside the contact), so the cost is (elements in contact) x (elements)."""
    out[:] = 0.0
    _convolve_add(d, p, out)


def _convolve_add_py(d: NDArray[np.float64], p: NDArray[np.float64],
                     out: NDArray[np.float64]) -> None:
    """out += C p (``_convolve_py`` without clearing ``out``)."""
    n = p.size
    for j in range(n):
        pj = p[j]
        if pj == 0.0:
            continue
        dj = d[j]
        for i in range(n):
            out[i] += dj[i] * pj


def _polonsky_keer_py(d: NDArray[np.float64], h: NDArray[np.float64],
                      p: NDArray[np.float64], load_n: float, approach_mm: float,
                      force_mode: bool, area_mm2: float, tol: float, max_iter: int
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64], int, float, int]:
    """Polonsky & Keer's CG from the start pressure p (flat, MPa, modified in place) on the
    flat gap h [mm] with the dense influence matrix d (``dense_influence``).

    Returns (p, u = C p, iterations, last relative change, status): status 0 converged,
    1 iteration limit, 2 no element in contact, 3 the pressure vanished (force mode)."""
    n = h.size
    u = np.empty(n)
    r = np.empty(n)
    g = np.empty(n)
    t = np.zeros(n)
    jump = np.zeros(n)
    g_old = 1.0
    reset = True
    iterations = 0
    change = np.inf
    status = 1
    _convolve(d, p, u)
    while iterations < max_iter:
        iterations += 1
        # u = C p here: from the full product at the start, then kept up to date
        n_active = 0
        sum_g = 0.0
        for i in range(n):
            g[i] = u[i] + h[i]
            if p[i] > 0.0:
                n_active += 1
                sum_g += g[i]
        if n_active == 0:
            status = 2
            break
        shift = sum_g / n_active if force_mode else approach_mm
        g_norm = 0.0
        for i in range(n):
            g[i] -= shift
            if p[i] > 0.0:
                g_norm += g[i] * g[i]
        beta = 0.0 if reset else g_norm / g_old
        for i in range(n):
            t[i] = g[i] + beta * t[i] if p[i] > 0.0 else 0.0
        g_old = g_norm
        _convolve(d, t, r)
        r_shift = 0.0
        if force_mode:
            for i in range(n):
                if p[i] > 0.0:
                    r_shift += r[i]
            r_shift /= n_active
        denom = 0.0
        num = 0.0
        for i in range(n):
            if p[i] > 0.0:
                denom += (r[i] - r_shift) * t[i]
                num += g[i] * t[i]
        step = num / denom if denom != 0.0 else 0.0
        reset = False
        total = 0.0
        n_jumps = 0
        diff = 0.0
        for i in range(n):
            old = p[i]
            free = old - step * t[i]
            new = free
            if not new > 0.0:
                new = 0.0
                if g[i] < 0.0:  # closing: a negative gap where there is no pressure, the
                    reset = True  # element enters the contact
                    new = -step * g[i]
            # C p_new = C p - step C t + C (p_new - (p - step t)): the last term is not 0
            # only where the pressure was cut to 0 or an element closed
            jump[i] = new - free
            if jump[i] != 0.0:
                n_jumps += 1
            u[i] -= step * r[i]
            p[i] = new
            total += new
            r[i] = old  # r keeps the old pressure for the change below
        if n_jumps > 0:
            _convolve_add(d, jump, u)
        if force_mode:
            if total <= 0.0:
                status = 3
                break
            scale = load_n / (area_mm2 * total)
            total = 0.0
            for i in range(n):
                p[i] *= scale
                u[i] *= scale  # C is linear
                total += p[i]
        for i in range(n):
            diff += abs(p[i] - r[i])
        change = diff / max(total, 1e-300)
        if change < tol:
            status = 0
            break
    _convolve(d, p, u)
    return p, u, iterations, change, status


if HAVE_NUMBA:
    _convolve_add = njit(cache=True, error_model="numpy")(_convolve_add_py)
    _convolve = njit(cache=True, error_model="numpy")(_convolve_py)
    _dense_influence_into = njit(cache=True)(_dense_influence_into_py)
    dense_influence = njit(cache=True)(_dense_influence_py)
    dense_influence_into = _dense_influence_into
    polonsky_keer = njit(cache=True, error_model="numpy")(_polonsky_keer_py)
else:  # pragma: no cover - exercised only without numba
    _convolve_add = _convolve_add_py  # type: ignore[assignment]
    _convolve = _convolve_py  # type: ignore[assignment]
    _dense_influence_into = _dense_influence_into_py  # type: ignore[assignment]
    dense_influence = _dense_influence_py  # type: ignore[assignment]
    dense_influence_into = _dense_influence_into_py  # type: ignore[assignment]
    polonsky_keer = None  # type: ignore[assignment]
