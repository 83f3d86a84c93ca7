"""What a finder reports for one cause: its held-out gain with a bootstrap interval, and the
finding (summary, evidence, fitted extension, gain, verdict flags).

Shared by the discrepancy finder of the hybrid model (:mod:`wearcast.statistics.discrepancy`)
and the physics diagnosis (:mod:`wearcast.statistics.physics_diagnosis`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wearcast.statistics.json_values import json_value


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
    """Held-out error before (the baseline) and after (the cause's extension).

    before_error, after_error : mean held-out error per measurement in the unit of ``metric``
        (the hybrid finder: log-area working residual squared and summed over both regions,
        or the wear-curve shape residual [mm²·points]; the physics diagnosis: squared FT, FH and
        qR error [mm²])
    relative : 1 - after / before; ci95_low, ci95_high : bootstrap interval over groups
    metric : 'log_area', 'wear_curve_shape' or 'ft_fh_qr_squared_error_mm2'
    calibrated_error : error of the model exactly as calibrated (hybrid finder, area metric)
    """

    before_error: float
    after_error: float
    relative: float
    ci95_low: float
    ci95_high: float
    metric: str
    calibrated_error: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"before_error": json_value(self.before_error),
                "after_error": json_value(self.after_error),
                "relative": json_value(self.relative), "ci95_low": json_value(self.ci95_low),
                "ci95_high": json_value(self.ci95_high),
                "calibrated_error": json_value(self.calibrated_error), "metric": self.metric}


@dataclass(frozen=True)
class Finding:
    """One cause: plain summary, evidence, fitted extension and gain; ``significant`` (its
    test rejects) and ``material`` (its relative gain is large enough)."""

    cause: str
    summary: str
    evidence: dict[str, Any]
    extension: dict[str, Any]
    gain: Gain
    significant: bool
    material: bool

    def to_dict(self) -> dict[str, Any]:
        return {"cause": self.cause, "summary": self.summary,
                "evidence": json_value(self.evidence), "extension": json_value(self.extension),
                "gain": self.gain.to_dict(), "significant": self.significant,
                "material": self.material}


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
