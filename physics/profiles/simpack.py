"""SIMPACK / CONTACT wheel and rail profile files (``.prw`` wheel, ``.prr`` rail).

Format (SIMPACK "Rail-Wheel Profile", as read by CONTACT): text; ``!`` starts a comment (to
the end of the line); a ``header.begin ... header.end`` block with ``key = value`` lines
(``type = 1`` wheel, ``0`` rail); a ``spline.begin ... spline.end`` block with processing
settings (``key = value``) and, inside it, ``point.begin ... point.end`` with one point per
line: ``y z [weight]`` in the file's length unit.

Processing settings applied here, in SIMPACK's numbered order:
  2 ``shift.y``/``shift.z`` added to the points; 3 ``rotate`` (about x, in the angle unit) turns
  (y, z) by that angle; 4 ``bound.y.min/max``, ``bound.z.min/max`` keep only points inside
  the bounds (a bound pair with min > max is inactive); 5 ``mirror.y``/``mirror.z`` negate y/z;
  6 ``inversion`` reverses the point order; 7 ``units.len.f`` = length unit per metre
  (1000: millimetres), ``units.ang.f`` = angle unit per radian.  ``point.dist.min`` (1) and
  ``approx.smooth`` are reported but not applied (smoothing is the curve's business).

Result frame ("profile frame" of SIMPACK and CONTACT): y lateral with the gauge side (the
rail's gauge corner, the wheel's flange) at y < 0, **z pointing down** (into the rail; for a
wheel, towards larger radius).  ``wheel_curve`` and ``rail_curve`` turn that into wearcast's
wheel frame (y from the tape circle, negative towards the flange; z = radius increase) and
rail frame (z up), as ``profiles.measured.ProfileCurve``.

Pure: ``parse_simpack_profile`` parses text; ``read_simpack_profile(path)`` is the only file
I/O and only reads the file it is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.profiles.measured import ProfileCurve
from wearcast.physics.profiles.rails import incline


class ProfileFileError(ValueError):
    """A profile file that cannot be read; ``field`` names the part that is wrong."""

    def __init__(self, field_name: str, reason: str) -> None:
        super().__init__(f"{field_name}: {reason}")
        self.field = field_name
        self.reason = reason


@dataclass(frozen=True)
class SimpackProfile:
    """A profile read from a ``.prw``/``.prr`` file, processing settings applied.

    kind : ``"wheel"`` or ``"rail"`` (header ``type``)
    y_mm, z_mm : points [mm] in the SIMPACK profile frame (module docstring: z down), in
        file order after ``inversion``
    header, settings : the raw ``key = value`` entries of the header and spline blocks
    comment : the spline block's ``comment`` (may say e.g. that a rail is already canted)
    """

    kind: str
    y_mm: NDArray[np.float64]
    z_mm: NDArray[np.float64]
    header: dict[str, str] = field(default_factory=dict)
    settings: dict[str, str] = field(default_factory=dict)
    comment: str = ""


def _strip_comment(line: str) -> str:
    # '!' starts a comment unless it is inside a quoted string
    out, quote = [], ""
    for ch in line:
        if quote:
            out.append(ch)
            if ch == quote:
                quote = ""
        elif ch in "'\"":
            quote = ch
            out.append(ch)
        elif ch == "!":
            break
        else:
            out.append(ch)
    return "".join(out).strip()


def _number(settings: dict[str, str], key: str, default: float) -> float:
    text = settings.get(key)
    if text is None:
        return default
    try:
        return float(text.replace("d", "e").replace("D", "e"))
    except ValueError as exc:
        raise ProfileFileError(key, f"not a number: {text!r}") from exc


def parse_simpack_profile(text: str) -> SimpackProfile:
    """Parse the text of a SIMPACK ``.prw``/``.prr`` profile file (module docstring).

    Raises ``ProfileFileError`` (a ``ValueError``) naming the block or key that is wrong:
    no ``point.begin`` block, a point row that is not two numbers, fewer than 3 points, an
    unknown header ``type``.
    """
    header: dict[str, str] = {}
    settings: dict[str, str] = {}
    rows: list[tuple[float, float]] = []
    block = ""
    seen_points = False
    for number, raw in enumerate(text.splitlines(), start=1):
        line = _strip_comment(raw)
        if not line:
            continue
        low = line.lower()
        if low in ("header.begin", "spline.begin", "point.begin"):
            block = low.split(".")[0]
            seen_points = seen_points or block == "point"
            continue
        if low in ("header.end", "spline.end"):
            block = ""
            continue
        if low == "point.end":
            block = "spline"
            continue
        if block == "point":
            parts = line.replace(",", " ").split()
            try:
                y_val, z_val = float(parts[0]), float(parts[1])
            except (IndexError, ValueError) as exc:
                raise ProfileFileError("point", f"line {number} is not 'y z': {raw!r}") from exc
            rows.append((y_val, z_val))
        elif block in ("header", "spline") and "=" in line:
            key, value = (part.strip() for part in line.split("=", 1))
            (header if block == "header" else settings)[key.lower()] = value.strip("'\"")
    if not seen_points:
        raise ProfileFileError("point", "no point.begin ... point.end block")
    if len(rows) < 3:
        raise ProfileFileError("point", f"{len(rows)} points; a profile needs at least 3")
    kind_code = header.get("type", "").strip()
    kinds = {"0": "rail", "1": "wheel"}
    if kind_code not in kinds:
        raise ProfileFileError("type", f"header type must be 0 (rail) or 1 (wheel), "
                                       f"got {kind_code!r}")
    pts = np.asarray(rows, dtype=float)
    y, z = pts[:, 0], pts[:, 1]
    mm_per_unit = 1000.0 / _number(settings, "units.len.f", 1000.0)
    rad_per_unit = 1.0 / _number(settings, "units.ang.f", 1.0)
    # 2 shift, 3 rotate, 4 bounds (in file units), 5 mirror, 6 inversion, 7 units
    y = y + _number(settings, "shift.y", 0.0)
    z = z + _number(settings, "shift.z", 0.0)
    angle = _number(settings, "rotate", 0.0) * rad_per_unit
    if angle != 0.0:
        c, s = math.cos(angle), math.sin(angle)
        y, z = c * y - s * z, s * y + c * z
    keep = np.ones(y.shape, dtype=bool)
    for name, values in (("y", y), ("z", z)):
        lo = _number(settings, f"bound.{name}.min", 1.0)
        hi = _number(settings, f"bound.{name}.max", 0.0)
        if lo <= hi:
            keep &= (values >= lo) & (values <= hi)
    y, z = y[keep], z[keep]
    if y.size < 3:
        raise ProfileFileError("bound", "fewer than 3 points inside the bounds")
    if _number(settings, "mirror.y", 0.0) != 0:
        y = -y
    if _number(settings, "mirror.z", 0.0) != 0:
        z = -z
    if _number(settings, "inversion", 0.0) != 0:
        y, z = y[::-1], z[::-1]
    return SimpackProfile(kind=kinds[kind_code], y_mm=y * mm_per_unit, z_mm=z * mm_per_unit,
                          header=header, settings=settings,
                          comment=settings.get("comment", ""))


def read_simpack_profile(path: str | Path) -> SimpackProfile:
    """Read and parse one ``.prw``/``.prr`` file (thin wrapper of ``parse_simpack_profile``)."""
    return parse_simpack_profile(Path(path).read_text(encoding="utf-8", errors="replace"))


def wheel_curve(profile: SimpackProfile, smoothing_mm: float = 0.0) -> ProfileCurve:
    """The wheel profile in wearcast's wheel frame: y as in the file (flange at y < 0, the
    origin of the file taken as the tape circle), z = radius increase = the file's z (down).

    ``smoothing_mm`` as ``ProfileCurve.from_points`` (0 interpolates)."""
    if profile.kind != "wheel":
        raise ProfileFileError("type", "expected a wheel profile (.prw, type = 1)")
    return ProfileCurve.from_points(profile.y_mm, profile.z_mm, smoothing_mm=smoothing_mm)


def rail_curve(profile: SimpackProfile, inclination: float = 0.0,
               smoothing_mm: float = 0.0) -> ProfileCurve:
    """The rail profile in wearcast's rail frame (z up, gauge side y < 0), optionally turned by
    a rail inclination (``profiles.rails.incline``; 0 for a file that is already canted,
    which its comment usually says).  Use it with ``WheelsetTrack(rail_inclination=0)``."""
    if profile.kind != "rail":
        raise ProfileFileError("type", "expected a rail profile (.prr, type = 0)")
    y, z = incline(profile.y_mm, -profile.z_mm, inclination)
    return ProfileCurve.from_points(y, z, smoothing_mm=smoothing_mm)
