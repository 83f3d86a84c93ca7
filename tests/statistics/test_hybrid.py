import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wearcast.statistics.hybrid import HybridModel, calibrate
from wearcast.statistics.hybrid_prediction import predict
from wearcast.statistics.route_measure import UnknownBogieTypeError, weighted_wear_measure
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM
from wearcast.statistics.wear_states import region_area_mm2
from wearcast.statistics.wear_tables import TABLE_COLUMNS, compile_wear_table, table_value

Y = np.asarray(DEFAULT_GRID_Y_MM)
SPLIT = -30.0
RADII = (250.0, 400.0, 700.0, 1500.0, 5000.0)


def make_table(flange_tangent=0.0):
    """A curve-radius table shaped like seed 001 Fig. 10: high rail and leading wheelset wear
    most, flange wear only in curves; motor bogies a little above trailer bogies."""
    rows = []
    for bogie, bf in (("motor", 1.2), ("trailer", 1.0)):
        for wheelset, wf in (("leading", 1.5), ("trailing", 0.6)):
            for measure, mf in (("tau_max", 1.0), ("t_gamma", 3.0)):
                rows.append((bogie, wheelset, "tangent", np.nan, "flange", measure, flange_tangent))
                rows.append((bogie, wheelset, "tangent", np.nan, "tread", measure, 40.0 * mf))
                for r in RADII:
                    rows.append((bogie, wheelset, "high", r, "flange", measure,
                                 bf * wf * mf * 3e4 / r))
                    rows.append((bogie, wheelset, "low", r, "flange", measure, 0.02 * mf))
                    rows.append((bogie, wheelset, "high", r, "tread", measure,
                                 mf * (40 + bf * wf * 1e4 / r)))
                    rows.append((bogie, wheelset, "low", r, "tread", measure,
                                 mf * (40 + bf * 3e3 / r)))
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)


CAL_ROUTE = Route("cal", (
    RouteClass(None, None, 0.0, 120.0, 0.5),
    RouteClass(300.0, "left", 100.0, 60.0, 0.3),   # asymmetric: left and right wheels differ
    RouteClass(600.0, "right", 60.0, 80.0, 0.2),
))


def _shapes():
    flange = np.exp(-0.5 * ((Y + 40.0) / 3.5) ** 2)
    tread = np.exp(-0.5 * (Y / 12.0) ** 2)
    return (flange / region_area_mm2(Y, flange, SPLIT, "flange"),
            tread / region_area_mm2(Y, tread, SPLIT, "tread"))


def make_fleet(table, c_true, n=800, seed=0, rel_noise=0.08, positions=None, running_mode="lead",
               measure="tau_max"):
    rng = np.random.default_rng(seed)
    positions = positions or [(b, a, s) for b in ("motor", "trailer") for a in (1, 2)
                              for s in ("left", "right")]
    wt = compile_wear_table(table)
    pos = [positions[i % len(positions)] for i in range(n)]
    s = rng.uniform(2_000, 150_000, n)
    fl, tr = _shapes()
    areas = {}
    for region in ("flange", "tread"):
        p = np.array([weighted_wear_measure(CAL_ROUTE, wt, bogie_type=b, axle=a, side=sd,
                                            running_mode=running_mode, region=region,
                                            measure=measure) for b, a, sd in pos])
        areas[region] = c_true[region] * p * s * (1 + rel_noise * rng.standard_normal(n))
    curves = areas["flange"][:, None] * fl + areas["tread"][:, None] * tr
    frame = pd.DataFrame({
        "wheel_id": [f"w{i % 64}" for i in range(n)],
        "bogie_type": [p[0] for p in pos], "axle": [p[1] for p in pos],
        "side": [p[2] for p in pos], "mileage_km": s, "route": "cal",
        "flange_area_mm2": areas["flange"], "tread_area_mm2": areas["tread"],
    })
    return frame, curves


C_TRUE = {"flange": 2e-5, "tread": 4e-6}


@pytest.fixture(scope="module")
def table():
    return make_table()


@pytest.fixture(scope="module")
def model(table):
    frame, curves = make_fleet(table, C_TRUE)
    return calibrate(frame, {"cal": CAL_ROUTE}, table, wear_curves_mm=curves,
                     measure="tau_max", running_mode="lead")


def test_weighted_measure_is_the_share_weighted_sum(table):
    # seed 001 eq. 2 by hand; right wheel, axle 1 leading: left curve -> high rail,
    # right curve -> low rail
    expected = (0.5 * table_value(table, "motor", "leading", "tangent", None, "tread", "tau_max")
                + 0.3 * table_value(table, "motor", "leading", "high", 300.0, "tread", "tau_max")
                + 0.2 * table_value(table, "motor", "leading", "low", 600.0, "tread", "tau_max"))
    got = weighted_wear_measure(CAL_ROUTE, table, bogie_type="motor", axle=1, side="right",
                                running_mode="lead", region="tread", measure="tau_max")
    assert got == pytest.approx(expected)


