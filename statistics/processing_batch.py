""":func:`.processing.process_profile` (``alignment="free"``) for a chunk of profiles at once.

The import processes profiles by the hundred (docs/conventions.md "The hybrid model" steps
1–2 per measurement: seed 001 §3.1, seed 000 §IV.A). One call per profile pays numpy's
per-call cost some three hundred times per profile; here the steps where that pays run once
per chunk over the profiles held as rows of one array (:mod:`.ragged`): the rigid alignment
(:func:`.alignment_batch.align_to_reference_batch`), the wear areas
(:func:`.wear_curves.wear_areas_rows`) and Sd/Sh/qR
(:func:`wearcast.physics.profiles.parameters.flange_parameters_rows`). Each rule is written
once and shared with the per-profile functions; the cleaning
(:func:`.cleaning.clean_profile`), the wear curves' interpolation and the reference check run
profile by profile.

The results are those of ``process_profile`` to floating-point round-off
(tests/statistics/test_processing_batch.py compares them profile by profile); a profile the
batch cannot fit is handed to the per-profile functions, so an unusable profile gets the same
``ValueError`` in its place.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.parameters import flange_parameters_rows, tape_circle_height_mm
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import AlignedProfile, ReferenceHeight, align_to_reference
from wearcast.statistics.alignment_batch import align_to_reference_batch
from wearcast.statistics.cleaning import CleanedProfile, clean_profile, resample_profile
from wearcast.statistics.processing import ProcessedProfile
from wearcast.statistics.profile_parameters import FlangeParameters
from wearcast.statistics.ragged import pack
from wearcast.statistics.reference_check import NEGATIVE_WEAR_MM, check_reference
from wearcast.statistics.wear_curves import (
    DEFAULT_GRID_Y_MM,
    DEFAULT_SPLIT_Y_MM,
    WearAreas,
    reference_on_grid,
    wear_areas_rows,
)


def _wear_rows(aligned: Sequence[AlignedProfile], grid: NDArray[np.float64],
               reference_height: ReferenceHeight) -> NDArray[np.float64]:
    """Wear curves w = z_ref - z_worn (M, g) [mm] on the grid, NaN outside each profile's
    lateral range (:func:`.wear_curves.wear_curve_mm` row by row)."""
    z_ref = reference_on_grid(grid, reference_height)
    out = np.empty((len(aligned), grid.size))
    for row, a in zip(out, aligned, strict=True):
        row[:] = resample_profile(a.y_mm, a.z_mm, grid)
    return z_ref - out


#: Profiles per block: each step's arrays of a block stay in the processor's cache.
BLOCK = 128


def process_profiles_free(
    profiles: Sequence[tuple[ArrayLike, ArrayLike]],
    *,
    reference_height: ReferenceHeight = s1002_height_mm,
    grid_y_mm: ArrayLike = DEFAULT_GRID_Y_MM,
    split_y_mm: float = DEFAULT_SPLIT_Y_MM,
) -> list[ProcessedProfile | ValueError]:
    """``process_profile(y, z, alignment="free")`` of each (y_mm, z_mm) raw profile [mm].

    Returns
    -------
    One ProcessedProfile per profile, in order, or the ``ValueError`` that
    ``process_profile`` raises for it (a profile that cannot be cleaned or aligned).
    """
    grid = np.asarray(grid_y_mm, dtype=float)
    out: list[ProcessedProfile | ValueError] = []
    for start in range(0, len(profiles), BLOCK):
        out += _process_block(profiles[start:start + BLOCK], reference_height, grid,
                              split_y_mm)
    return out


def flange_parameters_of(profiles: Sequence[tuple[NDArray, NDArray]]
                         ) -> list[FlangeParameters]:
    """:func:`.profile_parameters.flange_parameters` of each (y_mm, z_mm) profile [mm]
    (ascending y, finite), computed together."""
    if not profiles:
        return []
    y, valid = pack([p[0] for p in profiles], 0.0)
    z, _ = pack([p[1] for p in profiles], 0.0)
    return [FlangeParameters(sd_mm=sd, sh_mm=sh, qr_mm=qr)
            for sd, sh, qr in flange_parameters_rows(y, z, valid).tolist()]


def _process_block(profiles: Sequence[tuple[ArrayLike, ArrayLike]],
                   reference_height: ReferenceHeight, grid: NDArray[np.float64],
                   split_y_mm: float) -> list[ProcessedProfile | ValueError]:
    out: list[ProcessedProfile | ValueError] = []
    cleaned: list[CleanedProfile] = []
    where: list[int] = []
    for y, z in profiles:
        try:
            c = clean_profile(y, z)
        except ValueError as exc:
            out.append(exc)
            continue
        where.append(len(out))
        out.append(exc_placeholder)
        cleaned.append(c)
    aligned: list[AlignedProfile] = []
    kept: list[int] = []
    batch = align_to_reference_batch([(c.y_mm, c.z_mm) for c in cleaned], reference_height)
    for k, (c, a) in enumerate(zip(cleaned, batch, strict=True)):
        if a is None:
            try:
                a = align_to_reference(c.y_mm, c.z_mm, reference_height)
            except ValueError as exc:
                out[where[k]] = exc
                continue
        aligned.append(a)
        kept.append(k)
    if not aligned:
        return out
    wear = _wear_rows(aligned, grid, reference_height)
    flange, tread = wear_areas_rows(grid, wear, split_y_mm)
    parameters = flange_parameters_of([(a.y_mm, a.z_mm) for a in aligned])
    # a wear curve nowhere below -NEGATIVE_WEAR_MM has no stretch of material above the
    # reference: check_reference need not search it (the check's outcome is the same)
    with np.errstate(invalid="ignore"):
        may_stretch: NDArray[np.bool_] = np.any(wear < -NEGATIVE_WEAR_MM, axis=1)
    for row, (k, a) in enumerate(zip(kept, aligned, strict=True)):
        c = cleaned[k]
        areas = WearAreas(flange_mm2=float(flange[row]), tread_mm2=float(tread[row]))
        w = wear[row]
        out[where[k]] = ProcessedProfile(
            cleaned=c, aligned=a, grid_y_mm=grid, wear_mm=w, areas=areas,
            parameters=parameters[row], alignment="free", datum=None,
            reference_check=check_reference(
                parameters[row], areas, reference_height, tape_circle_height_mm(grid, w),
                a.rms_residual_mm, *((grid, w) if may_stretch[row] else (None, None))))
    return out


#: Stands in the output list for a profile whose result is not known yet.
exc_placeholder = ValueError("profile not processed")
