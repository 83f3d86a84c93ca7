"""The compiled bogie residual and Jacobian (``bogie_residual_kernel``) against their numpy
reference (``bogie_equations.bogie_residual``) and the solvers' forward differences, and the
compiled single-patch FASTSIM against ``fastsim_forces``.

States are drawn around a converged curving equilibrium (flange contact on the leading axle),
on the new S1002 and on a worn wheel (two-point and conformal contacts), with both creep laws,
so that every branch of the contact model is reached: unloaded slots, merged patches,
saturated creep forces.
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics import curving as cv
from wearcast.physics.bogie_equations import CompiledBogie, bogie_residual, compiled_residual
from wearcast.physics.contact.fastsim import fastsim_forces
from wearcast.physics.contact.fastsim_kernel import fastsim_totals_one
from wearcast.physics.contact.kalker import KALKER_ROW_SHAPE, KALKER_TABLE
from wearcast.physics.equilibrium_solvers import _jacobian
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicles import vehicle_preset

SCALES = np.array([3.0, 3.0, 1.0, 0.02, 0.02, 3.0, 3.0, 1.0, 0.02, 0.02, 3.0, 3.0])


def _worn(y):
    y = np.asarray(y, dtype=float)
    return s1002_height_mm(y) + 0.4 * np.exp(-((y - 5.0) / 12.0) ** 2) \
        + 0.3 * np.exp(-((y + 38.0) / 4.0) ** 2)


@pytest.fixture(scope="module")
def cases():
    vehicle = vehicle_preset("minuetto", "motor")
    out = []
    for table in (cv.vehicle_contact_table(vehicle),
                  cv.build_contact_table(_worn, vehicle.rail_profile, vehicle.rail_inclination,
                                         vehicle.wheel_radius_m)):
        res = cv.solve_curving(vehicle, 250.0, 100.0, table=table)
        rng = np.random.default_rng(7)
        q = res.saturation_state + rng.normal(size=(300, 12)) * SCALES
        params = np.column_stack([rng.uniform(-1 / 150, 1 / 150, 300),
                                  rng.uniform(-1.0, 1.0, 300),
                                  rng.uniform(-4000.0, 4000.0, 300)])
        out.append((vehicle, table, q, params))
    return out


@pytest.mark.parametrize("creep_grid", [None, 16, 7])
def test_compiled_residual_equals_the_numpy_reference(cases, creep_grid):
    for vehicle, table, q, p in cases:
        ref = bogie_residual(q, vehicle, table, p[:, 0], p[:, 1], p[:, 2],
                             creep_grid=creep_grid)
        new = compiled_residual(q, vehicle, table, p[:, 0], p[:, 1], p[:, 2],
                                creep_grid=creep_grid)
        assert new.shape == ref.shape
        # forces up to ~15 wheel loads: agreement to rounding
        assert np.max(np.abs(new - ref)) < 1e-12 * max(1.0, np.max(np.abs(ref)))
        # the states reach loaded and unloaded slots and saturated creep
        _, c = bogie_residual(q, vehicle, table, p[:, 0], p[:, 1], p[:, 2],
                              return_contacts=True, creep_grid=creep_grid)
        assert np.any(c.normal_force_n == 0) and np.any(c.normal_force_n > 0)


def test_compiled_residual_keeps_the_leading_shape_and_marks_non_finite_states(cases):
    vehicle, table, q, p = cases[0]
    new = compiled_residual(q[:6].reshape(2, 3, 12), vehicle, table, p[0, 0], p[0, 1], p[0, 2])
    ref = bogie_residual(q[:6], vehicle, table, p[0, 0], p[0, 1], p[0, 2])
    assert new.shape == (2, 3, 12)
    assert np.allclose(new.reshape(6, 12), ref, rtol=0, atol=1e-12)
    bad = q[:2].copy()
    bad[1, 4] = np.nan
    r = CompiledBogie(vehicle, table).residual(bad, p[:2])
    assert np.all(np.isfinite(r[0])) and np.all(np.isnan(r[1]))


@pytest.mark.parametrize("creep_grid", [None, 16])
def test_compiled_jacobian_is_the_forward_difference_of_the_residual(cases, creep_grid):
    # the same numbers as the solvers' finite differences of the compiled residual, bit for
    # bit: a perturbed state reuses the other wheelset's loads, which are unchanged
    for vehicle, table, q, p in cases:
        bogie = CompiledBogie(vehicle, table, creep_grid)
        steps = 1e-6 * np.maximum(1.0, np.abs(q[:20]))
        r0, jac = bogie.jacobian(q[:20], p[:20], steps)
        assert np.array_equal(r0, bogie.residual(q[:20], p[:20]))
        for i in range(20):
            def fd_residual(qq, i=i, bogie=bogie, p=p):
                return bogie.residual(qq, np.repeat(p[i:i + 1], len(qq), axis=0))

            fd = _jacobian(fd_residual, q[i])
            assert np.array_equal(jac[i], fd)
        # and a Jacobian of the numpy reference within its rounding (steps 1e-6)
        def numpy_residual(qq, vehicle=vehicle, table=table, p=p):
            return bogie_residual(qq, vehicle, table, p[0, 0], p[0, 1], p[0, 2],
                                  creep_grid=creep_grid)

        ref = _jacobian(numpy_residual, q[0])
        assert np.max(np.abs(jac[0] - ref)) < 1e-7 * max(1.0, np.max(np.abs(ref)))


def test_single_patch_fastsim_equals_the_batched_fastsim():
    rng = np.random.default_rng(11)
    n = 400
    a = rng.uniform(1.0, 9.0, n)
    b = rng.uniform(1.0, 9.0, n)
    fn = rng.uniform(0.0, 9e4, n)
    fn[:20] = 0.0
    xi, eta = rng.normal(0.0, 3e-3, n), rng.normal(0.0, 3e-3, n)
    phi = rng.normal(0.0, 3e-4, n)
    mu = rng.uniform(0.1, 0.5, n)
    for grid in (16, 5):
        ref = fastsim_forces(xi, eta, phi, a, b, fn, mu, n_x=grid, n_y=grid)
        for i in range(n):
            fx, fy, mz = fastsim_totals_one(xi[i], eta[i], phi[i], a[i], b[i], fn[i], mu[i],
                                            82_000.0, 0.28, grid, grid, 1.0 / 6.0,
                                            KALKER_TABLE, KALKER_ROW_SHAPE)
            scale = mu[i] * fn[i] + 1e-9
            assert abs(fx - ref.fx_n[i]) <= 1e-12 * scale
            assert abs(fy - ref.fy_n[i]) <= 1e-12 * scale
            assert abs(mz - ref.mz_nmm[i]) <= 1e-12 * scale * max(a[i], b[i])


def test_curving_with_the_compiled_residual_is_the_numpy_equilibrium():
    # the equilibrium found with the compiled residual satisfies the numpy equations
    vehicle = vehicle_preset("minuetto", "trailer")
    res = cv.solve_curving(vehicle, 400.0, 90.0)
    case = cv.curve_case(400.0, 90.0, None, "left", 0.58, vehicle.traction_torque_nm)
    table = cv.vehicle_contact_table(vehicle)
    r = bogie_residual(res.saturation_state[None, :], vehicle, table,
                       np.array([case.curvature_per_m]),
                       np.array([case.unbalanced_acceleration_m_s2]),
                       np.array([case.torque_nm]))
    assert float(np.linalg.norm(r)) < cv.DEFAULT_TOLERANCE
