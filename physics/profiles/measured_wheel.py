"""A measured wheel profile as the contact model's wheel.

The points are a copy of a measurement placed in the wheel frame of docs/conventions.md (y from
the tape circle, negative towards the flange; z the radius increase over the tape-circle radius,
as ``profiles.s1002.s1002_height_mm``), by the instrument's datum (``statistics.datum``):
the measurement itself is never moved. The contact model takes the height from a smoothing
spline through the points (``profiles.measured.ProfileCurve``, expected scatter
``smoothing_mm``, 0.02 mm by default, the order of a MiniProf's point scatter about a smooth
profile), sampled every 0.1 mm: on the raw points the curving continuation failed on four of
the nine reference wheels, with the spline on two
(``benchmarks/curving_measured_wheels.py``).
Equality and hashing go by content, so a MeasuredWheel keys the contact-table cache like the
name ``S1002``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.measured import ContentIdentity, ProfileCurve

#: Wheel-frame range the curving model searches for contact [mm] (flange tip to field side).
CONTACT_SEARCH_Y_MM = (-55.0, 45.0)
#: The profile must reach at least this far towards the flange [mm] (past the S1002 flange tip
#: at about -49.5 mm) and towards the field side [mm] for the contact search to be valid.
REQUIRED_COVER_Y_MM = (-50.0, 30.0)
#: Spacing of the smoothed profile's samples [mm].
SAMPLE_STEP_MM = 0.1


@dataclass(frozen=True, eq=False)
class MeasuredWheel(ContentIdentity):
    """A measured wheel profile (wheel frame, [mm]); see the module docstring.

    ``name`` says where it comes from (measurement, wheel, file).
    """

    name: str
    y_mm: NDArray[np.float64] = field(repr=False)
    z_mm: NDArray[np.float64] = field(repr=False)
    smoothing_mm: float = 0.02

    def __post_init__(self) -> None:
        y = np.asarray(self.y_mm, float).ravel()
        z = np.asarray(self.z_mm, float).ravel()
        if y.shape != z.shape or y.size < 20:
            raise ValueError("a measured wheel needs at least 20 (y, z) points of equal count")
        keep = np.isfinite(y) & np.isfinite(z)
        y, z = y[keep], z[keep]
        y, first = np.unique(y, return_index=True)  # ascending y, one height per y
        z = z[first]
        if y.size < 20:
            raise ValueError("a measured wheel needs at least 20 finite points with distinct y")
        lo, hi = REQUIRED_COVER_Y_MM
        if y[0] > lo or y[-1] < hi:
            raise ValueError(f"the profile covers y {y[0]:.1f} ... {y[-1]:.1f} mm; the contact "
                             f"search needs at least {lo:g} ... {hi:g} mm (flange tip to the "
                             "field side of the tread)")
        if self.smoothing_mm < 0:
            raise ValueError("smoothing_mm must be >= 0")
        object.__setattr__(self, "y_mm", y)
        object.__setattr__(self, "z_mm", z)
        curve = ProfileCurve.from_points(y, z, smoothing_mm=self.smoothing_mm)
        grid = np.arange(y[0], y[-1], SAMPLE_STEP_MM)
        height = curve.height_mm(grid)
        ok = np.isfinite(height)
        object.__setattr__(self, "_grid", (grid[ok], height[ok]))

    def identity_text(self) -> str:
        """The smoothing (hashed into ``digest`` after the points)."""
        return repr(self.smoothing_mm)

    def __str__(self) -> str:  # how it reads in labels and errors
        return f"measured wheel {self.name}"

    def height_mm(self, y_mm: ArrayLike) -> NDArray[np.float64]:
        """z(y) [mm] of the smoothed profile (module docstring), linear between its 0.1 mm
        samples, the end heights held beyond them."""
        grid, height = self._grid  # type: ignore[attr-defined]
        return np.interp(np.asarray(y_mm, dtype=float), grid, height)

    @property
    def search_range_mm(self) -> tuple[float, float]:
        """The part of ``CONTACT_SEARCH_Y_MM`` the profile covers [mm]."""
        return (max(CONTACT_SEARCH_Y_MM[0], float(self.y_mm[0])),
                min(CONTACT_SEARCH_Y_MM[1], float(self.y_mm[-1])))

    def on_grid(self, step_mm: float = 0.2) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(y, z) on a uniform grid over the covered range [mm] (the wear loop's start)."""
        n = int(np.floor((self.y_mm[-1] - self.y_mm[0]) / step_mm)) + 1
        y = self.y_mm[0] + step_mm * np.arange(n)
        return y, self.height_mm(y)
