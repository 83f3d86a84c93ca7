"""The parameter-surface first guess of the reprofiling search against the full search.

``_first_crossings`` estimates each crossing on the model's bilinear Sd/Sh/qR surface and
evaluates exact profiles only on a narrow bracket around it (falling back to the geometric
search when the bracket misses). Both paths must give the same crossing to within the
promised max(MILEAGE_RTOL · mileage, MILEAGE_ATOL_KM) and the same governing limit.
"""

from __future__ import annotations

import importlib.util
import itertools
from pathlib import Path

import numpy as np
import pytest

from wearcast.statistics import reprofiling
from wearcast.statistics.hybrid_prediction import region_rates
from wearcast.statistics.hybrid_profiles import parameters_at_areas
from wearcast.statistics.profile_parameters import WheelLimits
from wearcast.statistics.reprofiling import MILEAGE_ATOL_KM, MILEAGE_RTOL, _first_crossings
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_tables import compile_wear_table

_spec = importlib.util.spec_from_file_location(
    "_perf_reprofiling", Path(__file__).with_name("test_perf_reprofiling.py"))
perf = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(perf)

ROUTES = [perf.ROUTE, perf.TANGENT] + [
    Route("mixed", (RouteClass(None, None, 0.0, 100.0, 1.0 - share),
                    RouteClass(radius, direction, 60.0, 60.0, share)))
    for radius, direction, share in [(300.0, "left", 0.1), (800.0, "right", 0.5),
                                     (2000.0, "left", 0.9)]]


@pytest.fixture(scope="module")
def table():
    return compile_wear_table(perf._table())


def test_surface_interpolates_the_exact_parameters():
    model = perf._model()
    surface = model.parameter_surface
    assert surface is model.parameter_surface  # computed once per model
    # at the nodes the surface is exact (undefined parameters aside)
    fa, ta = np.meshgrid(surface.flange_mm2[::7], surface.tread_mm2[::5], indexing="ij")
    exact, _ = parameters_at_areas(model, fa.ravel(), ta.ravel())
    got, inside = surface.at(fa.ravel(), ta.ravel())
    ok = np.isfinite(exact).all(axis=1)
    assert inside.all() and ok.any()
    np.testing.assert_allclose(got[ok], exact[ok], atol=1e-9)
    # between the nodes it is close to the exact parameters: a first guess only (measured
    # here: median 0.002 mm, 90 % below 0.013 mm; up to 2.7 mm on badly worn flanges where
    # Sd/qR jump between grid points); points beyond its edge are flagged
    rng = np.random.default_rng(5)
    fa = rng.uniform(0.0, surface.flange_mm2[-1] / 2, 300)
    ta = rng.uniform(0.0, surface.tread_mm2[-1] / 2, 300)
    exact, _ = parameters_at_areas(model, fa, ta)
    got, inside = surface.at(fa, ta)
    ok = np.isfinite(exact).all(axis=1)
    assert ok.mean() > 0.5
    err = np.abs(got[ok] - exact[ok]).max(axis=1)
    assert np.median(err) < 0.01
    assert np.quantile(err, 0.9) < 0.05
    _, inside = surface.at(np.array([surface.flange_mm2[-1] * 1.01, 1.0]),
                           np.array([1.0, surface.tread_mm2[-1] * 1.01]))
    assert not inside.any()


def _cases():
    rng = np.random.default_rng(17)
    for cs, rel in itertools.product([(1e-5, 2e-6), (5e-5, 2e-5), (1e-4, 1e-6), (3e-6, 3e-5)],
                                     [0.05, 0.3]):
        limits = [WheelLimits(), WheelLimits(qr_min_mm=9.5),
                  WheelLimits(sd_min_mm=28.0, sh_max_mm=30.0),
                  WheelLimits(sd_min_mm=float(rng.uniform(18, 32)),
                              sh_max_mm=float(rng.uniform(29, 40)),
                              qr_min_mm=float(rng.uniform(4, 11)))]
        starts = [{"flange": 0.0, "tread": 0.0}, {"flange": 5.0, "tread": 20.0},
                  {"flange": float(rng.uniform(0, 80)), "tread": float(rng.uniform(0, 250))}]
        yield cs, rel, limits, starts


@pytest.mark.parametrize("case", list(_cases()), ids=lambda c: f"{c[0]}-{c[1]}")
def test_surface_guess_gives_the_full_search_crossing(case, table, monkeypatch):
    (c_f, c_t), rel, limits, starts = case
    model = perf._model(c_f, c_t, rel)
    calls = {"estimated": 0, "rows": 0}
    estimates = reprofiling._surface_estimates

    def counting(*args, **kwargs):
        est = estimates(*args, **kwargs)
        calls["estimated"] += int(np.isfinite(est).sum())
        calls["rows"] += est.size
        return est

    monkeypatch.setattr(reprofiling, "_surface_estimates", counting)
    for route, side, lim, start in itertools.product(ROUTES, ("left", "right"), limits,
                                                     starts):
        _, rates = region_rates(model, route, table, side=side, quantiles=(0.9, 0.5, 0.1),
                                **perf.KW)
        fast = _first_crossings(model, start, rates, lim, 3e6)
        full = _first_crossings(model, start, rates, lim, 3e6, use_surface=False)
        for f, e in zip(fast, full, strict=True):
            assert f.governing_limit == e.governing_limit
            assert f.extrapolated == e.extrapolated
            if not np.isfinite(e.mileage_km) or e.mileage_km == 0.0:
                assert f.mileage_km == e.mileage_km
                continue
            # promised: max(0.1 %, 50 km); measured on these cases below 3e-6 relative
            assert abs(f.mileage_km - e.mileage_km) <= max(MILEAGE_RTOL * e.mileage_km,
                                                           MILEAGE_ATOL_KM)
            assert f.mileage_km == pytest.approx(e.mileage_km, rel=1e-4)
            for got, want in zip((f.sd_mm, f.sh_mm, f.qr_mm), (e.sd_mm, e.sh_mm, e.qr_mm),
                                 strict=True):
                assert got == pytest.approx(want, abs=1e-2)
    # the surface path is taken (not only the fallback) for most rate sets
    assert calls["estimated"] > 0.4 * calls["rows"]


def test_a_missed_bracket_falls_back_to_the_full_search(table, monkeypatch):
    model = perf._model()
    _, rates = region_rates(model, perf.ROUTE, table, side="right",
                            quantiles=(0.9, 0.5, 0.1), **perf.KW)
    start = {"flange": 0.0, "tread": 0.0}
    full = _first_crossings(model, start, rates, WheelLimits(), 3e6, use_surface=False)
    good = reprofiling._surface_estimates(model, start, rates, WheelLimits(), 3e6)
    for factor in (0.5, 2.0, 1e-3):  # estimates far too early or too late
        monkeypatch.setattr(reprofiling, "_surface_estimates",
                            lambda *a, factor=factor, **k: good * factor)
        fast = _first_crossings(model, start, rates, WheelLimits(), 3e6)
        for f, e in zip(fast, full, strict=True):
            assert f.governing_limit == e.governing_limit
            assert abs(f.mileage_km - e.mileage_km) <= max(MILEAGE_RTOL * e.mileage_km,
                                                           MILEAGE_ATOL_KM)
