"""What a finder reports for one cause: its held-out gain with a bootstrap interval, and the
finding (summary, evidence, fitted extension, gain, verdict flags).

Shared by the discrepancy finder of the hybrid model (:mod:`wearcast.statistics.discrepancy`)
and the physics diagnosis (:mod:`wearcast.statistics.physics_diagnosis`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wearcast.statistics.json_values import fields_json


def bootstrap_gain_interval(before_by_group: ArrayLike, after_by_group: ArrayLike,
                            n_boot: int, rng: np.random.Generator) -> tuple[float, float]:
    """95 % percentile-bootstrap interval of the relative gain 1 - sum(after) / sum(before).

    The groups (vehicles, wheels or points) are resampled with replacement ``n_boot`` times;
    a resample whose baseline error sums to 0 counts as no gain.
    """
    before = np.asarray(before_by_group, dtype=float)
    after = np.asarray(after_by_group, dtype=float)
    pick = rng.integers(0, before.size, (n_boot, before.size))
    b = before[pick].sum(axis=1)
    rel = np.where(b > 0, 1.0 - after[pick].sum(axis=1) / np.where(b > 0, b, 1.0), 0.0)
    lo, hi = np.percentile(rel, [2.5, 97.5])
    return float(lo), float(hi)


@dataclass(frozen=True)
class Gain:
    """Held-out error of the finder's baseline (before) and of the cause's extension (after),
    and the relative gain with its bootstrap interval over the test groups."""

    before_error: float
    """mean held-out error per measurement of the baseline, in the unit of ``metric`` (the
    hybrid finder: log-area working residual squared and summed over both regions, or the
    wear-curve shape residual [mm²·points]; the physics diagnosis: squared FT, FH and qR error
    [mm²])"""
    after_error: float
    """mean held-out error per measurement with the cause's extension, in the unit of
    ``metric``"""
    relative: float
    """relative gain 1 - after_error / before_error [-]"""
    ci95_low: float
    """lower end of the 95 % percentile-bootstrap interval of ``relative`` over the test
    groups [-]"""
    ci95_high: float
    """upper end of the 95 % bootstrap interval of ``relative`` [-]"""
    calibrated_error: float | None = field(default=None, kw_only=True)
    """error of the model exactly as calibrated (hybrid finder, area metric; else None)"""
    metric: str
    """what the errors measure: ``log_area``, ``wear_curve_shape`` or
    ``ft_fh_qr_squared_error_mm2``"""

    def to_dict(self) -> dict[str, Any]:
        return fields_json(self)


@dataclass(frozen=True)
class Finding:
    """One cause: plain summary, evidence, fitted extension and gain; ``significant`` (its
    test rejects) and ``material`` (its relative gain is large enough)."""

    cause: str
    """code of the cause in the finder's catalogue"""
    summary: str
    """the finding in plain words: the fitted effect and the held-out gain"""
    evidence: dict[str, Any]
    """the test behind the finding: its p-values (raw and adjusted across the catalogue) and
    what the finder reports with them (the test, effect sizes, intervals, test groups)"""
    extension: dict[str, Any]
    """the extension the cause adds to the model, fitted (its parameters; what a saved
    model keeps)"""
    gain: Gain
    """held-out error before and after the extension"""
    significant: bool
    """the cause's test rejects "no effect" (p-value adjusted across the catalogue below
    the finder's alpha)"""
    material: bool
    """the relative gain is at least the finder's smallest material gain"""

    def to_dict(self) -> dict[str, Any]:
        return fields_json(self)


@dataclass(frozen=True)
class FinderResult:
    """What every finder answers: the verdict (a cause or ``none``), the findings, the causes
    it skipped with the reason, and how many measurements and test groups it used."""

    verdict: str
    findings: tuple[Finding, ...]
    skipped: dict[str, str]
    n_measurements: int
    n_groups: int
    group_by: str

    def finding(self, cause: str) -> Finding | None:
        return next((f for f in self.findings if f.cause == cause), None)

    def to_dict(self) -> dict[str, Any]:
        return {"verdict": self.verdict, "findings": [f.to_dict() for f in self.findings],
                "skipped": dict(self.skipped), "n_measurements": self.n_measurements,
                "n_groups": self.n_groups, "group_by": self.group_by}
