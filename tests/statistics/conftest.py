"""Shared helpers of the statistics tests: the size of the finder's resampled max-T test on
simulated null data (a fleet of vehicles with wheels measured several times)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics import finder_scoring as fs
from wearcast.statistics.findings import FinderResult


def nested_layout(n_vehicles: int, wheels_per_vehicle: int, measurements_per_wheel: int
                  ) -> tuple[NDArray[np.int_], NDArray[np.int_]]:
    """Vehicle and wheel index of every measurement, wheels nested in vehicles."""
    vehicle = np.repeat(np.arange(n_vehicles), wheels_per_vehicle * measurements_per_wheel)
    wheel = np.repeat(np.arange(n_vehicles * wheels_per_vehicle), measurements_per_wheel)
    return vehicle, wheel


def max_t_null_p_values(covariate: NDArray[np.float64], vehicle: NDArray[np.int_],
                        wheel: NDArray[np.int_], draw_residuals: Callable[[], NDArray[np.float64]],
                        n_sets: int, rng: np.random.Generator) -> NDArray[np.float64]:
    """Adjusted p-value of ``covariate`` by the resampled max-T test (the nuisance model's 99
    draws, folds by vehicle) on each of ``n_sets`` null data sets ``draw_residuals()``
    ((n, 1) residuals without the covariate's effect)."""
    n = vehicle.size
    folds = vehicle % 5
    null_design = np.ones((n, 1))
    alt_design = np.column_stack([np.ones(n), covariate])
    p_values = []
    for _ in range(n_sets):
        r = draw_residuals()
        obs = fs.bootstrap_gains(null_design, [alt_design], r, folds)[0]
        nm = fs.NuisanceModel.fit(r - r.mean(), np.ones_like(r), vehicle, wheel)
        null = fs.bootstrap_gains(null_design, [alt_design], nm.draws(99, rng), folds)
        _, adj = fs.min_p(obs, null)
        p_values.append(adj[0])
    return np.array(p_values)


def findings_summary(d: FinderResult, digits: int = 3) -> list[tuple[str, float, float]]:
    """Each finding's cause, relative gain and p-value: the message of a verdict assertion."""
    return [(f.cause, round(f.gain.relative, digits), f.evidence["p_value"])
            for f in d.findings]
