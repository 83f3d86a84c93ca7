"""Equivalent conicity of a wheelset from its rolling-radius difference.

The linearised conicity that ride-stability assessments use: the first harmonic of the
rolling-radius difference Delta r(y) over a sinusoidal lateral oscillation, the principle of
EN 15302's linearisation, or the secant Delta r(y_hat) / (2 y_hat).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.geometry_results import ContactTable

_FloatArray = NDArray[np.float64]


def equivalent_conicity(table: ContactTable, amplitude_mm: ArrayLike,
                        method: str = "harmonic") -> _FloatArray:
    """Equivalent conicity of the wheelset for a lateral amplitude [mm].

    ``method="harmonic"`` (default): harmonic linearisation of Delta r(y) (the first Fourier
    coefficient of Delta r over a sinusoidal oscillation of amplitude y_hat, the principle of
    EN 15302's linearisation): lambda = 1/(2 pi y_hat) * integral_0^2pi Delta r(y_hat sin t)
    sin t dt.  ``method="secant"``: lambda = Delta r(y_hat) / (2 y_hat).  For a cone of
    half-angle tan(gamma) both give gamma.  Delta r is interpolated linearly in the table, which
    must cover +/- amplitude.
    """
    amp = np.atleast_1d(np.asarray(amplitude_mm, dtype=float))
    shifts = table.shift_mm
    order = np.argsort(shifts)
    dr = table.rolling_radius_difference_mm[order]
    shifts = shifts[order]
    if np.any(amp <= 0) or amp.max() > min(-shifts[0], shifts[-1]) + 1e-12:
        raise ValueError("amplitude must be > 0 and covered by the table's shifts on both sides")
    if method == "secant":
        return np.interp(amp, shifts, dr) / (2.0 * amp)
    if method != "harmonic":
        raise ValueError(f"unknown method {method!r}; use 'harmonic' or 'secant'")
    theta = (np.arange(512) + 0.5) * (2.0 * np.pi / 512)
    y = amp[:, None] * np.sin(theta)[None, :]
    values = np.interp(y, shifts, dr)
    first_harmonic = np.mean(values * np.sin(theta)[None, :], axis=1) * 2.0
    return first_harmonic / (2.0 * amp)
