"""The fleet twin's wear-curve shapes (all lengths in mm): a wear curve of a given area per
region, the worn profile it makes of S1002 and the regions' areas of a worn profile.

Tread: hollow wear, a main bump around y = +4 mm and a smaller one around y = -12 mm (seed
001 Fig. 6/9 shows worn curves with two maxima), widening as wear grows. Flange: the flange
face is thinned horizontally by a smooth bump d(y) on -52 < y < -30 (peak near y = -41),
which moves the Sd point inwards by about d; the vertical wear curve is
w = z_ref(y) - z_ref(y + d(y)). Wear of the tread lies entirely in y >= split and of the
flange entirely in y < split, so each region's area is exact.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import S1002_Y_MAX_MM, S1002_Y_MIN_MM, s1002_height_mm

Array = NDArray[np.float64]


# Fine lateral grid on which wear curves are built and areas integrated [mm].
FINE_STEP_MM = 0.02
FINE_Y_MM = np.linspace(S1002_Y_MIN_MM, S1002_Y_MAX_MM,
                         int(round((S1002_Y_MAX_MM - S1002_Y_MIN_MM) / FINE_STEP_MM)) + 1)


def _hann(u: Array) -> Array:
    """Raised-cosine bump, 1 at u = 0, 0 for |u| >= 1."""
    return np.where(np.abs(u) < 1.0, 0.5 * (1.0 + np.cos(np.pi * np.clip(u, -1.0, 1.0))), 0.0)


def tread_wear_curve(y_mm: Array, area_mm2: float, centre_shift_mm: float = 0.0,
                     split_y_mm: float = -30.0) -> Array:
    """Hollow tread wear w(y) [mm] with exactly ``area_mm2`` over y >= split.

    A main bump at y = 4 + shift (half-width 20..28 mm, widening with wear) and a secondary
    bump at y = -12 + shift (half-width 9 mm, 35 % weight): seed 001 Fig. 6/9 (two maxima).
    Support is clipped to y in (split, +45) so that no tread wear leaks into the flange region.
    """
    y = np.asarray(y_mm, dtype=float)
    if area_mm2 <= 0.0:
        return np.zeros_like(y)
    half_width = 20.0 + 8.0 * np.tanh(area_mm2 / 80.0)
    shape = _hann((y - 4.0 - centre_shift_mm) / half_width)
    shape = shape + 0.35 * _hann((y + 12.0 - centre_shift_mm) / 9.0)
    shape = np.where((y > split_y_mm + 1.0) & (y < 45.0), shape, 0.0)
    fine = np.where((FINE_Y_MM > split_y_mm + 1.0) & (FINE_Y_MM < 45.0),
                    _hann((FINE_Y_MM - 4.0 - centre_shift_mm) / half_width)
                    + 0.35 * _hann((FINE_Y_MM + 12.0 - centre_shift_mm) / 9.0), 0.0)
    norm = float(np.trapezoid(fine, FINE_Y_MM))
    return area_mm2 * shape / norm


def _flange_thinning(y: Array, amplitude_mm: Array | float, centre_mm: float) -> Array:
    # Half-width grows with amplitude so that 1 + d'(y) > 0 (the face stays a function of y).
    amplitude = np.asarray(amplitude_mm, dtype=float)
    half_width = 10.0 + 0.6 * amplitude
    return amplitude * _hann((y - centre_mm) / half_width)


def _flange_curve_from_amplitude(y: Array, amplitude_mm: Array | float, centre_mm: float,
                                 split_y_mm: float) -> Array:
    d = _flange_thinning(y, amplitude_mm, centre_mm)
    w = s1002_height_mm(y) - s1002_height_mm(np.clip(y + d, S1002_Y_MIN_MM, S1002_Y_MAX_MM))
    return np.where((y < split_y_mm) & (y > -55.0), np.clip(w, 0.0, None), 0.0)


_FLANGE_AMPLITUDES_MM = np.linspace(0.0, 9.0, 181)
_FLANGE_AREA_CACHE: dict[tuple[float, float], Array] = {}


def _flange_area_table(centre_mm: float, split_y_mm: float) -> Array:
    key = (round(centre_mm, 3), split_y_mm)
    if key not in _FLANGE_AREA_CACHE:
        mask = (FINE_Y_MM > -56.0) & (FINE_Y_MM < split_y_mm + 0.5)
        y = FINE_Y_MM[mask]
        curves = _flange_curve_from_amplitude(y[None, :], _FLANGE_AMPLITUDES_MM[:, None],
                                              centre_mm, split_y_mm)
        _FLANGE_AREA_CACHE[key] = np.asarray(np.trapezoid(curves, y, axis=1), dtype=float)
    return _FLANGE_AREA_CACHE[key]


def flange_thinning_for_area(area_mm2: float, centre_mm: float = -41.0,
                             split_y_mm: float = -30.0) -> float:
    """Peak horizontal flange-face thinning d_max [mm] that gives a flange wear area [mm^2].

    About equal to the loss of flange thickness Sd for the default centre.
    """
    areas = _flange_area_table(centre_mm, split_y_mm)
    if area_mm2 > areas[-1]:
        raise ValueError(f"flange wear area {area_mm2:.1f} mm^2 exceeds the shape family's "
                         f"maximum {areas[-1]:.1f} mm^2 (about 9 mm of flange thinning)")
    return float(np.interp(area_mm2, areas, _FLANGE_AMPLITUDES_MM))


def flange_wear_curve(y_mm: Array, area_mm2: float, centre_mm: float = -41.0,
                      split_y_mm: float = -30.0) -> Array:
    """Flange-face wear w(y) [mm] with ``area_mm2`` over y < split.

    The face is thinned horizontally by d(y) (raised cosine, peak near y = -41 mm), so
    w = z_ref(y) - z_ref(y + d(y)) with z_ref the S1002 profile.
    """
    y = np.asarray(y_mm, dtype=float)
    if area_mm2 <= 0.0:
        return np.zeros_like(y)
    amplitude = flange_thinning_for_area(area_mm2, centre_mm, split_y_mm)
    return _flange_curve_from_amplitude(y, amplitude, centre_mm, split_y_mm)


def flange_thinning_at_sd_mm(flange_area_mm2: float, centre_mm: float = -41.0,
               split_y_mm: float = -30.0) -> float:
    """Horizontal flange-face thinning [mm] at y = -37.5 mm for a flange wear area [mm^2].

    y = -37.5 mm is where S1002's Sd is read (10 mm above the tape circle). The Sd of the worn
    profile differs from 32.5 mm minus this thinning because tread wear lowers the tape-circle
    height and so raises the Sd measuring height (EN 15313 definition).
    """
    if flange_area_mm2 <= 0.0:
        return 0.0
    amplitude = flange_thinning_for_area(flange_area_mm2, centre_mm, split_y_mm)
    return float(_flange_thinning(np.asarray([-37.5]), amplitude, centre_mm)[0])


def worn_profile_mm(y_mm: Array, tread_area_mm2: float, flange_area_mm2: float,
                    tread_shift_mm: float = 0.0, flange_centre_mm: float = -41.0,
                    split_y_mm: float = -30.0) -> Array:
    """Worn profile z(y) = S1002(y) - w_tread(y) - w_flange(y) [mm]."""
    y = np.asarray(y_mm, dtype=float)
    return (s1002_height_mm(y) - tread_wear_curve(y, tread_area_mm2, tread_shift_mm, split_y_mm)
            - flange_wear_curve(y, flange_area_mm2, flange_centre_mm, split_y_mm))


def wear_areas_mm2(y_mm: Array, z_mm: Array, split_y_mm: float = -30.0) -> tuple[float, float]:
    """(tread, flange) wear areas [mm^2] of an *aligned* profile against S1002 by trapezoid rule.

    A plain integral for checks on generated data; the statistical core's processing does
    cleaning and alignment for real measurements.
    """
    y = np.asarray(y_mm, dtype=float)
    order = np.argsort(y)
    y, w = y[order], (s1002_height_mm(y) - np.asarray(z_mm, dtype=float))[order]
    tread = y >= split_y_mm
    return float(np.trapezoid(w[tread], y[tread])), float(np.trapezoid(w[~tread], y[~tread]))
