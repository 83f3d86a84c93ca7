"""Catalogue of reference (new) wheel profiles: S1002 and its thinner-flange variants, and
profiles given as points (a drawing, or a measured new wheel).

A reference profile is a height function z(y) [mm] in the wheel frame (y from the tape
circle, back face at y = -70, negative towards the flange; z up towards the flange tip, 0 at
the tape circle), NaN where it is not defined. Wear areas and wear curves are taken against
one, and name it.

S1002 flange-thickness variants (EN 13715)
-----------------------------------------
EN 13715 gives S1002 for flange thicknesses e from 32.5 mm (the analytic profile of
:mod:`.s1002`) down to 28.5 mm; depots turn worn wheels to a thinner flange because it costs
less diameter. The standard builds a variant by translating the connection zone between tread
and flange and the flange zone next to it laterally towards the back face by 32.5 - e mm and
bridging the step this leaves with a straight line. Our construction, from the public
summaries of the standard (its figure is not reproduced here; check it before relying on the
exact shape):

* the tread (S1002 sections A and B, y >= -26 mm) stays where it is;
* the flange-root connection zone, the flange flank and the flange tip (sections C to G,
  y < -26 mm) are translated by -(32.5 - e) mm, so the flank point 10 mm above the tape
  circle moves from y = -37.5 to -37.5 - (32.5 - e): Sd = e exactly, qR stays 10.8 mm;
* the step between y = -26 - (32.5 - e) and -26 is bridged by the straight (here level)
  line at the height S1002 has at y = -26;
* the flange back (section H, the R20.5 arc meeting the back face at y = -70) belongs to the
  wheel's inner face and is not moved: the variant is the intersection of the translated
  flange with the untranslated flange-back arc (z = min of the two), which trims the tip of
  the thinnest variant by 0.015 mm (e = 28.5 mm: flange height 27.985 mm).

The 1:40 and 1:20 tread families of EN 13715 have no public analytic definition that the
project can cite, so they are not in the catalogue; give them as points instead.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.parameters import FlangeParameters, flange_parameters
from wearcast.physics.profiles.s1002 import (
    S1002_Y_MAX_MM,
    S1002_Y_MIN_MM,
    s1002_height_mm,
)

HeightFunction = Callable[[ArrayLike], NDArray[np.float64]]

#: Flange thickness of the full S1002 [mm].
S1002_FLANGE_THICKNESS_MM = 32.5
#: The flange thicknesses EN 13715 lists for S1002 [mm].
S1002_FLANGE_THICKNESSES_MM = (32.5, 31.5, 30.5, 29.5, 28.5)
#: Thinnest variant the construction accepts [mm].
S1002_MIN_FLANGE_THICKNESS_MM = 28.5
#: Lateral start of the translated zones (S1002 section C, the flange-root connection), where
#: the tread ends [mm].
S1002_ROOT_Y_MM = -26.0
#: The flange-back arc of S1002 (section H): z = A + sqrt(R^2 - (y + C)^2).
_H_A, _H_R, _H_C = 9.519259302, 20.5, 49.5

_NAME = re.compile(r"^\s*S\s*1002\s*(?:(?:[/_\-\s]|e\s*=|/e\s*=)\s*(\d{2}(?:[.,]\d+)?))?\s*$",
                   re.IGNORECASE)


@dataclass(frozen=True, eq=False)
class ReferenceProfile:
    """A reference profile of the catalogue.

    Attributes
    ----------
    name : canonical name (``S1002``, ``S1002/31.5``, or a user's name)
    height_mm : z(y) [mm] in the wheel frame, NaN outside ``y_range_mm``
    y_range_mm : lateral extent of the definition [mm]
    kind : ``analytic`` (S1002 family) or ``points`` (uploaded)
    description : how it is defined, in one sentence
    """

    name: str
    height_mm: HeightFunction
    y_range_mm: tuple[float, float]
    kind: str
    description: str

    @property
    def parameters(self) -> FlangeParameters:
        """Sd, Sh, qR [mm] of the reference itself (EN 15313 definitions)."""
        return _parameters_of(self.height_mm, self.y_range_mm)


@lru_cache(maxsize=64)
def _parameters_of(height: HeightFunction, y_range: tuple[float, float]) -> FlangeParameters:
    lo, hi = y_range
    y = np.linspace(lo, hi, int(round((hi - lo) / 0.05)) + 1)
    z = np.asarray(height(y), dtype=float)
    ok = np.isfinite(z)
    return flange_parameters(y[ok], z[ok])


def _flange_back_mm(y: NDArray[np.float64]) -> NDArray[np.float64]:
    return _H_A + np.sqrt(np.clip(_H_R**2 - (y + _H_C) ** 2, 0.0, None))


@lru_cache(maxsize=32)
def s1002_variant_height(flange_thickness_mm: float) -> HeightFunction:
    """Height function of S1002 with flange thickness e [mm] (module docstring).

    Parameters
    ----------
    flange_thickness_mm : e, 28.5 <= e <= 32.5 [mm]; 32.5 returns the analytic S1002

    Returns
    -------
    z(y) [mm], NaN outside -70 <= y <= 60 mm. The same object for the same e (cached), so
    tables built on it are cached too.
    """
    e = float(flange_thickness_mm)
    if not S1002_MIN_FLANGE_THICKNESS_MM <= e <= S1002_FLANGE_THICKNESS_MM:
        raise ValueError(f"flange_thickness_mm: {e:g} is outside the EN 13715 range "
                         f"{S1002_MIN_FLANGE_THICKNESS_MM:g} to {S1002_FLANGE_THICKNESS_MM:g} mm")
    if e == S1002_FLANGE_THICKNESS_MM:
        return s1002_height_mm
    delta = S1002_FLANGE_THICKNESS_MM - e
    root_z = float(s1002_height_mm(np.array([S1002_ROOT_Y_MM]))[0])

    def height(y_mm: ArrayLike) -> NDArray[np.float64]:
        y = np.asarray(y_mm, dtype=float)
        tread = s1002_height_mm(y)
        moved = s1002_height_mm(np.minimum(y + delta, S1002_ROOT_Y_MM - 1e-9))
        back = np.where(y <= -_H_C, _flange_back_mm(y), np.inf)
        flange = np.minimum(moved, back)
        z = np.where(y >= S1002_ROOT_Y_MM, tread,
                     np.where(y >= S1002_ROOT_Y_MM - delta, root_z, flange))
        inside = (y >= S1002_Y_MIN_MM) & (y <= S1002_Y_MAX_MM)
        return np.where(inside, z, np.nan)

    height.__name__ = f"s1002_e{e:g}_height_mm"
    return height


def canonical_s1002_name(name: str) -> str | None:
    """``S1002/<e>`` (or ``S1002`` for e = 32.5) if ``name`` spells an S1002 variant
    (``S1002``, ``s1002-31.5``, ``S1002 e=31,5``, ``S1002/31.5`` …), else None."""
    found = _NAME.match(name)
    if not found:
        return None
    if found.group(1) is None:
        return "S1002"
    e = float(found.group(1).replace(",", "."))
    return "S1002" if e == S1002_FLANGE_THICKNESS_MM else f"S1002/{e:g}"


def builtin_reference(name: str) -> ReferenceProfile | None:
    """The catalogue's S1002 variant named ``name`` (any spelling), or None.

    Raises ValueError when the name is an S1002 variant outside 28.5 to 32.5 mm.
    """
    canonical = canonical_s1002_name(name)
    if canonical is None:
        return None
    e = S1002_FLANGE_THICKNESS_MM if canonical == "S1002" else float(canonical.split("/")[1])
    height = s1002_variant_height(e)
    how = ("EN 13715 S1002, analytic (Netter/DLR piecewise definition)" if canonical == "S1002"
           else f"S1002 with the flange zones translated {S1002_FLANGE_THICKNESS_MM - e:g} mm "
           "towards the back face (EN 13715 thinner-flange construction)")
    return ReferenceProfile(canonical, height, (S1002_Y_MIN_MM, S1002_Y_MAX_MM), "analytic",
                            how)


def builtin_references() -> list[ReferenceProfile]:
    """Every built-in reference: S1002 at each EN 13715 flange thickness."""
    out = []
    for e in S1002_FLANGE_THICKNESSES_MM:
        ref = builtin_reference("S1002" if e == S1002_FLANGE_THICKNESS_MM else f"S1002/{e:g}")
        assert ref is not None
        out.append(ref)
    return out


def points_height(y_mm: ArrayLike, z_mm: ArrayLike) -> HeightFunction:
    """Height function of a profile given as points [mm] (linear between them).

    The points must be single valued in y once sorted (a drawing or a cleaned measured new
    wheel); NaN outside their lateral range.
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    order = np.argsort(y, kind="stable")
    y, z = y[order], z[order]
    if y.size < 4 or np.any(np.diff(y) <= 0.0):
        raise ValueError("points: need at least 4 points with distinct y")

    def height(q_mm: ArrayLike) -> NDArray[np.float64]:
        return np.interp(np.asarray(q_mm, dtype=float), y, z, left=np.nan, right=np.nan)

    return height


def points_reference(name: str, y_mm: ArrayLike, z_mm: ArrayLike,
                     description: str = "profile given as points") -> ReferenceProfile:
    """A reference profile from points [mm] in the wheel frame (see :func:`points_height`)."""
    y = np.asarray(y_mm, dtype=float)
    return ReferenceProfile(name, points_height(y, z_mm), (float(y.min()), float(y.max())),
                            "points", description)
