"""Turning a worn wheel: the radial cut that restores a target profile, the economic target,
and the wheel's remaining life in turnings and kilometres.

Frame: the wheel frame of the profile readers, y [mm] from the tape circle (back face at
y = -70, fixed on the lathe: a turning never moves it), z [mm] radius over the tape circle.
A worn profile's heights are taken from its own tape-circle height z_w(0), as measured (the
MiniProf zeroes its Y at the taperline); a target profile's heights from its tape circle.

**Cut.** Turning to a target profile t leaves the wheel with the radius R' + z_t(y), where R'
is the new tape-circle radius; material must exist wherever the tool cuts, so
R' + z_t(y) <= R_w + z_w(y) - z_w(0) at every y where both profiles are defined. The
smallest radial cut (tape-circle radius removed) is therefore

    c = R_w - R' = max_y [ z_t(y) - (z_w(y) - z_w(0)) ]

and the diameter loss is 2 c. The maximum is taken over a 0.05 mm grid of the overlap of
the two profiles plus every measured point inside it (the worn profile is the polyline
through its points; the target is evaluated exactly) inside ``CHECK_RANGE_Y_MM``, from the
flange tip's inner end to the end of the tread, leaving out where the target is steeper
than ``MAX_CHECK_SLOPE`` (3:1). Not checked: the back of the flange towards the back face and
the outer chamfer beyond the tread. Neither is in wheel-rail contact, the lathe restores
them in the same pass, and on a measured wheel they carry what the frame cannot know (a
datum's lateral error on the near-vertical flange back, the rim's own chamfer): on the real
MiniProf wheels they otherwise bound the cut at y = -68.5 or +60 mm for every target. On a
steep flank a height difference measures a lateral one (a tenth of a millimetre of
sampling moves it by tenths of a millimetre); the flange face of S1002 (70°, slope 2.75)
is checked. A cut below zero (the worn wheel has
more material than the target everywhere, never the case after wear) is reported as is.

**Targets.** S1002 (EN 13715) and its thinner-flange variants from the reference catalogue
(:func:`wearcast.physics.profiles.references.s1002_variant_height`), unless the caller gives
its own heights. A variant's flange is translated towards the back face with its tip, so on a
wheel whose flange back is unworn the tip of a thin variant stands up to about 0.5 mm over the
old flange back and the cut there can bind.

**Economic choice.** For each target that restores every limit, the kilometres until the
first limit is reached again (the restored margins over the wheel's wear rates) per
millimetre of diameter the turning and that wear cost; the economic target has the most
kilometres per millimetre, the frugal one the least diameter loss.

**Life.** With the same cut and wear every cycle, the number of turnings before the tape-
circle diameter would go below the scrap diameter and the kilometres they give.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.parameters import flange_parameters, tape_circle_height_mm
from wearcast.physics.profiles.references import (
    S1002_FLANGE_THICKNESS_MM,
    S1002_FLANGE_THICKNESSES_MM,
    s1002_variant_height,
)
from wearcast.physics.profiles.s1002 import S1002_Y_MAX_MM, S1002_Y_MIN_MM, s1002_height_mm
from wearcast.statistics.maintenance.limits import FLANGE_LIMITS, FleetLimits

Heights = Callable[[ArrayLike], NDArray[np.float64]]
#: The worn profile must cover this lateral range [mm] (flange tip to the outer tread).
REQUIRED_COVERAGE_MM = (-60.0, 25.0)
GRID_STEP_MM = 0.05
#: Target slopes |dz/dy| above which the cut is not checked (the flange back).
MAX_CHECK_SLOPE = 3.0
#: Where the cut is checked [mm]: from the inner end of the S1002 flange-tip arc to the end
#: of its tread (the section boundaries of the Netter/DLR piecewise form).
CHECK_RANGE_Y_MM = (-62.764705882, 32.15796)


@dataclass(frozen=True)
class TargetProfile:
    """A profile a wheel can be turned to: its name, heights and flange parameters [mm]."""

    name: str
    heights: Heights
    sd_mm: float
    sh_mm: float
    qr_mm: float
    y_min_mm: float = S1002_Y_MIN_MM
    y_max_mm: float = S1002_Y_MAX_MM


def _target(name: str, heights: Heights) -> TargetProfile:
    y = np.arange(S1002_Y_MIN_MM, S1002_Y_MAX_MM + 1e-9, 0.1)
    p = flange_parameters(y, heights(y))
    return TargetProfile(name, heights, p.sd_mm, p.sh_mm, p.qr_mm)


def s1002_targets(thicknesses_mm: Sequence[float] = S1002_FLANGE_THICKNESSES_MM
                  ) -> list[TargetProfile]:
    """S1002 and its EN 13715 thinner-flange variants from the reference catalogue (names
    ``S1002`` and ``S1002/e<Sd>``); raises ValueError "flange_thickness_mm: ..." outside
    28.5 to 32.5 mm."""
    out = []
    for e in thicknesses_mm:
        name = "S1002" if e == S1002_FLANGE_THICKNESS_MM else f"S1002/e{e:g}"
        out.append(_target(name, s1002_variant_height(float(e))))
    return out


@dataclass(frozen=True)
class Cut:
    """The smallest cut restoring one target: radial [mm], diameter loss [mm], where it
    binds (y [mm]) and the lateral range it was checked on [mm]."""

    target: str
    radial_mm: float
    diameter_loss_mm: float
    binding_y_mm: float
    checked_y_mm: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return {"target": self.target, "radial_mm": self.radial_mm,
                "diameter_loss_mm": self.diameter_loss_mm, "binding_y_mm": self.binding_y_mm,
                "checked_y_mm": list(self.checked_y_mm)}


def _polyline(y_mm: ArrayLike, z_mm: ArrayLike) -> tuple[NDArray, NDArray]:
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    ok = np.isfinite(y) & np.isfinite(z)
    y, z = y[ok], z[ok]
    order = np.argsort(y, kind="stable")
    y, z = y[order], z[order]
    if y.size < 5:
        raise ValueError("profile: needs at least 5 points")
    return y, z


def turning_cut(worn_y_mm: ArrayLike, worn_z_mm: ArrayLike, target: TargetProfile) -> Cut:
    """The smallest radial cut that restores ``target`` on a worn profile (module docstring).

    Raises ValueError "profile: ..." when the worn profile does not cover
    ``REQUIRED_COVERAGE_MM`` (the cut could not be checked where it matters).
    """
    y, z = _polyline(worn_y_mm, worn_z_mm)
    lo_req, hi_req = REQUIRED_COVERAGE_MM
    if y[0] > lo_req or y[-1] < hi_req:
        raise ValueError(f"profile: covers y {y[0]:.1f} to {y[-1]:.1f} mm; the cut needs "
                         f"{lo_req:g} to {hi_req:g} mm")
    z_rel = z - tape_circle_height_mm(y, z)
    lo = max(y[0], target.y_min_mm, CHECK_RANGE_Y_MM[0])
    hi = min(y[-1], target.y_max_mm, CHECK_RANGE_Y_MM[1])
    grid = np.arange(lo, hi + 1e-9, GRID_STEP_MM)
    inside = y[(y >= lo) & (y <= hi)]
    grid = np.union1d(grid, inside)
    zt, checked = _target_on(target, grid)
    excess = np.where(checked, zt - np.interp(grid, y, z_rel), np.nan)
    k = int(np.nanargmax(excess))
    c = float(excess[k])
    return Cut(target.name, c, 2.0 * c, float(grid[k]), (float(lo), float(hi)))


_TARGET_CACHE: dict[tuple[str, int, bytes], tuple[NDArray, NDArray]] = {}
_TARGET_CACHE_SIZE = 64


def _target_on(target: TargetProfile, grid: NDArray) -> tuple[NDArray, NDArray]:
    """Target heights on ``grid`` and where they are checked (slope <= MAX_CHECK_SLOPE),
    kept for the last few grids (a plan evaluates each wheel's grid many times)."""
    key = (target.name, id(target.heights), grid.tobytes())
    found = _TARGET_CACHE.get(key)
    if found is None:
        zt = target.heights(grid)
        found = (zt, np.abs(np.gradient(zt, grid)) <= MAX_CHECK_SLOPE)
        if len(_TARGET_CACHE) >= _TARGET_CACHE_SIZE:
            _TARGET_CACHE.pop(next(iter(_TARGET_CACHE)))
        _TARGET_CACHE[key] = found
    return found


def projected_profile(y_mm: ArrayLike, z_mm: ArrayLike, factor: float,
                      reference: Heights = s1002_height_mm) -> NDArray[np.float64]:
    """Worn heights [mm] with the wear against ``reference`` scaled by ``factor`` (linear
    wear progression: the wear areas grow linearly with mileage, seed 001 eq. 4). Heights
    are in the worn profile's own tape-circle frame."""
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    z_rel = z - tape_circle_height_mm(*_polyline(y, z))
    ref = reference(y)
    return ref - float(factor) * (ref - z_rel)


@dataclass(frozen=True)
class TurningOption:
    """One target for one worn wheel: the cut, the restored margins [mm] and what it buys."""

    cut: Cut
    restores_all: bool
    margins_mm: dict[str, float]
    km_to_next_limit: float
    governing_limit: str | None
    diameter_per_cycle_mm: float
    km_per_mm: float

    def to_dict(self) -> dict[str, Any]:
        return {**self.cut.to_dict(), "restores_all": self.restores_all,
                "margins_mm": self.margins_mm, "km_to_next_limit": _num(self.km_to_next_limit),
                "governing_limit": self.governing_limit,
                "diameter_per_cycle_mm": self.diameter_per_cycle_mm,
                "km_per_mm": _num(self.km_per_mm)}


def _num(value: float) -> float | str | None:
    if isinstance(value, float) and not math.isfinite(value):
        return None if value != value else "inf"
    return value


def turning_options(worn_y_mm: ArrayLike, worn_z_mm: ArrayLike,
                    targets: Sequence[TargetProfile], limits: FleetLimits,
                    rates_mm_per_km: Mapping[str, float],
                    diameter_rate_mm_per_km: float = 0.0) -> list[TurningOption]:
    """Every target's cut and what it buys (module docstring, economic choice).

    ``rates_mm_per_km`` : margin consumed per km [mm/km] for ``sd``, ``sh``, ``qr`` (from
    the wheel's history or the fleet's); ``diameter_rate_mm_per_km`` : tread wear of the
    diameter [mm/km].
    """
    out = []
    for target in targets:
        cut = turning_cut(worn_y_mm, worn_z_mm, target)
        values = {"sd": target.sd_mm, "sh": target.sh_mm, "qr": target.qr_mm}
        margins = {n: limits.margin(n, values[n]) for n in FLANGE_LIMITS}
        restores = all(m > 0 for m in margins.values())
        km, gov = math.inf, None
        for n in FLANGE_LIMITS:
            r = float(rates_mm_per_km.get(n, 0.0) or 0.0)
            if r > 0 and margins[n] / r < km:
                km, gov = max(margins[n], 0.0) / r, n
        per_cycle = cut.diameter_loss_mm + (diameter_rate_mm_per_km * km
                                            if math.isfinite(km) else 0.0)
        kpm = km / per_cycle if per_cycle > 0 else math.inf
        out.append(TurningOption(cut, restores, margins, km, gov, per_cycle, kpm))
    return out


def economic_choice(options: Sequence[TurningOption]) -> tuple[TurningOption | None,
                                                               TurningOption | None]:
    """(most km per mm of diameter, least diameter loss) among the options that restore
    every limit; ties of km per mm go to the smaller loss. (None, None) if none does."""
    ok = [o for o in options if o.restores_all]
    if not ok:
        return None, None
    best = max(ok, key=lambda o: (o.km_per_mm, -o.cut.diameter_loss_mm))
    least = min(ok, key=lambda o: (o.cut.diameter_loss_mm, -o.km_per_mm))
    return best, least


@dataclass(frozen=True)
class WheelLife:
    """Turnings left before the scrap diameter and the kilometres they give."""

    turnings_left: int
    km_to_scrap: float
    diameter_after_mm: float

    def to_dict(self) -> dict[str, Any]:
        return {"turnings_left": self.turnings_left, "km_to_scrap": _num(self.km_to_scrap),
                "diameter_after_mm": self.diameter_after_mm}


def wheel_life(diameter_mm: float, scrap_diameter_mm: float, cut_diameter_mm: float,
               km_per_cycle: float, diameter_rate_mm_per_km: float = 0.0,
               remaining_now_km: float = 0.0) -> WheelLife:
    """Turnings k with D - k·cut - (k-1)·wear >= scrap (the same cut ``cut_diameter_mm``
    and wear ``rate · km_per_cycle`` every cycle) and the km: the remaining km now plus
    k cycles of ``km_per_cycle`` (all [mm], [km])."""
    wear = max(diameter_rate_mm_per_km, 0.0) * (km_per_cycle if math.isfinite(km_per_cycle)
                                                else 0.0)
    per = cut_diameter_mm + wear
    if diameter_mm - cut_diameter_mm < scrap_diameter_mm:
        return WheelLife(0, remaining_now_km, diameter_mm)
    k = int(math.floor((diameter_mm - scrap_diameter_mm + wear) / per)) if per > 0 else 0
    return WheelLife(k, remaining_now_km + k * km_per_cycle, diameter_mm - cut_diameter_mm)
