"""Any wheel or rail profile given as points: a spline parameterised by arc length.

A profile is a plane curve (y(s), z(s)) with s the arc length [mm].  Parameterising by arc
length, not by y, keeps steep and even overhanging parts (flange flanks, rail flanks, a
measured flange with a lip) well posed.  Coordinates are whatever frame the points are given
in; wheels use the wheel frame of docs/conventions.md (y from the tape circle, negative towards the
flange; z the radius increase over the tape circle), rails the rail frame of
``profiles.rails`` (z up, top at (0, 0), gauge side at y < 0).

Sign conventions
----------------
* The curve is oriented so that y increases, overall, with s.
* ``tangent_angle_rad`` = atan2(dz/ds, dy/ds): 0 for a flat part, positive where z rises
  with y.  On a single-valued part ``slope = dz/dy = tan(angle)``.
* ``curvature_per_mm`` = (y' z'' - z' y'') / (y'^2 + z'^2)^1.5 (primes: d/ds), positive when
  the curve turns towards +z, i.e. z'' > 0 on a graph z(y) (a valley seen from +z).  A rail
  crown of radius R has curvature -1/R in the rail frame; the S1002 flange tip (R12) has
  -1/12 and its flange root (y = -30) about +0.044 in the wheel frame.  A surface is convex
  towards the body it touches where this curvature is negative (both frames have z pointing
  at the mating body).

Smoothing: ``smoothing_mm = 0`` interpolates (analytic profiles sampled finely); a positive
value is the expected RMS scatter of measured points about the true profile, used as the
FITPACK smoothing condition sum((y_i - y(s_i))^2 + ...) <= n * smoothing_mm^2 per coordinate.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import BSpline, UnivariateSpline, make_interp_spline

from wearcast.physics.profiles.rails import rail_profile, resample_by_arc_length
from wearcast.physics.profiles.s1002 import S1002_Y_MAX_MM, S1002_Y_MIN_MM, s1002_height_mm


class ContentIdentity:
    """Equality and hashing by content, for frozen records of measured points (``y_mm``,
    ``z_mm``): ``digest`` is the SHA-256 of the points (little-endian float64) and of
    ``identity_text()`` (what else sets the record's meaning), so equal content keys the
    same contact-table cache entry."""

    y_mm: NDArray[np.float64]
    z_mm: NDArray[np.float64]

    def identity_text(self) -> str:
        """The record's other content, hashed after the points."""
        raise NotImplementedError

    @cached_property
    def digest(self) -> str:
        """SHA-256 of the points and ``identity_text()`` (content identity)."""
        h = hashlib.sha256()
        h.update(np.ascontiguousarray(self.y_mm, "<f8").tobytes())
        h.update(np.ascontiguousarray(self.z_mm, "<f8").tobytes())
        h.update(self.identity_text().encode())
        return h.hexdigest()

    def __eq__(self, other: object) -> bool:
        return isinstance(other, type(self)) and other.digest == self.digest

    def __hash__(self) -> int:
        return hash(self.digest)


#: Arc-length step of the dense lookup table used to invert y(s) [mm].
_LOOKUP_STEP_MM = 0.05


@dataclass(frozen=True, eq=False)
class ProfileCurve:
    """A profile as an arc-length spline; build with ``from_points`` (or ``s1002_curve``,
    ``rail_curve``).  Lengths in [mm]."""

    length_mm: float
    _y: BSpline | UnivariateSpline = field(repr=False)
    _z: BSpline | UnivariateSpline = field(repr=False)
    _lookup: tuple[NDArray[np.float64], NDArray[np.float64]] = field(repr=False)

    @classmethod
    def from_points(cls, y_mm: ArrayLike, z_mm: ArrayLike,
                    smoothing_mm: float = 0.0) -> ProfileCurve:
        """Fit a profile curve through ordered points.

        Parameters
        ----------
        y_mm, z_mm : profile points [mm] in order along the profile (either direction);
            consecutive duplicates are dropped
        smoothing_mm : expected RMS scatter of the points [mm]; 0 interpolates

        Returns
        -------
        ProfileCurve with y increasing (overall) along the arc length.
        """
        y = np.asarray(y_mm, dtype=float).ravel()
        z = np.asarray(z_mm, dtype=float).ravel()
        if y.shape != z.shape:
            raise ValueError("y_mm and z_mm must have the same length")
        finite = np.isfinite(y) & np.isfinite(z)
        y, z = y[finite], z[finite]
        if y.size < 4:
            raise ValueError("a profile needs at least 4 finite points")
        if smoothing_mm < 0:
            raise ValueError("smoothing_mm must be >= 0")
        if y[-1] < y[0]:
            y, z = y[::-1], z[::-1]
        chord = np.hypot(np.diff(y), np.diff(z))
        keep = np.concatenate([[True], chord > 1e-9])
        y, z = y[keep], z[keep]
        s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))])
        if smoothing_mm == 0.0:
            spline_y: BSpline | UnivariateSpline = make_interp_spline(s, y, k=3)
            spline_z: BSpline | UnivariateSpline = make_interp_spline(s, z, k=3)
        else:
            condition = y.size * smoothing_mm**2
            spline_y = UnivariateSpline(s, y, k=3, s=condition)
            spline_z = UnivariateSpline(s, z, k=3, s=condition)
        length = float(s[-1])
        s_dense = np.linspace(0.0, length, max(int(length / _LOOKUP_STEP_MM) + 1, 8))
        return cls(length, spline_y, spline_z, (s_dense, np.asarray(spline_y(s_dense))))

    # --- by arc length -------------------------------------------------------------------
    def point(self, s_mm: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(y, z) [mm] at arc length(s) s [mm]."""
        s = np.asarray(s_mm, dtype=float)
        return np.asarray(self._y(s)), np.asarray(self._z(s))

    def _derivatives(self, s: NDArray[np.float64], order: int) -> tuple[NDArray, NDArray]:
        return np.asarray(self._y.derivative(order)(s)), np.asarray(self._z.derivative(order)(s))

    def tangent_angle_at(self, s_mm: ArrayLike) -> NDArray[np.float64]:
        """Tangent angle atan2(dz, dy) [rad] at arc length(s) s [mm]."""
        dy, dz = self._derivatives(np.asarray(s_mm, dtype=float), 1)
        return np.arctan2(dz, dy)

    def curvature_at(self, s_mm: ArrayLike) -> NDArray[np.float64]:
        """Signed curvature [1/mm] at arc length(s) s [mm] (positive turning towards +z)."""
        s = np.asarray(s_mm, dtype=float)
        dy, dz = self._derivatives(s, 1)
        ddy, ddz = self._derivatives(s, 2)
        return (dy * ddz - dz * ddy) / np.hypot(dy, dz) ** 3

    def sample(self, step_mm: float) -> NDArray[np.float64]:
        """Arc lengths [mm] evenly spaced by about ``step_mm`` over the whole curve."""
        return np.linspace(0.0, self.length_mm, max(int(np.ceil(self.length_mm / step_mm)) + 1, 2))

    # --- by lateral position --------------------------------------------------------------
    def arc_length_at(self, y_mm: ArrayLike) -> NDArray[np.float64]:
        """Arc length s [mm] of the point with lateral position y [mm].

        NaN where y is outside the profile or where the profile is not single valued in y
        (an overhang: several points share that y).
        """
        y_q = np.atleast_1d(np.asarray(y_mm, dtype=float))
        s_d, y_d = self._lookup
        increasing = np.diff(y_d) > 0
        result = np.full(y_q.shape, np.nan)
        hits = np.zeros(y_q.shape, dtype=int)
        # monotone runs of the dense table; count how many runs cover each query
        edges = np.flatnonzero(np.diff(increasing.astype(int))) + 1
        starts = np.concatenate([[0], edges])
        stops = np.concatenate([edges, [increasing.size]])
        for start, stop in zip(starts, stops, strict=True):
            ys = y_d[start:stop + 1]
            ss = s_d[start:stop + 1]
            if not increasing[start]:
                ys, ss = ys[::-1], ss[::-1]
            inside = (y_q >= ys[0]) & (y_q <= ys[-1])
            if ys[-1] - ys[0] <= 0:
                continue
            hits += inside
            result = np.where(inside, np.interp(y_q, ys, ss), result)
        result = np.where(hits == 1, result, np.nan)
        # Newton polish on y(s) = y_q (the table is linear between 0.05 mm knots)
        ok = np.isfinite(result)
        s = np.where(ok, result, 0.0)
        for _ in range(2):
            dy = np.asarray(self._y.derivative(1)(s))
            step = (np.asarray(self._y(s)) - y_q) / np.where(np.abs(dy) > 1e-12, dy, np.nan)
            s = np.clip(s - np.where(ok, np.nan_to_num(step), 0.0), 0.0, self.length_mm)
        out = np.where(ok, s, np.nan)
        return out.reshape(np.shape(y_mm)) if np.ndim(y_mm) else out

    def height_mm(self, y_mm: ArrayLike) -> NDArray[np.float64]:
        """z(y) [mm] where the profile is single valued in y, NaN elsewhere."""
        s = self.arc_length_at(y_mm)
        z = np.asarray(self._z(np.nan_to_num(s)))
        return np.where(np.isfinite(s), z, np.nan)

    def slope(self, y_mm: ArrayLike) -> NDArray[np.float64]:
        """dz/dy [-] at lateral position y [mm] (NaN where not single valued)."""
        s = self.arc_length_at(y_mm)
        dy, dz = self._derivatives(np.nan_to_num(s), 1)
        return np.where(np.isfinite(s), dz / dy, np.nan)

    def curvature_per_mm(self, y_mm: ArrayLike) -> NDArray[np.float64]:
        """Signed curvature [1/mm] at lateral position y [mm] (see module docstring)."""
        s = self.arc_length_at(y_mm)
        return np.where(np.isfinite(s), self.curvature_at(np.nan_to_num(s)), np.nan)


def s1002_curve(step_mm: float = 0.1, y_min_mm: float = S1002_Y_MIN_MM,
                y_max_mm: float = S1002_Y_MAX_MM) -> ProfileCurve:
    """S1002 wheel profile (wheel frame of docs/conventions.md) as an interpolating arc-length
    spline.

    Parameters
    ----------
    step_mm : arc-length spacing of the analytic samples the spline passes through [mm]
    y_min_mm, y_max_mm : lateral extent [mm] (default the whole definition, -70 ... 60)
    """
    y = np.linspace(y_min_mm, y_max_mm, int(round((y_max_mm - y_min_mm) / 0.005)) + 1)
    z = s1002_height_mm(y)
    ys, zs = resample_by_arc_length(y, z, step_mm)
    return ProfileCurve.from_points(ys, zs)


def rail_curve(name: str = "60E1", inclination: float = 0.0,
               step_mm: float = 0.1) -> ProfileCurve:
    """A rail head (``profiles.rails``) as an interpolating arc-length spline, rail frame.

    Parameters
    ----------
    name : ``"60E1"`` or ``"60E2"``
    inclination : rail inclination slope (0 = upright, 1/40, 1/20), turned about the top
    step_mm : arc-length spacing of the analytic samples [mm]
    """
    y, z = rail_profile(name, step_mm=step_mm, inclination=inclination)
    return ProfileCurve.from_points(y, z)
