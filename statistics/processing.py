"""One call per measured profile: clean, align, wear curve, wear areas, flange parameters.

This is docs/conventions.md "The hybrid model" steps 1–2 for a single measurement (seed 001 §3.1,
seed
000 §IV.A), the call the import service makes for each profile it stores.

Two ways to bring the profile onto its reference for the wear curve (``alignment``):

* ``"datum"`` (measurements from an instrument with a datum, e.g. MiniProf): the profile is
  placed by the instrument's own back face and tape circle (:mod:`.datum`, no free rotation;
  a residual tilt both datum windows prove is corrected, bounded), then shifted vertically
  onto the reference's unworn windows (:func:`.alignment.align_vertically`): the lateral
  datum is kept, so Sd/Sh/qR of the profile the wear is computed on are those measured;
* ``"free"`` (profiles without a known datum, e.g. the synthetic fleets): the seed 000
  §IV.A rigid fit (lateral, vertical shift and rotation, :func:`.alignment.align_to_reference`).

Either way the profile is then checked against its reference (:mod:`.reference_check`): a
shape the reference cannot have worn into is flagged, never turned into negative wear.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.parameters import tape_circle_height_mm
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import (
    FIT_WINDOWS_MM,
    AlignedProfile,
    ReferenceHeight,
    align_to_reference,
    align_vertically,
)
from wearcast.statistics.cleaning import CleanedProfile, clean_profile
from wearcast.statistics.datum import DatumPlacement, place_on_datum
from wearcast.statistics.profile_parameters import FlangeParameters, flange_parameters
from wearcast.statistics.reference_check import ReferenceCheck, check_reference
from wearcast.statistics.wear_curves import (
    DEFAULT_GRID_Y_MM,
    DEFAULT_SPLIT_Y_MM,
    WearAreas,
    wear_areas_mm2,
    wear_curve_mm,
)


@dataclass(frozen=True)
class ProcessedProfile:
    """A measured profile reduced to what the statistical model uses.

    Attributes
    ----------
    cleaned : the cleaned profile before alignment (``CleanedProfile``)
    aligned : the aligned profile and the alignment applied (``AlignedProfile``; its fields
        also read as ``y_aligned_mm``, ``z_aligned_mm``, ``lateral_shift_mm``,
        ``vertical_shift_mm``, ``rotation_rad``, ``rms_residual_mm`` and ``n_used``)
    grid_y_mm : lateral grid of the wear curve [mm]
    wear_mm : wear curve w = z_ref - z_worn on the grid [mm], NaN where no data
    areas : flange/tread wear areas [mm²]
    parameters : Sd, Sh, qR of the aligned profile [mm] (with ``"datum"`` alignment: of the
        profile as measured, since the vertical shift does not change them)
    alignment : ``"datum"`` or ``"free"`` (module docstring)
    datum : the datum placement (``"datum"`` alignment only)
    reference_check : whether the shape fits the reference (flagged shapes: see
        :mod:`.reference_check`)
    """

    cleaned: CleanedProfile
    aligned: AlignedProfile
    grid_y_mm: NDArray[np.float64]
    wear_mm: NDArray[np.float64]
    areas: WearAreas
    parameters: FlangeParameters
    alignment: str = "free"
    datum: DatumPlacement | None = None
    reference_check: ReferenceCheck | None = None

    @property
    def y_aligned_mm(self) -> NDArray[np.float64]:
        """Aligned profile y [mm]."""
        return self.aligned.y_mm

    @property
    def z_aligned_mm(self) -> NDArray[np.float64]:
        """Aligned profile z [mm]."""
        return self.aligned.z_mm

    @property
    def lateral_shift_mm(self) -> float:
        return self.aligned.lateral_shift_mm

    @property
    def vertical_shift_mm(self) -> float:
        return self.aligned.vertical_shift_mm

    @property
    def rotation_rad(self) -> float:
        return self.aligned.rotation_rad

    @property
    def rms_residual_mm(self) -> float:
        return self.aligned.rms_residual_mm

    @property
    def n_used(self) -> int:
        return self.aligned.n_used

    @property
    def notes(self) -> tuple[str, ...]:
        """Corrections made while cleaning."""
        return self.cleaned.notes


def process_profile(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    reference_height: ReferenceHeight = s1002_height_mm,
    grid_y_mm: ArrayLike = DEFAULT_GRID_Y_MM,
    split_y_mm: float = DEFAULT_SPLIT_Y_MM,
    alignment: Literal["free", "datum"] = "free",
) -> ProcessedProfile:
    """Clean, align and reduce one measured profile.

    Parameters
    ----------
    y_mm, z_mm : raw points [mm] in the wheel frame (instrument order is fine)
    reference_height : reference profile z(y) [mm] (default S1002)
    grid_y_mm : lateral grid of the wear curve [mm]
    split_y_mm : flange/tread boundary [mm] (seed 001: -30)
    alignment : ``"free"`` rigid fit or ``"datum"`` placement (module docstring)

    Returns
    -------
    ProcessedProfile

    Raises
    ------
    ValueError : the profile cannot be used (see ``clean_profile``) or aligned.
    """
    if alignment not in ("free", "datum"):
        raise ValueError(f"alignment must be 'free' or 'datum', got {alignment!r}")
    cleaned = clean_profile(y_mm, z_mm)
    datum: DatumPlacement | None = None
    if alignment == "datum":
        datum = place_on_datum(y_mm, z_mm, reference_height)
        if datum.tilt_applied_rad != 0.0:
            cleaned = clean_profile(datum.y_mm, datum.z_mm)
        aligned = align_vertically(cleaned.y_mm, cleaned.z_mm, reference_height,
                                   windows_mm=(FIT_WINDOWS_MM[0],))
        parameters = flange_parameters(cleaned.y_mm, cleaned.z_mm)
    else:
        aligned = align_to_reference(cleaned.y_mm, cleaned.z_mm, reference_height)
        parameters = flange_parameters(aligned.y_mm, aligned.z_mm)
    grid = np.asarray(grid_y_mm, dtype=float)
    wear = wear_curve_mm(aligned.y_mm, aligned.z_mm, grid, reference_height)
    areas = wear_areas_mm2(grid, wear, split_y_mm)
    return ProcessedProfile(
        cleaned=cleaned,
        aligned=aligned,
        grid_y_mm=grid,
        wear_mm=wear,
        areas=areas,
        parameters=parameters,
        alignment=alignment,
        datum=datum,
        reference_check=check_reference(parameters, areas, reference_height,
                                        tape_circle_height_mm(grid, wear),
                                        aligned.rms_residual_mm, grid, wear),
    )


def process_profiles(
    profiles: Iterable[tuple[ArrayLike, ArrayLike]],
    *,
    reference_height: ReferenceHeight = s1002_height_mm,
    grid_y_mm: ArrayLike = DEFAULT_GRID_Y_MM,
    split_y_mm: float = DEFAULT_SPLIT_Y_MM,
) -> list[ProcessedProfile | ValueError]:
    """``process_profile`` for many profiles; a profile that cannot be used yields its
    ``ValueError`` in its place instead of stopping the batch.

    Parameters
    ----------
    profiles : iterable of (y_mm, z_mm) raw point arrays [mm]

    Returns
    -------
    list, one ``ProcessedProfile`` or ``ValueError`` per input, in input order.
    """
    grid = np.asarray(grid_y_mm, dtype=float)
    out: list[ProcessedProfile | ValueError] = []
    for y, z in profiles:
        try:
            out.append(
                process_profile(
                    y, z, reference_height=reference_height, grid_y_mm=grid,
                    split_y_mm=split_y_mm,
                )
            )
        except ValueError as exc:
            out.append(exc)
    return out