def test_left_curve_puts_right_wheel_on_high_rail(table):
    route = Route("l", (RouteClass(400.0, "left", 80.0, 60.0, 1.0),))
    kw = {"bogie_type": "trailer", "axle": 2, "running_mode": "lead", "region": "flange",
          "measure": "t_gamma"}
    high = table_value(table, "trailer", "trailing", "high", 400.0, "flange", "t_gamma")
    low = table_value(table, "trailer", "trailing", "low", 400.0, "flange", "t_gamma")
    assert weighted_wear_measure(route, table, side="right", **kw) == pytest.approx(high)
    assert weighted_wear_measure(route, table, side="left", **kw) == pytest.approx(low)


@settings(max_examples=25, deadline=None)
@given(shares=st.lists(st.floats(0.01, 1.0), min_size=1, max_size=5),
       radii=st.lists(st.sampled_from([260.0, 333.0, 800.0, 4000.0]), min_size=5, max_size=5),
       dirs=st.lists(st.sampled_from(["left", "right"]), min_size=5, max_size=5),
       axle=st.sampled_from([1, 2]), mode=st.sampled_from(["lead", "mixed"]))
def test_mirrored_route_with_swapped_side_gives_the_same_measure(shares, radii, dirs, axle,
                                                                 mode):
    table = compile_wear_table(make_table())
    total = sum(shares)
    classes = [RouteClass(radii[i], dirs[i], 50.0, 60.0, s / total) for i, s in enumerate(shares)]
    mirrored = [RouteClass(c.radius_m, "left" if c.direction == "right" else "right",
                           c.cant_mm, c.speed_kmh, c.share) for c in classes]
    for region in ("flange", "tread"):
        kw = {"bogie_type": "motor", "axle": axle, "running_mode": mode, "region": region,
              "measure": "tau_max"}
        a = weighted_wear_measure(Route("a", tuple(classes)), table, side="left", **kw)
        b = weighted_wear_measure(Route("b", tuple(mirrored)), table, side="right", **kw)
        assert a == pytest.approx(b, rel=1e-12)


def test_mixed_is_the_average_of_leading_and_trailing(table):
    for region in ("flange", "tread"):
        kw = {"bogie_type": "motor", "side": "left", "region": region, "measure": "tau_max"}
        lead1 = weighted_wear_measure(CAL_ROUTE, table, axle=1, running_mode="lead", **kw)
        lead2 = weighted_wear_measure(CAL_ROUTE, table, axle=2, running_mode="lead", **kw)
        mixed1 = weighted_wear_measure(CAL_ROUTE, table, axle=1, running_mode="mixed", **kw)
        mixed2 = weighted_wear_measure(CAL_ROUTE, table, axle=2, running_mode="mixed", **kw)
        assert lead1 > lead2
        assert mixed1 == pytest.approx(0.5 * (lead1 + lead2)) == pytest.approx(mixed2)


def test_calibration_recovers_the_known_factor(model):
    for region in ("flange", "tread"):
        cal = model.region(region)
        # 800 measurements with 8 % scatter: c_s to ~0.3 %; we ask for 3 standard errors
        err = abs(cal.c_s - C_TRUE[region]) / C_TRUE[region]
        assert err < 3 * cal.c_s_rel_std_error + 1e-12
        assert err < 0.01
        assert cal.c_s_rel_spread == pytest.approx(0.08, rel=0.15)
    assert model.bogie_types == ("motor", "trailer")


def test_with_equal_positions_c_s_equals_k_m_over_p_m(table):
    frame, curves = make_fleet(table, C_TRUE, n=120, positions=[("motor", 1, "left")])
    m = calibrate(frame, CAL_ROUTE, table, wear_curves_mm=curves, measure="tau_max",
                  running_mode="lead")
    for region in ("flange", "tread"):
        cal = m.region(region)
        assert cal.c_s == pytest.approx(cal.rate.rate_mm2_per_km / cal.p_m, rel=1e-9)  # eq. 3


def test_prediction_on_the_calibration_route_reproduces_the_measured_rate(model, table):
    frame, _ = make_fleet(table, C_TRUE, n=400, seed=7, positions=[("trailer", 2, "right")])
    measured = {r: np.median(frame[f"{r}_area_mm2"] / frame["mileage_km"])
                for r in ("flange", "tread")}
    pred = predict(model, CAL_ROUTE, table, bogie_type="trailer", axle=2, side="right",
                   mileage_km=[100_000.0])
    for region in ("flange", "tread"):
        rate = getattr(pred, f"{region}_area_mm2")[1, 0] / 100_000.0
        assert rate == pytest.approx(measured[region], rel=0.02)
        p10, p50, p90 = getattr(pred, f"{region}_area_mm2")[:, 0]
        assert p10 < p50 < p90


