"""Scenario builder for the discrepancy-finder tests (fleet twin, calibrate, diagnose)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from wearcast.statistics.discrepancy import Diagnosis, diagnose
from wearcast.statistics.generators import scenarios, twin_wear_table
from wearcast.statistics.generators import twin_effects as te

TABLE = twin_wear_table.synthetic_wear_table()

#: Moderate strengths of every cause (the hidden-effect tests).
EFFECTS = te.moderate_effects(TABLE)


def run_scenario(wear_effects=(), profile_effects=(), seed=0, **kwargs):
    """Generate the test fleet, calibrate on unit A's motor bogies as a user would, diagnose
    (:func:`wearcast.statistics.generators.scenarios.twin_scenario`)."""
    s = scenarios.twin_scenario(wear_effects, profile_effects, seed=seed, table=TABLE)
    args, finder_kwargs = s.finder_arguments()
    diagnosis = diagnose(*args, **finder_kwargs, **kwargs)
    return s.model, s.measurements, s.wear_curves_mm, s.routes, diagnosis


@lru_cache(maxsize=16)
def cached(name: str, seed: int = 0) -> tuple:
    we, pe = EFFECTS[name]
    return run_scenario(we, pe, seed=seed)


def verdict_of(name: str, seed: int = 0) -> Diagnosis:
    return cached(name, seed)[4]


__all__ = ["EFFECTS", "TABLE", "cached", "np", "run_scenario", "verdict_of"]
