"""Quasi-static curving: equilibrium, symmetry, linear theory, flange contact onset."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics import curving as cv
from wearcast.physics.vehicles import GRAVITY_M_S2, vehicle_preset
from wearcast.physics.wear_measures import equilibrium_wear_measures

SIGN = np.array([1.0, -1.0])  # left wheel at +y


@pytest.fixture(scope="module")
def trailer():
    return vehicle_preset("manchester", "trailer")


@pytest.fixture(scope="module")
def curve_500(trailer):
    left = cv.solve_curving(trailer, 500.0, cant_mm=80.0, direction="left")
    right = cv.solve_curving(trailer, 500.0, cant_mm=80.0, direction="right")
    return left, right


def _equilibrium(vehicle, r: cv.CurvingResult):
    """Force and moment balance recomputed from the reported contact forces and state [N, N m]."""
    kappa = 0.0 if not np.isfinite(r.radius_m) else (1.0 if r.direction == "left" else -1.0) \
        / r.radius_m
    a_unb = r.unbalanced_acceleration_m_s2
    s = SIGN[:, None]
    cos, sin = np.cos(r.contact_angle_rad), np.sin(r.contact_angle_rad)
    lat = np.sum(s * (-r.normal_force_n * sin + r.fy_n * cos), axis=(-2, -1))
    vert = np.sum(r.normal_force_n * cos + r.fy_n * sin, axis=-1)
    yaw = np.sum(-(s * r.lateral_position_mm / 1000) * r.fx_n + s * r.mz_nmm * cos / 1000,
                 axis=(-2, -1))
    pitch = np.sum(r.rolling_radius_m * r.fx_n, axis=(-2, -1))
    x = np.array([1.0, -1.0]) * vehicle.wheelbase_m / 2
    dy = (r.wheelset_shift_mm / 1000 + kappa * x**2 / 2 - r.bogie_shift_mm / 1000
          - r.bogie_yaw_rad * x)
    dpsi = r.wheelset_yaw_rad + kappa * x - r.bogie_yaw_rad
    f_prim = -2 * vehicle.primary_lateral_stiffness_n_per_m * dy
    m_prim = (-2 * vehicle.primary_longitudinal_stiffness_n_per_m
              * vehicle.primary_semi_spacing_m**2 * dpsi)
    q = vehicle.wheel_load_n
    loads = q - SIGN * q * a_unb / GRAVITY_M_S2 * vehicle.cog_height_m / 0.75
    body_yaw = -kappa * vehicle.bogie_centre_distance_m / 2
    return np.concatenate([
        lat + f_prim - vehicle.wheelset_mass_kg * a_unb,
        yaw + m_prim,
        vehicle.traction_torque_nm - pitch,
        (vert - loads[None, :]).ravel(),
        [np.sum(-f_prim) - (vehicle.bogie_mass_kg + vehicle.body_mass_kg) * a_unb,
         np.sum(-m_prim - x * f_prim)
         - vehicle.secondary_yaw_stiffness_nm_per_rad * (r.bogie_yaw_rad - body_yaw)],
    ])


def test_speed_from_unbalanced_acceleration_closed_form():
    # V^2 = R (a + g h / 1500): R = 1000 m, h = 100 mm, a = 0.58 m/s^2 (seed 001)
    v = cv.speed_from_cant_deficiency(1000.0, 100.0, 0.58)
    assert v == pytest.approx(np.sqrt(1000 * (0.58 + 9.81 * 100 / 1500)), rel=1e-12)
    case = cv.curve_case(1000.0, 100.0, None, "left", 0.58)
    assert case.unbalanced_acceleration_m_s2 == pytest.approx(0.58, rel=1e-12)
    assert cv.curve_case(1000.0, 100.0, None, "right").curvature_per_m == -1e-3
    assert np.isinf(cv.speed_from_cant_deficiency(np.inf, 0.0))


@pytest.mark.parametrize("kwargs, match", [
    ({"radius_m": -5.0}, "radius_m"), ({"radius_m": 500.0, "direction": "up"}, "direction"),
    ({"radius_m": 500.0, "cant_mm": -1.0}, "cant_mm"),
])
def test_curve_case_refuses_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        cv.curve_case(**kwargs)


def test_tangent_track_centres_symmetric_wheelsets(trailer):
    r = cv.solve_curving(trailer, None)
    assert np.allclose(r.wheelset_shift_mm, 0.0, atol=1e-6)
    assert np.allclose(r.wheelset_yaw_rad, 0.0, atol=1e-9)
    assert abs(r.bogie_shift_mm) < 1e-6 and abs(r.bogie_yaw_rad) < 1e-9
    assert np.allclose(r.normal_force_n[:, 0], r.normal_force_n[:, 1], rtol=1e-6)
    assert not np.any(r.flange_contact)
    assert r.rail_of("left") == "tangent" and r.high_rail_side is None
    # free rolling: tread measures small but non-zero (spin of the coned tread)
    assert np.all(r.t_gamma_n[r.in_contact] > 0)


@pytest.mark.parametrize("radius_m", [None, 2000.0, 500.0, 180.0])
def test_force_and_moment_equilibrium_at_the_solution(trailer, radius_m):
    r = cv.solve_curving(trailer, radius_m, cant_mm=0.0 if radius_m is None else 100.0)
    residual = _equilibrium(trailer, r)
    # solver tolerance: scaled residual norm 1e-6 of the wheel load (~0.05 N)
    assert np.max(np.abs(residual)) < 1e-6 * trailer.wheel_load_n
    assert r.residual_norm < cv.DEFAULT_TOLERANCE


def test_equilibrium_with_traction_torque():
    motor = vehicle_preset("manchester", "motor", traction_torque_nm=3000.0)
    r = cv.solve_curving(motor, 600.0, cant_mm=100.0)
    assert np.max(np.abs(_equilibrium(motor, r))) < 1e-6 * motor.wheel_load_n
    # the torque is carried by longitudinal creep forces: sum r Fx = T per axle
    assert np.sum(r.rolling_radius_m * r.fx_n, axis=(-2, -1)) == pytest.approx([3000, 3000],
                                                                               rel=1e-6)


def test_left_curve_mirrors_right_curve(curve_500):
    left, right = curve_500
    assert left.high_rail_side == "right" and right.high_rail_side == "left"
    assert np.allclose(left.wheelset_shift_mm, -right.wheelset_shift_mm, atol=1e-6)
    assert np.allclose(left.wheelset_yaw_rad, -right.wheelset_yaw_rad, atol=1e-9)
    assert left.bogie_shift_mm == pytest.approx(-right.bogie_shift_mm, abs=1e-6)
    swap = (slice(None), [1, 0])
    for name in ("normal_force_n", "t_gamma_n", "tau_max_mpa", "wheel_y_mm"):
        assert np.allclose(getattr(left, name), getattr(right, name)[swap], rtol=1e-5,
                           atol=1e-6), name
    # outward shift of the leading wheelset, high-rail wheel loaded more (cant deficiency)
    assert left.wheelset_shift_mm[0] < 0
    assert left.normal_force_n[0, 1].sum() > left.normal_force_n[0, 0].sum()


@pytest.mark.parametrize("radius_m", [2000.0, 5000.0, 10000.0])
def test_free_conical_wheelset_follows_linear_steady_curving_theory(radius_m):
    # Boocock (1969) / Wickens: a free wheelset with conical wheels rolls purely at
    # y = r0 b0 / (lambda R) towards the outer rail (b0: half the contact spacing).
    conicity = 0.05
    table = cv.build_contact_table(cv.conical_wheel(conicity))
    centre = table.candidates(0.0)
    patch = int(np.argmin(centre["gap_mm"]))
    r0_m = centre["radius_m"][patch]
    b0_m = centre["lateral_mm"][patch] / 1000
    # the table's pose includes the rigid roll (contact.geometry): the rolled cone meets the
    # curved rail crown a little further out, so its rolling-radius difference grows by ~1.7 %
    # over 2 lambda y; the theory takes that effective conicity from the table's geometry
    side = table.candidates(np.array([1.0, -1.0]))
    pick = np.argmin(side["gap_mm"], axis=-1)
    radius_diff_m = side["radius_m"][0, pick[0]] - side["radius_m"][1, pick[1]]
    effective = radius_diff_m * 1000 / 2.0
    assert effective == pytest.approx(conicity, rel=0.03)
    shift_mm, yaw_rad, xi = cv.solve_free_wheelset(table, radius_m, direction="left")
    expected_mm = -r0_m * b0_m / (effective * radius_m) * 1000
    # the cone is exactly linear, so only spin and the discretisation of the table
    # (0.1 mm shift step, 0.2 mm wheel points) separate us from the theory: 0.5 %
    assert shift_mm == pytest.approx(expected_mm, rel=5e-3)
    assert abs(yaw_rad) < 1e-5
    assert np.all(np.abs(xi) < 1e-6)  # pure rolling
    mirrored, _, _ = cv.solve_free_wheelset(table, radius_m, direction="right")
    assert mirrored == pytest.approx(-shift_mm, rel=1e-6)


def test_flange_contact_appears_on_leading_high_rail_wheel(trailer):
    wide = cv.solve_curving(trailer, 3000.0, cant_mm=100.0)
    tight = cv.solve_curving(trailer, 250.0, cant_mm=100.0)
    assert not np.any(wide.flange_contact & (wide.wheel_y_mm[..., 1] < cv.FLANGE_SPLIT_Y_MM))
    high = 1  # left curve: right wheel on the high rail
    flange = (tight.wheel_y_mm[0, high] < cv.FLANGE_SPLIT_Y_MM) & tight.in_contact[0, high]
    assert np.any(flange)
    assert np.max(np.abs(tight.contact_angle_rad[0, high][flange])) > 0.3
    # the trailing wheelset and the low-rail wheels stay on their treads
    low = tight.wheel_y_mm[:, 0][tight.in_contact[:, 0]]
    assert np.all(low >= cv.FLANGE_SPLIT_Y_MM)


def test_flange_contact_radius_brackets_the_onset(trailer):
    radius = cv.flange_contact_radius_m(trailer, cant_mm=0.0, rtol=0.01)
    assert 300.0 < radius < 3000.0

    def flanging(r_m):
        res = cv.solve_curving(trailer, r_m, cant_mm=0.0)
        part = (res.wheel_y_mm[0, 1] < cv.FLANGE_SPLIT_Y_MM) & (
            res.normal_force_n[0, 1] > 0.01 * trailer.wheel_load_n)
        return bool(np.any(part))

    assert flanging(radius * 0.97)
    assert not flanging(radius * 1.03)


def test_non_convergence_is_reported(trailer):
    with pytest.raises(cv.CurvingConvergenceError) as err:
        cv.solve_curving(trailer, 400.0, cant_mm=100.0, tol=1e-30)
    assert err.value.radius_m == pytest.approx(400.0)
    assert err.value.residual_norm > 0


def test_contact_table_agrees_with_the_rigid_geometry_with_roll():
    # Cross-check with contact.geometry (rigid S1002/60E1 1:40 contact with the roll solved):
    # for a wheelset centre shift y_c our contact shift solves y = y_c + r0 theta(y). Measured
    # agreement: tread positions within 0.5 mm (our gap is smoothed over 2 mm), roll within
    # 1 % on the tread and 20 % once the flange climbs; on the flange flank the smoothed
    # contact lags the rigid one by up to 5 mm but is on the flank (delta > 0.75 rad) too.
    from wearcast.physics.contact import geometry

    rigid = geometry.s1002_60e1(1 / 40, 460.0)
    table = cv.build_contact_table(None, "60E1", 1 / 40, 0.46)
    for y_c, pos_tol, roll_tol in [(-5.0, 0.5, 0.01), (-3.0, 0.5, 0.01), (0.0, 0.5, 0.01),
                                   (3.0, 0.5, 0.01), (6.5, 5.0, 0.2), (8.0, 5.0, 0.2)]:
        y = y_c
        for _ in range(100):
            theta = (table.rigid_rise(y) - table.rigid_rise(-y)) / 1500.0
            y = y_c + 460.0 * theta
        ours = table.candidates(y)
        k = int(np.argmin(ours["gap_mm"]))
        ref = geometry.contact_points(rigid, y_c)
        patch = min(ref.left, key=lambda p: p.gap_mm)
        assert ours["wheel_y_mm"][k] == pytest.approx(patch.y_wheel_mm, abs=pos_tol)
        if y_c != 0.0:
            assert theta == pytest.approx(ref.roll_rad, rel=roll_tol)
        if y_c > 6.0:
            assert ours["angle_rad"][k] > 0.75 and -patch.contact_angle_rad > 0.75


def test_scipy_polish_survives_non_finite_probes():
    # On badly worn profiles MINPACK may probe states where the contact table yields NaN, and a
    # NaN state made the table lookup raise IndexError (a crashed wear loop). The polish must
    # answer non-finite states with a large finite residual and report non-convergence.
    table = np.linspace(-10.0, 10.0, 21)

    def fun(q, p):  # like the contact table: indexes with the state, NaN residual far out
        idx = np.floor(q).astype(int) + 10
        out = table[np.clip(idx, 0, 20)] * 0.0 + np.arctan(q - p)
        return np.where(np.abs(q) > 5.0, np.nan, out)

    q, norm, ok = cv.scipy_polish(fun, np.array([0.2, -0.2]), np.array([0.5, -0.25]), 1e-9)
    assert ok and np.allclose(q, [0.5, -0.25])
    q, norm, ok = cv.scipy_polish(fun, np.array([np.nan, 0.0]), np.array([0.5, 0.0]), 1e-9)
    assert not ok and norm == np.inf
    q, norm, ok = cv.scipy_polish(fun, np.array([3.0, -3.0]), np.array([0.5, -0.25]), 1e-9)
    assert np.all(np.isfinite(q)) and ok == (norm < 1e-9)


def test_kik_piotrowski_width_widens_narrow_patches_only():
    # Minuetto (S1002 on 60E1 1:20) in a 162 m curve: the leading outer wheel touches the rail
    # in the flange root (S1002 section D, concave R13) on the gauge corner (convex R13), a
    # conformal pair. With the masked table (stop 30) the smoothed gap's Hertz ellipse there is
    # already wide (measured b 8.19 mm at 90 kN; the former Gaussian table's was < 1 mm wide at
    # p_mean > 3 GPa), and the Kik-Piotrowski width (the unsmoothed gap within 0.55 x the
    # approach, Kik & Piotrowski 1996) never narrows a patch: it keeps b there. On the Hertzian
    # tread patch of the tangent class it widens b by less than 25 % (KP with epsilon = 0.55 is
    # ~5 % wider than Hertz for a circular patch, more for our circular estimate of the
    # approach on elongated ellipses; measured 3.30 -> 3.88 mm).
    from wearcast.physics.class_contacts import class_contacts
    from wearcast.physics.profiles.s1002 import s1002_height_mm
    from wearcast.physics.vocabulary import CurveClass

    y = np.linspace(-70.0, 60.0, 651)
    z = s1002_height_mm(y)
    veh = vehicle_preset("minuetto")
    classes = [CurveClass(162.0, 131.0, 60.0, "left", 0.5), CurveClass(None, share=0.5)]
    hertz, _ = class_contacts(veh, classes, y, z, axle=1, side="right")
    kp, _ = class_contacts(veh, classes, y, z, axle=1, side="right",
                           patch_width="kik_piotrowski")
    root = hertz.in_contact[0] & (hertz.wheel_y_mm[0] < -30.0)
    tread = hertz.in_contact[1]
    assert root.any() and tread.any()
    assert np.all(hertz.b_mm[0][root] > 5.0)
    assert np.all(kp.b_mm[0][root] >= hertz.b_mm[0][root])
    assert np.all(kp.b_mm[1][tread] > 1.1 * hertz.b_mm[1][tread])
    assert np.all(kp.b_mm[1][tread] < 1.25 * hertz.b_mm[1][tread])
    # everything else (equilibrium, forces, creepages, a) is the curving model's
    for name in ("normal_force_n", "a_mm", "xi", "eta", "wheel_y_mm"):
        assert np.array_equal(getattr(kp, name), getattr(hertz, name))
    with pytest.raises(ValueError, match="patch_width"):
        class_contacts(veh, classes, y, z, patch_width="ellipse")


def _half_width_one_patch_at_a_time(yg, zg, rail, inclination, yw, yr, n, a, b,
                                    search_mm=12.0):
    """conformal_half_width_mm as written before it took all patches at once: a loop over
    the loaded patches (the reference the batched version must equal bit for bit)."""
    from wearcast.physics.conformal_patch_width import KIK_PIOTROWSKI_EPSILON
    from wearcast.physics.contact.hertz import effective_modulus_mpa
    from wearcast.physics.curving_table import rail_envelope

    yw, yr, n, a, b = np.broadcast_arrays(*(np.asarray(v, dtype=float)
                                            for v in (yw, yr, n, a, b)))
    ry, rz, _ = rail_envelope(rail, inclination)
    e_star = effective_modulus_mpa()
    out = b.copy()
    step = 0.05
    local = np.arange(-search_mm, search_mm + 1e-9, step)
    for idx in zip(*np.nonzero((n > 1.0) & (a > 0) & (b > 0)), strict=True):
        y = yw[idx] + local
        gap = -np.interp(y, yg, zg) - np.interp(y + (yr[idx] - yw[idx]), ry, rz,
                                                left=np.nan, right=np.nan)
        gap = np.where(np.isfinite(gap), gap, np.inf)
        centre = int(np.argmin(np.abs(local)))
        lo_win = max(0, centre - int(round(1.0 / step)))
        hi_win = min(local.size, centre + int(round(1.0 / step)) + 1)
        g_min = float(np.min(gap[lo_win:hi_win]))
        delta = 3.0 * n[idx] / (4.0 * e_star * np.sqrt(a[idx] * b[idx]))
        inside = gap <= g_min + KIK_PIOTROWSKI_EPSILON * delta
        j0 = lo_win + int(np.argmin(gap[lo_win:hi_win]))
        left = j0
        while left > 0 and inside[left - 1]:
            left -= 1
        right = j0
        while right < local.size - 1 and inside[right + 1]:
            right += 1
        slope = np.interp(yw[idx], yg, np.gradient(zg, yg))
        out[idx] = max(b[idx], 0.5 * (right - left + 1) * step * np.sqrt(1.0 + slope * slope))
    return out


def test_kik_piotrowski_width_of_all_patches_at_once_equals_one_at_a_time():
    # conformal_half_width_mm takes every loaded patch in one batch: the same numbers, bit for
    # bit, as the loop over the patches, on the loop's contacts (flange root and tread, 4
    # wheels, a tangent and two curves) and on random patches (some unloaded, some whose
    # search range leaves the rail: an infinite gap)
    from wearcast.physics.class_contacts import class_contacts_all_wheels
    from wearcast.physics.conformal_patch_width import conformal_half_width_mm
    from wearcast.physics.profiles.s1002 import s1002_height_mm
    from wearcast.physics.vocabulary import CurveClass

    y = np.linspace(-70.0, 60.0, 651)
    z = s1002_height_mm(y)
    veh = vehicle_preset("minuetto")
    classes = [CurveClass(162.0, 131.0, 60.0, "left", 0.4), CurveClass(300.0, 80.0, 60.0,
                                                                       "right", 0.3),
               CurveClass(None, share=0.3)]
    contacts, _ = class_contacts_all_wheels(veh, classes, y, z)
    rail, inc = veh.rail_profile, veh.rail_inclination
    for c in contacts.values():
        args = (c.wheel_y_mm, c.rail_y_mm, np.where(c.in_contact, c.normal_force_n, 0.0),
                c.a_mm, c.b_mm)
        want = _half_width_one_patch_at_a_time(y, z, rail, inc, *args)
        assert np.array_equal(conformal_half_width_mm(y, z, rail, inc, *args), want)
    rng = np.random.default_rng(3)
    shape = (40, 6)
    yw = rng.uniform(-45.0, 40.0, shape)
    args = (yw, yw + rng.uniform(-3.0, 3.0, shape) - 15.0,
            np.where(rng.random(shape) < 0.2, 0.0, rng.uniform(100.0, 6e4, shape)),
            rng.uniform(0.2, 8.0, shape), rng.uniform(0.05, 6.0, shape))
    want = _half_width_one_patch_at_a_time(y, z, rail, inc, *args)
    assert np.array_equal(conformal_half_width_mm(y, z, rail, inc, *args), want)
    assert np.any(want > args[4])  # some patches widened beyond Hertz


def _continuation_failing(row: int):
    """``curving.continuation_batch`` that reports case ``row`` as not converged."""
    real = cv.continuation_batch

    def fake(fun, q0, p_start, p_end, tol, **kw):
        q, norm, conv = real(fun, q0, p_start, p_end, tol, **kw)
        conv = conv.copy()
        conv[row] = False
        return q, norm, conv

    return fake


def test_failed_cases_are_skipped_in_one_batch(trailer, monkeypatch):
    # The wear loop's fallback: a case that does not converge comes back as None and the others
    # are solved in the same batch (the old path re-solved the whole batch per failure).
    cases = [cv.curve_case(r, 100.0, None, "left") for r in (300.0, 600.0, 1200.0)]
    ok = cv.solve_curving_cases_or_none(trailer, cases)
    assert all(r is not None for r in ok)

    def fail_all(fun, q0, p_start, p_end, tol, **kw):
        return q0.copy(), np.full(len(q0), np.inf), np.zeros(len(q0), dtype=bool)

    monkeypatch.setattr(cv, "continuation_batch", _continuation_failing(1))
    # the arclength continuation rescues a case the natural one lost; here it fails too
    monkeypatch.setattr(cv, "arclength_continuation_batch", fail_all)
    skipped = cv.solve_curving_cases_or_none(trailer, cases)
    assert skipped[1] is None
    for got, want in zip((skipped[0], skipped[2]), (ok[0], ok[2]), strict=True):
        assert got is not None and want is not None
        assert np.array_equal(got.state, want.state)
    with pytest.raises(cv.CurvingConvergenceError):
        cv.solve_curving_cases(trailer, cases)


def test_initial_states_restart_newton_at_the_solution(trailer):
    # A warm start from an equilibrium at the case's own load parameters returns it unchanged
    # (the wear loop's retry for points that fail the continuation on a new profile).
    cases = [cv.curve_case(r, 100.0, None, "left") for r in (300.0, 1200.0)]
    cold = cv.solve_curving_cases_or_none(trailer, cases)
    warm = cv.solve_curving_cases_or_none(trailer, cases,
                                          initial_states=[cold[0].state, None])
    assert np.allclose(warm[0].state, cold[0].state, atol=1e-9)
    assert np.array_equal(warm[1].state, cold[1].state)


def test_tau_max_in_full_slip_is_mu_p0_with_the_elliptic_bound():
    # full slip (creepage 50x the characteristic one): the traction equals mu p everywhere, so
    # tau_max = mu p0 for the Hertz (elliptic) pressure; the parabolic bound would give 4/3 of it
    a, b, fn, mu = 6.0, 4.0, 80_000.0, 0.3
    out = equilibrium_wear_measures(0.05, 0.0, 0.0, a, b, fn, 0.0, 0.0, 0.0, mu, fastsim_grid=40)
    p0 = 1.5 * fn / (np.pi * a * b)
    # the grid's element centres miss the patch centre by half an element: (1 - rho^2)^0.5 there
    assert float(out["tau_max_mpa"]) == pytest.approx(mu * p0, rel=2e-3)
    from wearcast.physics.contact.fastsim import fastsim
    parabolic = fastsim(0.05, 0.0, 0.0, a, b, fn, mu, cv.SHEAR_MODULUS_MPA, n_x=40, n_y=40)
    assert float(np.max(parabolic.shear_traction_mpa)) == pytest.approx(4 / 3 * mu * p0,
                                                                         rel=2e-3)


@pytest.mark.parametrize("wheel", ["s1002", "worn"])
def test_compiled_candidates_equal_the_numpy_reference(wheel):
    from wearcast.physics.profiles.s1002 import s1002_height_mm
    if wheel == "s1002":
        table = cv.build_contact_table(None, "60E1", 1 / 40, 0.46)
    else:  # a hollow-worn tread and a thinner flange: more minima, merged patches
        def worn(y):
            y = np.asarray(y, dtype=float)
            return s1002_height_mm(y) + 0.4 * np.exp(-((y - 5.0) / 12.0) ** 2) \
                + 0.3 * np.exp(-((y + 38.0) / 4.0) ** 2)
        table = cv.build_contact_table(worn, "60E1", 1 / 20, 0.46)
    shifts = np.random.default_rng(3).uniform(-16.0, 16.0, 400)
    ref = table._candidate_slots_numpy(shifts)
    cols = table.candidates(shifts)
    for name, r in zip(("wheel_y_mm", "gap_mm", None, "weight"), ref, strict=True):
        if name is None:
            continue
        assert np.allclose(cols[name], r, rtol=1e-9, atol=1e-9), name


def test_saturation_state_is_the_saturation_law_equilibrium(trailer, curve_500):
    # the warm start of a later solve (CurvingResult.saturation_state) is the equilibrium of the
    # smooth saturation law the solve went through, not FASTSIM's (the state)
    from wearcast.physics.bogie_equations import bogie_residual

    res = curve_500[0]
    case = cv.curve_case(500.0, 80.0, None, "left", 0.58, trailer.traction_torque_nm)
    table = cv.vehicle_contact_table(trailer)

    def norm(q, creep_grid):
        r = bogie_residual(q[None, :], trailer, table, np.array([case.curvature_per_m]),
                           np.array([case.unbalanced_acceleration_m_s2]),
                           np.array([case.torque_nm]), creep_grid=creep_grid)
        return float(np.linalg.norm(r))

    assert res.creep_grid == cv.DEFAULT_CREEP_GRID
    assert norm(res.saturation_state, None) < cv.DEFAULT_TOLERANCE
    assert norm(res.state, None) > 10 * cv.DEFAULT_TOLERANCE
    smooth = cv.solve_curving(trailer, 500.0, creep_grid=None)
    assert np.array_equal(smooth.saturation_state, smooth.state)


def test_table_rows_onto_the_wheel_grid_are_numpy_interp():
    # build_contact_table maps the geometry's gap rows onto the wheel grid in one pass
    # (_interp_rows): the same numbers as np.interp row by row, grid points and ends included
    from wearcast.physics.curving_table import _interp_rows

    rng = np.random.default_rng(5)
    xp = np.sort(rng.uniform(-60.0, 50.0, 800))
    fp = rng.normal(size=(7, 800))
    x = np.concatenate([np.arange(-55.0, 45.0001, 0.2), xp[:40], [xp[0], xp[-1], -70.0, 70.0]])
    ref = np.stack([np.interp(x, xp, row, left=100.0, right=100.0) for row in fp])
    assert np.array_equal(_interp_rows(x, xp, fp, 100.0), ref)


def test_a_case_the_natural_continuation_loses_is_followed_by_arclength(trailer, monkeypatch):
    # a case whose continuation stops (at a fold, on hollow-worn treads) is followed along the
    # curve of equilibria by the arclength continuation, to the same equilibrium here
    cases = [cv.curve_case(r, 100.0, None, "left") for r in (300.0, 600.0)]
    ok = cv.solve_curving_cases_or_none(trailer, cases)
    monkeypatch.setattr(cv, "continuation_batch", _continuation_failing(0))
    rescued = cv.solve_curving_cases_or_none(trailer, cases)
    assert rescued[0] is not None and ok[0] is not None
    np.testing.assert_allclose(rescued[0].wheelset_shift_mm, ok[0].wheelset_shift_mm, atol=1e-4)
    np.testing.assert_allclose(rescued[0].tau_max_mpa, ok[0].tau_max_mpa, rtol=1e-4, atol=1e-6)


def test_the_leading_high_rail_patch_is_the_most_loaded_one(trailer):
    res = cv.solve_curving(trailer, 300.0, cant_mm=100.0)
    patch = res.leading_high_rail_patch()
    high = cv.SIDES.index(res.high_rail_side)
    assert patch["normal_force_n"] == float(np.max(res.normal_force_n[0, high]))
    k = int(np.argmax(res.normal_force_n[0, high]))
    assert patch["wheel_y_mm"] == float(res.wheel_y_mm[0, high, k])
    assert patch["tau_max_mpa"] == float(res.tau_max_mpa[0, high, k])
    with pytest.raises(ValueError, match="source"):
        res.leading_high_rail_patch("pipeline")  # solved without the pipeline
    with pytest.raises(ValueError, match="radius_m"):
        cv.solve_curving(trailer, None).leading_high_rail_patch()