def test_tangent_track_gives_no_flange_wear(model, table):
    # seed 001 §5 / Fig. 15: on 100 % tangent track only the tread wears
    tangent = Route("tangent", (RouteClass(None, None, 0.0, 160.0, 1.0),))
    for axle in (1, 2):
        assert weighted_wear_measure(tangent, table, bogie_type="trailer", axle=axle,
                                     side="left", running_mode="mixed", region="flange",
                                     measure="tau_max") == 0.0
    pred = predict(model, tangent, table, bogie_type="trailer", axle=1, side="left",
                   mileage_km=[50_000.0, 100_000.0])
    assert np.all(pred.flange_area_mm2 == 0.0)
    assert np.all(pred.wear_mm[:, Y < SPLIT - 2.5] == 0.0)
    assert np.all(pred.tread_area_mm2[1] > 0)
    curved = predict(model, CAL_ROUTE, table, bogie_type="trailer", axle=1, side="left",
                     mileage_km=[100_000.0])
    assert curved.flange_area_mm2[1, 0] > 0


def test_prediction_profile_and_parameters(model, table):
    pred = predict(model, CAL_ROUTE, table, bogie_type="motor", axle=1, side="right",
                   mileage_km=[0.0, 60_000.0, 120_000.0])
    # new S1002: Sd 32.5, Sh 28.0, qR 10.8 mm (docs/conventions.md); the parameters come from the
    # grid
    assert pred.sd_mm[0] == pytest.approx(32.5, abs=0.05)
    assert pred.sh_mm[0] == pytest.approx(28.0, abs=0.05)
    assert pred.qr_mm[0] == pytest.approx(10.8, abs=0.05)
    # flange-flank wear thins the flange, tread wear raises the flange height
    assert pred.sd_mm[2] < pred.sd_mm[1] < pred.sd_mm[0]
    assert pred.sh_mm[2] > pred.sh_mm[1] > pred.sh_mm[0]
    # worn profile = reference - wear curve, on the full grid
    assert np.isfinite(pred.z_mm).all()
    assert np.allclose(pred.z_mm[0] - pred.z_mm[2], pred.wear_mm[2] - pred.wear_mm[0])
    json.dumps(pred.to_dict())


def test_extrapolation_flag(model, table):
    last = model.states.tread.areas_mm2[-1]
    rate = predict(model, CAL_ROUTE, table, bogie_type="motor", axle=1, side="left",
                   mileage_km=[1.0]).tread_rate_mm2_per_km[1]
    pred = predict(model, CAL_ROUTE, table, bogie_type="motor", axle=1, side="left",
                   mileage_km=[0.5 * last / rate, 3 * last / rate])
    assert pred.extrapolated.tolist() == [False, True]
    assert pred.any_extrapolated


def test_model_round_trips_and_rejects_unknown_bogie(model, table):
    back = HybridModel.from_dict(json.loads(json.dumps(model.to_dict())))
    kw = {"bogie_type": "motor", "axle": 2, "side": "left", "mileage_km": [1e4, 5e4]}
    a = predict(model, CAL_ROUTE, table, **kw)
    b = predict(back, CAL_ROUTE, table, **kw)
    assert np.array_equal(a.wear_mm, b.wear_mm) and np.array_equal(a.qr_mm, b.qr_mm)
    with pytest.raises(UnknownBogieTypeError, match="bogie_type"):
        predict(model, CAL_ROUTE, table, **{**kw, "bogie_type": "locomotive"})
    assert issubclass(UnknownBogieTypeError, ValueError)


def test_calibration_input_errors_name_the_field(table):
    frame, curves = make_fleet(table, C_TRUE, n=20)
    with pytest.raises(ValueError, match="mileage_km"):
        calibrate(frame.drop(columns="mileage_km"), CAL_ROUTE, table, wear_curves_mm=curves,
                  measure="tau_max", running_mode="lead")
    with pytest.raises(ValueError, match="running_mode"):
        calibrate(frame, CAL_ROUTE, table, wear_curves_mm=curves, measure="tau_max",
                  running_mode="backwards")
    with pytest.raises(ValueError, match="wear_curves_mm"):
        calibrate(frame, CAL_ROUTE, table, wear_curves_mm=curves[:5], measure="tau_max",
                  running_mode="lead")
    with pytest.raises(ValueError, match="route"):
        calibrate(frame, {"other": CAL_ROUTE}, table, wear_curves_mm=curves,
                  measure="tau_max", running_mode="lead")
