"""The verdict's margin over the runner-up (``finder_scoring.margin_p``): a parametric
bootstrap under "the runner-up is the cause", checked on linear designs with vehicle and
wheel random effects where the truth is known."""

from __future__ import annotations

import numpy as np

from wearcast.statistics import finder_scoring as fs

N_VEHICLES, WHEELS, MEASUREMENTS = 12, 8, 5


def _layout(rng: np.random.Generator):
    n = N_VEHICLES * WHEELS * MEASUREMENTS
    vehicle = np.repeat(np.arange(N_VEHICLES), WHEELS * MEASUREMENTS)
    wheel = np.repeat(np.arange(N_VEHICLES * WHEELS), MEASUREMENTS)
    motor = (vehicle % 2 == 0).astype(float)           # half the cars carry the contrast
    load = rng.normal(0.0, 1.0, N_VEHICLES)[vehicle] + 0.5 * motor   # correlated with it
    # designs on rows (measurement, region): region intercepts + one column per cause
    null = np.zeros((n, 2, 2))
    null[:, 0, 0] = 1.0
    null[:, 1, 1] = 1.0
    traction = np.zeros((n, 2, 1))
    traction[:, 1, 0] = motor                          # tread only
    load_x = np.repeat(load[:, None, None], 2, axis=1)  # both regions
    designs = {name: np.concatenate([null, x], axis=2).reshape(2 * n, -1)
               for name, x in (("traction", traction), ("load", load_x))}
    folds = np.repeat(vehicle % 4, 2)
    return n, vehicle, wheel, null.reshape(2 * n, 2), designs, folds


def _p(truth: str, size: float, seed: int) -> float:
    """p of "traction beats load" on data carrying ``size`` x the ``truth`` column."""
    rng = np.random.default_rng(seed)
    n, vehicle, wheel, null, designs, folds = _layout(rng)
    noise = (rng.normal(0, 0.08, (N_VEHICLES, 2))[vehicle]
             + rng.normal(0, 0.1, (N_VEHICLES * WHEELS, 2))[wheel]
             + rng.standard_t(4, (n, 2)) * 0.05)
    y = noise.reshape(-1) + size * designs[truth][:, 2]
    gains = fs.bootstrap_gains(null, [designs["traction"], designs["load"]], y[:, None], folds)
    observed = float(gains[0, 0] - gains[1, 0])
    return fs.margin_p(y, np.ones((n, 2)), null, designs["traction"], designs["load"],
                       observed, vehicle, wheel, folds, 199, np.random.default_rng(seed + 1))


def test_margin_is_significant_when_the_best_cause_is_the_truth():
    ps = [_p("traction", 0.3, s) for s in range(10)]
    assert sum(p <= 0.05 for p in ps) >= 9, ps


def test_margin_rejects_at_its_level_when_the_runner_up_is_the_truth():
    # the data carry the runner-up's (load's) effect: traction's margin over it must not be
    # significant more often than the test's level allows
    ps = [_p("load", 0.1, s) for s in range(40)]
    rejected = sum(p <= 0.05 for p in ps)
    assert rejected <= 5, ps    # 40 x 0.05 = 2 expected; binomial 99 % bound is 6
