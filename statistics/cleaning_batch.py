""":func:`.cleaning.clean_profile` for a list of raw profiles.

The cleaning rules are written once, in :func:`.cleaning.clean_profile`; this is that function
profile by profile, with the contract the block processing once had of its vectorised copy of
the rules: a profile with a NaN or infinite coordinate and one that cannot be used get
``None``, and the caller runs ``clean_profile`` on it itself (for the note on the dropped
points, or the ``ValueError`` that says why). The block processing (:mod:`.processing_batch`)
now calls ``clean_profile`` directly. (The vectorised copy saved about 7 % of the cleaning
time of a block of 128 profiles, which did not pay for a second copy of every rule.)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.cleaning import CleanedProfile, clean_profile


def clean_profiles_batch(
    profiles: Sequence[tuple[NDArray, NDArray]],
    *,
    min_spacing_mm: float = 0.05,
    max_end_slope: float = 20.0,
    spike_mm: float = 1.0,
) -> list[CleanedProfile | None]:
    """``clean_profile`` of each raw (y_mm, z_mm) profile [mm] with finite coordinates;
    ``None`` for one with a NaN or infinite coordinate or one ``clean_profile`` refuses
    (module docstring)."""
    out: list[CleanedProfile | None] = []
    for y, z in profiles:
        ya, za = np.asarray(y, dtype=float), np.asarray(z, dtype=float)
        if not (np.isfinite(ya).all() and np.isfinite(za).all()):
            out.append(None)
            continue
        try:
            out.append(clean_profile(ya, za, min_spacing_mm=min_spacing_mm,
                                     max_end_slope=max_end_slope, spike_mm=spike_mm))
        except ValueError:
            out.append(None)
    return out
