"""A measured wheel profile placed in the wheel frame by the instrument's own datum.

A wheel profile gauge (MiniProf and alike) measures against two datums of the wheel itself:
the **back face** (inner face of the rim, the lateral datum, y = -70 mm in the wheel frame)
and the **tape circle** 70 mm from it (the vertical datum, z = 0 there). The instrument writes
its points in that frame already (X from the back face, Y zero at the taperline), so the
placement here keeps the points where the instrument put them and only *checks* the datums:

* back face: the near-vertical run of points at the lateral minimum of the profile
  (``BACK_FACE_BAND_MM`` wide, without its top ``BACK_FACE_ARC_MM`` where the flange-back
  arc starts). ``found`` when at least ``MIN_BACK_FACE_POINTS`` points span
  ``MIN_BACK_FACE_SPAN_MM`` vertically; its mean position is reported (it should be
  y = -70 mm); otherwise the lateral datum is the file's X = 0, reported as ``guessed``;
* tape circle: the profile height at y = 0 (the instrument zeroes it, so it should be 0);
* tilt: the only free rotation allowed is a residual tilt that *both* datum windows prove:
  the back-face run's angle from the vertical (``tilt_back_face_rad``) and the field-side
  end of the tread (``FIELD_WINDOW_MM``, outside the running band) against the declared
  reference's slope there (``tilt_field_rad``). It is applied only when both are larger than
  ``TILT_EVIDENCE_RAD`` with the same sign, and then by the smaller of the two, bounded by
  ``MAX_TILT_RAD``; the rotation is about the tape-circle point (0, 0), so the vertical
  datum stays where it was.

Sd/Sh/qR of the placed profile therefore equal those of the file's raw points to within the
bounded tilt (at most ~0.1 mm). The alignment to a reference profile for wear areas is a
separate step (:func:`wearcast.statistics.alignment.align_vertically`) that never moves the
stored measurement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.parameters import tape_circle_height_mm
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import ReferenceHeight, reference_table

#: Lateral position of the back face in the wheel frame [mm].
BACK_FACE_Y_MM = -70.0
#: Width [mm] of the band at the profile's lateral minimum holding the back-face run.
BACK_FACE_BAND_MM = 0.3
#: The top of the band, where the flange-back arc leaves the back face (S1002's R20.5 rises
#: 3.5 mm within 0.3 mm of it), is left out of the run [mm].
BACK_FACE_ARC_MM = 4.0
#: A back face is "found" with at least this many points ...
MIN_BACK_FACE_POINTS = 10
#: ... spanning at least this height [mm].
MIN_BACK_FACE_SPAN_MM = 5.0
#: The back face should lie within this distance [mm] of y = -70 (else a warning).
BACK_FACE_TOLERANCE_MM = 0.5
#: The tape-circle height should be within this [mm] of z = 0 (else a warning).
TAPE_CIRCLE_TOLERANCE_MM = 0.5
#: Field-side end of the tread used as the second tilt window [mm] (outside the running band
#: of seed 001 Figs. 6-7, which ends near y = +30).
FIELD_WINDOW_MM = (40.0, 58.0)
#: Fewest points in the field window for a tilt estimate there.
MIN_FIELD_POINTS = 8
#: Smallest tilt [rad] a window must show for it to count as evidence.
TILT_EVIDENCE_RAD = 2e-3
#: Largest tilt correction [rad] ever applied.
MAX_TILT_RAD = 5e-3


@dataclass(frozen=True)
class DatumPlacement:
    """A measured profile on the instrument's datum, with what was found and done.

    Attributes
    ----------
    y_mm, z_mm : the placed points [mm], same order as given (identical to the input when
        ``tilt_applied_rad`` is 0)
    back_face_found : the back-face run was measured (else the lateral datum is guessed)
    back_face_y_mm : mean lateral position of the back-face run [mm] (NaN when not found)
    back_face_points : points in the back-face run
    tape_circle_z_mm : height of the profile at y = 0 [mm] (NaN if y = 0 is not covered)
    tilt_back_face_rad : tilt shown by the back-face run [rad] (NaN when not found)
    tilt_field_rad : tilt shown by the field-side window against the reference [rad]
        (NaN when the window has too few points)
    tilt_applied_rad : rotation applied about (0, 0) [rad], counter-clockwise positive,
        |value| <= ``MAX_TILT_RAD``
    notes : what was found, guessed and done, one sentence each
    """

    y_mm: NDArray[np.float64]
    z_mm: NDArray[np.float64]
    back_face_found: bool
    back_face_y_mm: float
    back_face_points: int
    tape_circle_z_mm: float
    tilt_back_face_rad: float
    tilt_field_rad: float
    tilt_applied_rad: float
    notes: tuple[str, ...]


def _back_face(y: NDArray, z: NDArray) -> tuple[NDArray, float]:
    """Mask of the back-face run and its tilt [rad] (NaN if not found)."""
    y_min = float(np.min(y))
    run = y <= y_min + BACK_FACE_BAND_MM
    if run.any():
        run &= z <= float(z[run].max()) - BACK_FACE_ARC_MM
    if (y_min > BACK_FACE_Y_MM + 2.0 or int(run.sum()) < MIN_BACK_FACE_POINTS
            or float(np.ptp(z[run])) < MIN_BACK_FACE_SPAN_MM):
        return np.zeros_like(run), float("nan")
    slope = float(np.polyfit(z[run], y[run], 1)[0])  # dy/dz of the run
    return run, math.atan(slope)


def _field_tilt(y: NDArray, z: NDArray, reference_height: ReferenceHeight) -> float:
    """Rotation [rad] that would give the field window the reference's mean slope."""
    lo, hi = FIELD_WINDOW_MM
    window = (y >= lo) & (y <= hi)
    if int(window.sum()) < MIN_FIELD_POINTS:
        return float("nan")
    yw, zw = y[window], z[window]
    z_ref = reference_table(reference_height).height_mm(yw)
    ok = np.isfinite(z_ref)
    if int(ok.sum()) < MIN_FIELD_POINTS:
        return float("nan")
    slope = float(np.polyfit(yw[ok], zw[ok], 1)[0])
    slope_ref = float(np.polyfit(yw[ok], z_ref[ok], 1)[0])
    return math.atan(slope_ref) - math.atan(slope)


