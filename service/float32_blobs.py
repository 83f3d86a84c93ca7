"""Arrays stored as blobs: little-endian float32 (profile points, wear curves, references).

The ``measurements`` table keeps a profile's points and its wear curve this way, the
``reference_profiles`` table a reference's points (:mod:`wearcast.service.models_db`): four
bytes a value, read back without parsing.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def f32(values: Any) -> bytes:
    """Compact blob of an array: little-endian float32."""
    return np.ascontiguousarray(values, dtype="<f4").tobytes()


def floats_of(blob: bytes) -> np.ndarray:
    """The float64 array of a blob written by :func:`f32`."""
    return np.frombuffer(blob, dtype="<f4").astype(float)


def from_f32(blob: bytes | None) -> np.ndarray | None:
    """The float64 array of a blob written by :func:`f32`; None for None."""
    return None if blob is None else floats_of(blob)
