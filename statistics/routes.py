"""Routes as curve classes: the statistical track description of seed 003 §5.3.

A route is described by classes of (curve radius, direction, cant, speed), each with the share
of the route length it covers. The hybrid model weights a curve-radius table with these shares
(seed 001 eq. 2, ``P = sum_i c_i P_i``).

Conventions (docs/conventions.md "Sides and curves"): ``direction`` is the side of the vehicle
towards
which the track bends (``'left'`` or ``'right'``); a tangent class has ``radius_m = None`` and
``direction = None``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import pandas as pd

from wearcast.physics.vehicles import GRAVITY_M_S2
from wearcast.physics.vocabulary import DIRECTIONS, RAILS, SIDES, CurveClass, Direction, Rail
from wearcast.physics.vocabulary import rail_for as vocabulary_rail_for

SHARE_TOLERANCE = 1e-3
#: Speed rules of :func:`route_from_segments`: length-weighted mean of the segments' speeds, or
#: the seed 003 §5.3 rule (speed from a non-compensated acceleration at the class's
#: representative radius and cant, capped).
SPEED_RULES = ("mean", "a_nc")
#: Seed 003 §5.3: non-compensated lateral acceleration limit a_nc^lim [m/s^2].
SEED_003_A_NC_M_S2 = 0.8
#: Lateral base of the cant angle [mm] (rail-centre spacing, as ``physics.curving``).
CANT_BASE_MM = 1500.0
#: Number of radius (and cant) classes a route's segments are binned into by default (seed 003
#: Table 3: n_class = 7).
DEFAULT_N_CLASS = 7


def speed_from_unbalanced_acceleration_kmh(radius_m: Any, cant_mm: Any,
                                           unbalanced_acceleration_m_s2: float =
                                           SEED_003_A_NC_M_S2,
                                           max_speed_kmh: float | None = None,
                                           cant_base_mm: float = CANT_BASE_MM) -> np.ndarray:
    """Curve speed at which the non-compensated lateral acceleration equals a_nc.

    V = sqrt(R (a_nc + g h / b)) [m/s], returned in km/h and capped at ``max_speed_kmh``.

    Parameters
    ----------
    radius_m : curve radius R [m] (> 0); cant_mm : cant h [mm]
    unbalanced_acceleration_m_s2 : a_nc [m/s^2] (seed 003 §5.3: 0.8)
    max_speed_kmh : cap, the line speed [km/h] (None: no cap)
    cant_base_mm : lateral base b of the cant angle [mm] (1500 mm rail-centre spacing as in
        ``physics.curving``; 1435 mm, the gauge, reproduces seed 003 Table 3's speeds to the
        printed km/h, see tests/statistics/test_routes.py)

    Returns
    -------
    speed [km/h]

    Seed 003 §5.3 (a_nc^lim = 0.8 m/s^2, its refs. [9], [5]).
    """
    r = np.asarray(radius_m, dtype=float)
    h = np.asarray(cant_mm, dtype=float)
    v_kmh = 3.6 * np.sqrt(np.clip(r * (unbalanced_acceleration_m_s2
                                       + GRAVITY_M_S2 * h / cant_base_mm), 0.0, None))
    return v_kmh if max_speed_kmh is None else np.minimum(v_kmh, max_speed_kmh)


def _finite(value: Any, field: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{field}: must be a number, got {value!r}") from exc
    if not math.isfinite(number):
        raise ValueError(f"{field}: must be finite, got {value!r}")
    return number


def _is_tangent_radius(radius: Any) -> bool:
    if radius is None:
        return True
    try:
        value = float(radius)
    except (TypeError, ValueError):
        return False
    return math.isnan(value) or math.isinf(value)


@dataclass(frozen=True)
class RouteClass:
    """One curve class of a route, as the route description stores it (seed 003 §5.3).

    Not the physics' :class:`wearcast.physics.vocabulary.CurveClass` (the operating point the
    wear loop and the curve-radius tables take), though both carry a radius, cant, speed,
    direction and share: here the speed is always given (the route's recorded or binned speed,
    0 allowed), a tangent has no direction (None), the cant may be negative (binned from
    segments) and the share is a fraction of the route length in [0, 1] (a :class:`Route`'s
    shares sum to 1); a ``CurveClass`` may leave the speed to the unbalanced lateral
    acceleration (None), always has a direction, a cant >= 0 and any shares >= 0.
    :meth:`curve_class` builds the physics' class from this one.

    Attributes
    ----------
    radius_m : representative curve radius [m] (> 0), ``None`` for tangent track
    direction : ``'left'``/``'right'`` (side towards which the track bends), ``None`` on tangent
    cant_mm : representative cant (superelevation) [mm]
    speed_kmh : representative speed [km/h]
    share : fraction of the route length in this class [-], 0 <= share <= 1
    """

    radius_m: float | None
    direction: str | None
    cant_mm: float
    speed_kmh: float
    share: float

    def __post_init__(self) -> None:
        if _is_tangent_radius(self.radius_m):
            object.__setattr__(self, "radius_m", None)
            if self.direction is not None:
                raise ValueError("direction: must be null on tangent track (radius_m is null)")
        else:
            radius = _finite(self.radius_m, "radius_m")
            if radius <= 0.0:
                raise ValueError(f"radius_m: must be > 0, got {radius}")
            object.__setattr__(self, "radius_m", radius)
            if self.direction not in DIRECTIONS:
                raise ValueError(
                    f"direction: must be 'left' or 'right' for a curve, got {self.direction!r}"
                )
        object.__setattr__(self, "cant_mm", _finite(self.cant_mm, "cant_mm"))
        speed = _finite(self.speed_kmh, "speed_kmh")
        if speed < 0.0:
            raise ValueError(f"speed_kmh: must be >= 0, got {speed}")
        object.__setattr__(self, "speed_kmh", speed)
        share = _finite(self.share, "share")
        if not 0.0 <= share <= 1.0 + SHARE_TOLERANCE:
            raise ValueError(f"share: must lie in [0, 1], got {share}")
        object.__setattr__(self, "share", share)

    @property
    def is_tangent(self) -> bool:
        return self.radius_m is None

    def curve_class(self) -> CurveClass:
        """This class as the physics' :class:`~wearcast.physics.vocabulary.CurveClass`: the same
        radius, cant, speed and share; a tangent's direction (None) becomes ``'left'``, unused
        on tangent track. Raises ValueError where the physics' class is narrower (a negative
        cant, a speed of 0)."""
        return CurveClass(radius_m=self.radius_m, cant_mm=self.cant_mm, speed_kmh=self.speed_kmh,
                          direction=cast(Direction, self.direction or "left"), share=self.share)

    def to_dict(self) -> dict[str, Any]:
        return {
            "radius_m": self.radius_m,
            "direction": self.direction,
            "cant_mm": self.cant_mm,
            "speed_kmh": self.speed_kmh,
            "share": self.share,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RouteClass:
        missing = [k for k in ("cant_mm", "speed_kmh", "share") if k not in data]
        if missing:
            raise ValueError(f"{missing[0]}: missing")
        return cls(
            radius_m=data.get("radius_m"),
            direction=data.get("direction"),
            cant_mm=data["cant_mm"],
            speed_kmh=data["speed_kmh"],
            share=data["share"],
        )


@dataclass(frozen=True)
class Route:
    """A named route: its curve classes, whose shares sum to 1 (within 1e-3)."""

    name: str
    classes: tuple[RouteClass, ...]

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError("name: must be a non-empty string")
        classes = tuple(self.classes)
        if not classes:
            raise ValueError("classes: a route needs at least one class")
        for i, c in enumerate(classes):
            if not isinstance(c, RouteClass):
                raise ValueError(f"classes[{i}]: must be a RouteClass")
        total = sum(c.share for c in classes)
        if abs(total - 1.0) > SHARE_TOLERANCE:
            raise ValueError(
                f"classes.share: shares must sum to 1 (±{SHARE_TOLERANCE}), got {total}"
            )
        object.__setattr__(self, "classes", classes)

    def __hash__(self) -> int:
        """The hash of (name, classes), as the dataclass's, computed once per object.

        A route is immutable and is part of the keys of the service's per-request caches;
        hashing its classes anew on every lookup cost tens of microseconds a request. The
        cached value is not pickled (string hashes differ between processes).
        """
        cached = self.__dict__.get("_hash")
        if cached is None:
            cached = hash((self.name, self.classes))
            object.__setattr__(self, "_hash", cached)
        return int(cached)

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_hash", None)
        return state

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "classes": [c.to_dict() for c in self.classes]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Route:
        if "name" not in data:
            raise ValueError("name: missing")
        if "classes" not in data:
            raise ValueError("classes: missing")
        classes = []
        for i, item in enumerate(data["classes"]):
            try:
                classes.append(RouteClass.from_dict(item))
            except ValueError as exc:
                raise ValueError(f"classes[{i}].{exc}") from exc
        return cls(name=data["name"], classes=tuple(classes))


def radius_class_bounds_m(min_radius_m: float, max_radius_m: float, n_class: int) -> np.ndarray:
    """Bounds of ``n_class`` radius classes, equally spaced in curvature 1/R.

    Parameters
    ----------
    min_radius_m, max_radius_m : smallest and largest curve radius on the route [m]
    n_class : number of radius classes

    Returns
    -------
    (n_class + 1,) radius bounds [m], ascending from ``min_radius_m`` to ``max_radius_m``.

    Seed 003 Table 3 (n_class = 7, 150 to 8400 m) has bounds 150, 175, 209, 259, 342, 503, 948,
    8400 m: these are equally spaced in curvature, which is the rule used here.
    """
    if n_class < 1:
        raise ValueError(f"n_class: must be >= 1, got {n_class}")
    if not 0.0 < min_radius_m <= max_radius_m:
        raise ValueError("min_radius_m/max_radius_m: need 0 < min_radius_m <= max_radius_m")
    curvature = np.linspace(1.0 / min_radius_m, 1.0 / max_radius_m, n_class + 1)
    return 1.0 / curvature


def cant_class_bounds_mm(max_cant_mm: float, n_class: int, min_cant_mm: float = 0.0) -> np.ndarray:
    """Bounds of ``n_class`` cant subclasses, equally spaced from ``min_cant_mm`` to the max.

    Seed 003 Table 3 (n_class = 7, cant up to 140 mm): subclasses 0-19, 20-39, ..., 120-140 mm,
    i.e. width 20 mm.
    """
    if n_class < 1:
        raise ValueError(f"n_class: must be >= 1, got {n_class}")
    if max_cant_mm < min_cant_mm:
        raise ValueError("max_cant_mm: must be >= min_cant_mm")
    return np.linspace(min_cant_mm, max_cant_mm, n_class + 1)


_SEGMENT_FIELDS = ("length_m", "radius_m", "direction", "cant_mm", "speed_kmh")


def _segments_frame(segments: pd.DataFrame | Iterable[Mapping[str, Any]]) -> pd.DataFrame:
    frame = segments.copy() if isinstance(segments, pd.DataFrame) else pd.DataFrame(list(segments))
    if frame.empty:
        raise ValueError("segments: at least one segment is needed")
    for field in _SEGMENT_FIELDS:
        if field not in frame.columns:
            raise ValueError(f"segments.{field}: missing")
    out = pd.DataFrame(index=range(len(frame)))
    for field in ("length_m", "cant_mm", "speed_kmh"):
        values = pd.to_numeric(frame[field], errors="coerce").to_numpy(dtype=float)
        bad = ~np.isfinite(values)
        if bad.any():
            raise ValueError(f"segments[{int(np.argmax(bad))}].{field}: must be a finite number")
        out[field] = values
    if (out["length_m"] <= 0).any():
        raise ValueError(
            f"segments[{int(np.argmax(out['length_m'].to_numpy() <= 0))}].length_m: must be > 0"
        )
    if (out["speed_kmh"] < 0).any():
        i = int(np.argmax(out["speed_kmh"].to_numpy() < 0))
        raise ValueError(f"segments[{i}].speed_kmh: must be >= 0")
    radius = np.full(len(frame), np.inf)
    direction: list[str | None] = []
    for i, (r, d) in enumerate(zip(frame["radius_m"], frame["direction"], strict=True)):
        if _is_tangent_radius(r) or (isinstance(r, str) and not r.strip()):
            direction.append(None)
            continue
        value = _finite(r, f"segments[{i}].radius_m")
        if value <= 0:
            raise ValueError(f"segments[{i}].radius_m: must be > 0, got {value}")
        if d not in DIRECTIONS:
            raise ValueError(f"segments[{i}].direction: must be 'left' or 'right' for a curve")
        radius[i] = value
        direction.append(str(d))
    out["radius_m"] = radius
    out["direction"] = direction
    return out


def route_from_segments(
    segments: pd.DataFrame | Sequence[Mapping[str, Any]],
    *,
    name: str = "route",
    n_class: int = DEFAULT_N_CLASS,
    tangent_min_radius_m: float | None = None,
    speed_rule: str = "mean",
    unbalanced_acceleration_m_s2: float = SEED_003_A_NC_M_S2,
    max_speed_kmh: float | None = None,
) -> Route:
    """Bin a full route (its segments) into curve classes like seed 003 §5.3.

    Parameters
    ----------
    segments : rows with ``length_m`` [m], ``radius_m`` [m] (None/NaN/inf = tangent),
        ``direction`` ('left'/'right', ignored on tangents), ``cant_mm`` [mm], ``speed_kmh``
    name : route name
    n_class : number of radius classes and of cant subclasses per radius class (seed 003)
    tangent_min_radius_m : radii >= this count as tangent track (default: only explicit
        tangents)
    speed_rule : speed of a curve class: ``'mean'`` (default) the length-weighted mean of its
        segments' speeds; ``'a_nc'`` the seed 003 §5.3 rule, V = min(max_speed_kmh,
        sqrt(R_c (a_nc + g H / 1500 mm))) at the class's representative radius R_c and cant H
        (:func:`speed_from_unbalanced_acceleration_kmh`). Tangent track keeps the mean speed
        of its segments either way (seed 003: the tangent speed comes from the track data).
    unbalanced_acceleration_m_s2 : a_nc of the ``'a_nc'`` rule [m/s^2] (seed 003: 0.8)
    max_speed_kmh : cap of the ``'a_nc'`` rule, the line speed [km/h] (None: no cap)

    Returns
    -------
    Route whose classes are: radius classes equally spaced in curvature between the route's
    smallest and largest curve radius (seed 003 Table 3), each split by direction and into
    ``n_class`` cant subclasses equally spaced from 0 (or the smallest cant, if negative) to
    the largest cant; the representative radius and cant are length-weighted means over the
    segments of the (sub)class (seed 003 §5.3), the speed follows ``speed_rule``, and the
    share is the class length over the route length. Classes are also split by curve
    direction (seed 003 does not, its vehicle being symmetric), sharing the representative
    radius of their radius class. Tangent track forms one class. Empty
    classes are left out.
    """
    if speed_rule not in SPEED_RULES:
        raise ValueError(f"speed_rule: must be one of {SPEED_RULES}, got {speed_rule!r}")
    if max_speed_kmh is not None and not max_speed_kmh > 0:
        raise ValueError(f"max_speed_kmh: must be > 0, got {max_speed_kmh}")
    frame = _segments_frame(segments)
    if tangent_min_radius_m is not None:
        frame.loc[frame["radius_m"] >= tangent_min_radius_m, "radius_m"] = np.inf
        frame.loc[~np.isfinite(frame["radius_m"]), "direction"] = None
    total = float(frame["length_m"].sum())
    classes: list[RouteClass] = []

    tangent = frame[~np.isfinite(frame["radius_m"])]
    if not tangent.empty:
        w = tangent["length_m"].to_numpy()
        classes.append(
            RouteClass(
                radius_m=None,
                direction=None,
                cant_mm=float(np.average(tangent["cant_mm"], weights=w)),
                speed_kmh=float(np.average(tangent["speed_kmh"], weights=w)),
                share=float(w.sum() / total),
            )
        )

    curves = frame[np.isfinite(frame["radius_m"])]
    if not curves.empty:
        r_bounds = radius_class_bounds_m(
            float(curves["radius_m"].min()), float(curves["radius_m"].max()), n_class
        )
        # curvature bins, descending curvature bounds -> bin index 0 = tightest
        curvature = 1.0 / curves["radius_m"].to_numpy()
        k_bounds = 1.0 / r_bounds
        r_idx = np.clip(np.searchsorted(-k_bounds, -curvature, side="right") - 1, 0, n_class - 1)
        cant = curves["cant_mm"].to_numpy()
        c_bounds = cant_class_bounds_mm(float(cant.max()), n_class, min(0.0, float(cant.min())))
        c_idx = np.clip(np.searchsorted(c_bounds, cant, side="right") - 1, 0, n_class - 1)
        keyed = curves.assign(r_idx=r_idx, c_idx=c_idx)
        # representative radius per radius class, over both directions (seed 003 §5.3)
        rep = {
            int(ri): float(np.average(rows["radius_m"], weights=rows["length_m"]))
            for ri, rows in keyed.groupby("r_idx", sort=True)
        }
        for (ri, direction), by_radius in keyed.groupby(["r_idx", "direction"], sort=True):
            rep_radius = rep[int(ri)]
            for _, sub in by_radius.groupby("c_idx", sort=True):
                w = sub["length_m"].to_numpy()
                rep_cant = float(np.average(sub["cant_mm"], weights=w))
                if speed_rule == "a_nc":
                    speed = float(speed_from_unbalanced_acceleration_kmh(
                        rep_radius, rep_cant, unbalanced_acceleration_m_s2, max_speed_kmh))
                else:
                    speed = float(np.average(sub["speed_kmh"], weights=w))
                classes.append(
                    RouteClass(
                        radius_m=rep_radius,
                        direction=str(direction),
                        cant_mm=rep_cant,
                        speed_kmh=speed,
                        share=float(w.sum() / total),
                    )
                )
    return Route(name=name, classes=tuple(classes))


def route_share_by_rail(route: Route, side: str) -> dict[str, float]:
    """Share of a route on which a wheel on ``side`` runs on the high, low or tangent rail."""
    if side not in SIDES:
        raise ValueError(f"side: must be 'left' or 'right', got {side!r}")
    out: dict[str, float] = dict.fromkeys(RAILS, 0.0)
    for c in route.classes:
        out[rail_for(c, side)] += c.share
    return out


def rail_for(route_class: RouteClass, side: str) -> Rail:
    """Rail a wheel on ``side`` runs on in this class: 'tangent', 'high' or 'low'.

    The rail rule of :func:`wearcast.physics.vocabulary.rail_for` (docs/conventions.md "Sides
    and curves": in a left curve the right wheels run on the high (outer) rail and the left
    wheels on the low rail; mirrored in a right curve).
    """
    direction = None if route_class.radius_m is None else route_class.direction
    return vocabulary_rail_for(direction, side)  # type: ignore[arg-type]