def place_on_datum(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    reference_height: ReferenceHeight = s1002_height_mm,
) -> DatumPlacement:
    """Check a measured profile's datums and correct a residual tilt both windows prove.

    Parameters
    ----------
    y_mm, z_mm : raw points [mm] in the wheel frame as the instrument gives them
        (y = X - 70 from the back face, z = Y up from the taperline), any order
    reference_height : the declared reference z(y) [mm] (for the field-window tilt only)

    Returns
    -------
    DatumPlacement (see the module docstring for the rules).
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    finite = np.isfinite(y) & np.isfinite(z)
    yf, zf = y[finite], z[finite]
    if yf.size < 3:
        raise ValueError("profile has fewer than 3 finite points")
    notes: list[str] = []
    run, tilt_back = _back_face(yf, zf)
    found = bool(run.any())
    if found:
        back_y = float(np.mean(yf[run]))
        notes.append(f"datum found: back face measured ({int(run.sum())} points over "
                     f"{float(np.ptp(zf[run])):.1f} mm) at y = {back_y:.2f} mm "
                     f"(X = {back_y - BACK_FACE_Y_MM:.2f} mm)")
        if abs(back_y - BACK_FACE_Y_MM) > BACK_FACE_TOLERANCE_MM:
            notes.append(f"back face lies {back_y - BACK_FACE_Y_MM:+.2f} mm from X = 0: the "
                         "points are kept as measured; check the instrument's X datum")
    else:
        back_y = float("nan")
        notes.append("datum guessed: no back-face run measured (profile starts at "
                     f"X = {float(yf.min()) - BACK_FACE_Y_MM:.2f} mm); the lateral datum is "
                     "the file's X = 0")
    order = np.argsort(yf, kind="stable")
    ys, zs = yf[order], zf[order]
    if ys[0] <= 0.0 <= ys[-1]:
        tape_z = tape_circle_height_mm(ys, zs)
        if abs(tape_z) > TAPE_CIRCLE_TOLERANCE_MM:
            notes.append(f"tape circle at z = {tape_z:+.2f} mm, not 0: the file's vertical "
                         "datum is not the taperline")
    else:
        tape_z = float("nan")
        notes.append("datum guessed: the points do not reach the tape circle (X = 70 mm)")
    tilt_field = _field_tilt(ys, zs, reference_height)
    tilt = 0.0
    if (math.isfinite(tilt_back) and math.isfinite(tilt_field)
            and abs(tilt_back) > TILT_EVIDENCE_RAD and abs(tilt_field) > TILT_EVIDENCE_RAD
            and math.copysign(1.0, tilt_back) == math.copysign(1.0, tilt_field)):
        tilt = math.copysign(min(abs(tilt_back), abs(tilt_field), MAX_TILT_RAD), tilt_back)
        notes.append(f"tilt corrected by {tilt * 1e3:+.2f} mrad about the tape circle (back "
                     f"face shows {tilt_back * 1e3:+.2f}, field side {tilt_field * 1e3:+.2f} "
                     f"mrad; bound {MAX_TILT_RAD * 1e3:g} mrad)")
    else:
        shown = ", ".join(f"{name} {value * 1e3:+.2f} mrad" for name, value in
                          (("back face", tilt_back), ("field side", tilt_field))
                          if math.isfinite(value))
        notes.append("no tilt corrected: the two datum windows do not both prove one"
                     + (f" ({shown})" if shown else ""))
    if tilt != 0.0:
        c, s = math.cos(tilt), math.sin(tilt)
        y_out = c * y - s * z
        z_out = s * y + c * z
    else:
        y_out, z_out = y.copy(), z.copy()
    return DatumPlacement(
        y_mm=y_out, z_mm=z_out, back_face_found=found, back_face_y_mm=back_y,
        back_face_points=int(run.sum()), tape_circle_z_mm=tape_z,
        tilt_back_face_rad=tilt_back, tilt_field_rad=tilt_field, tilt_applied_rad=tilt,
        notes=tuple(notes))
