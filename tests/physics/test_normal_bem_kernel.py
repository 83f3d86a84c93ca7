"""The compiled normal BEM (``normal_bem_kernel``: direct product with the dense influence
matrix) against the numpy FFT solver it replaces on small grids, and the warm start."""

import numpy as np
import pytest

from wearcast.physics.contact.normal_bem import influence_coefficients, solve_normal_bem
from wearcast.physics.contact.normal_bem_kernel import (
    DIRECT_MAX_ELEMENTS,
    HAVE_NUMBA,
    dense_influence,
)

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="the compiled solver needs numba")


def _conformal_gap(ny, nx, dx=0.45, dy=0.3):
    """A non-Hertzian gap on an (ny, nx) grid: a cubic and a wavy lateral term."""
    x = (np.arange(nx) - 0.5 * nx + 0.5) * dx
    y = (np.arange(ny) - 0.5 * ny + 0.3) * dy
    gap = (x[None, :] ** 2 / 460.0 + 0.004 * y[:, None] ** 2 + 0.0004 * y[:, None] ** 3
           + 0.0006 * np.sin(1.7 * y[:, None]))
    return gap, x, y


def test_dense_matrix_is_the_convolution():
    ny, nx = 5, 7
    kernel = influence_coefficients(nx, ny, 0.3, 0.2, 1.1e5)
    d = dense_influence(kernel, ny, nx)
    rng = np.random.default_rng(3)
    p = rng.random((ny, nx))
    # u_i = sum_j C(offset i - j) p_j, written out
    u = np.zeros((ny, nx))
    for jy in range(ny):
        for jx in range(nx):
            for iy in range(ny):
                for ix in range(nx):
                    u[iy, ix] += kernel[iy - jy + ny - 1, ix - jx + nx - 1] * p[jy, jx]
    np.testing.assert_allclose((p.ravel() @ d).reshape(ny, nx), u, rtol=1e-13)
    np.testing.assert_allclose(d, d.T, rtol=1e-12)  # C(-offset) = C(offset)


@pytest.mark.parametrize(("ny", "nx"), [(24, 24), (21, 26), (31, 33)])
@pytest.mark.parametrize("mode", ["force", "approach"])
def test_compiled_equals_fft(ny, nx, mode):
    gap, x, y = _conformal_gap(ny, nx)
    kw = {"normal_force_n": 15_000.0} if mode == "force" else {"approach_mm": 0.04}
    fft = solve_normal_bem(gap, x, y, tol=1e-7, compiled=False, **kw)
    direct = solve_normal_bem(gap, x, y, tol=1e-7, compiled=True, **kw)
    assert gap.size <= DIRECT_MAX_ELEMENTS
    assert direct.iterations == fft.iterations  # the same iteration, step for step
    np.testing.assert_allclose(direct.pressure_mpa, fft.pressure_mpa,
                               atol=1e-10 * fft.peak_pressure_mpa)
    assert direct.normal_force_n == pytest.approx(fft.normal_force_n, rel=1e-12)
    assert direct.approach_mm == pytest.approx(fft.approach_mm, rel=1e-10)
    # the default takes the compiled path on a grid this small
    default = solve_normal_bem(gap, x, y, tol=1e-7, **kw)
    np.testing.assert_array_equal(default.pressure_mpa, direct.pressure_mpa)


@pytest.mark.parametrize("compiled", [False, True])
def test_warm_start_converges_to_the_same_solution(compiled):
    gap, x, y = _conformal_gap(24, 24)
    cold = solve_normal_bem(gap, x, y, normal_force_n=15_000.0, tol=1e-8, compiled=compiled)
    # the solution at a 3 % smaller load as the start of the 15 kN problem
    near = solve_normal_bem(gap, x, y, normal_force_n=14_550.0, tol=1e-8, compiled=compiled)
    warm = solve_normal_bem(gap, x, y, normal_force_n=15_000.0, tol=1e-8, compiled=compiled,
                            initial_pressure_mpa=near.pressure_mpa)
    np.testing.assert_allclose(warm.pressure_mpa, cold.pressure_mpa,
                               atol=1e-5 * cold.peak_pressure_mpa)
    assert warm.approach_mm == pytest.approx(cold.approach_mm, rel=1e-6)
    assert warm.iterations < cold.iterations
    with pytest.raises(ValueError, match="shape"):
        solve_normal_bem(gap, x, y, normal_force_n=1.0, initial_pressure_mpa=np.ones((2, 2)))


@pytest.mark.parametrize(("nx", "ny", "dx", "dy"), [(20, 26, 0.2378, 0.2828), (1, 3, 0.2, 0.2),
                                                    (28, 30, 0.3, 0.2), (29, 5, 0.2, 0.2)])
def test_cached_dense_matrix_is_the_grids_own(nx, ny, dx, dy):
    """The dense matrix built from a window of the kernel cached per element size (or, past
    its width, from the grid's own kernel) is the one of the grid's own kernel exactly."""
    from wearcast.physics.contact.normal_bem import _dense

    expected = dense_influence(influence_coefficients(nx, ny, dx, dy, 1.15e5), ny, nx)
    np.testing.assert_array_equal(_dense(nx, ny, dx, dy, 1.15e5), expected)


def test_dense_matrices_are_kept_per_thread():
    """A recycled buffer must never be one another thread is solving with: each thread keeps
    its own matrices."""
    import threading

    from wearcast.physics.contact import normal_bem

    mine = normal_bem._dense(6, 5, 0.3, 0.2, 1.15e5)
    seen = {}

    def other():
        seen["empty"] = len(normal_bem._dense_cache.entries) == 0
        seen["matrix"] = normal_bem._dense(6, 5, 0.3, 0.2, 1.15e5)

    worker = threading.Thread(target=other)
    worker.start()
    worker.join()
    assert seen["empty"]
    assert seen["matrix"] is not mine
    np.testing.assert_array_equal(seen["matrix"], mine)
