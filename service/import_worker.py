"""Profile processing of an import, run in the importing process or in its pool of worker
processes (:func:`wearcast.service.import_pool.submit_profiles`).

This module imports only numpy and the physics and statistics cores — not the web framework,
the database layer or the rest of the service — so that a spawned pool worker is ready after
about a tenth of the CPU time that importing the whole service would cost it. For the same
reason the reference a profile is taken against travels as a plain tuple
(:data:`RefTuple`), not as the service's ``ReferenceSpec``.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any, NamedTuple, TypeAlias

import numpy as np

from wearcast.physics.profiles.references import (
    HeightFunction,
    builtin_reference,
    points_height,
)

#: (name, kind ``builtin`` | ``points``, y [mm], z [mm]) of a resolved reference.
RefTuple: TypeAlias = tuple[str, str, tuple[float, ...], tuple[float, ...]]
S1002_REF: RefTuple = ("S1002", "builtin", (), ())


class Processed(NamedTuple):
    """What the measurements row keeps of a processed profile (small, so it pickles fast)."""

    wear_mm: np.ndarray
    grid_start_mm: float
    grid_step_mm: float
    flange_area_mm2: float
    tread_area_mm2: float
    lateral_shift_mm: float
    vertical_shift_mm: float
    rotation_rad: float
    rms_residual_mm: float
    sd_mm: float
    sh_mm: float
    qr_mm: float
    reference: str = "S1002"
    reference_fits: bool = True
    reference_reasons: tuple[str, ...] = ()
    placement: dict[str, Any] | None = None
    n_raw: int = 0
    n_removed: int = 0
    cleaning_notes: tuple[str, ...] = ()


def finite_or_none(value: Any) -> float | None:
    """A finite float, or None (for None, NaN and infinities): a nullable number column."""
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


@lru_cache(maxsize=64)
def reference_height(ref: RefTuple) -> HeightFunction:
    """The height function z(y) [mm] of a reference (the same object per reference)."""
    name, kind, y_mm, z_mm = ref
    if kind == "builtin":
        found = builtin_reference(name)
        assert found is not None
        return found.height_mm
    return points_height(np.asarray(y_mm), np.asarray(z_mm))


def process_arrays(y_mm: np.ndarray, z_mm: np.ndarray, ref: RefTuple | None = None,
                   datum: bool = False) -> Processed | str:
    """The processed profile, or the reason it cannot be used.

    ``ref`` is the declared reference (default S1002); ``datum`` places the profile by the
    instrument's datum instead of the free rigid fit. Runs in worker processes too, so it
    returns the error as text instead of raising.
    """
    from wearcast.statistics.processing import process_profile

    ref = ref if ref is not None else S1002_REF
    try:
        p = process_profile(y_mm, z_mm, reference_height=reference_height(ref),
                            alignment="datum" if datum else "free")
    except ValueError as exc:
        return str(exc)
    return _processed(p, y_mm, ref, datum)


def _processed(p: Any, y_mm: np.ndarray, ref: RefTuple, datum: bool,
               measured: Any = None) -> Processed:
    """What the row keeps of a ``ProcessedProfile`` ``p`` of the raw points ``y_mm``
    (``measured``: Sd/Sh/qR of its cleaned points, when already computed)."""
    from wearcast.statistics.profile_parameters import flange_parameters

    if datum:
        params = p.parameters  # of the profile as placed on its datum (= as measured)
    elif measured is not None:
        params = measured
    else:
        # Sd/Sh/qR of the profile as measured (back-face referenced, like the instrument),
        # not of the profile moved by the free fit: its lateral shift would move Sd.
        params = flange_parameters(p.cleaned.y_mm, p.cleaned.z_mm)
    grid = np.asarray(p.grid_y_mm)
    placement: dict[str, Any] = {"alignment": p.alignment}
    if p.datum is not None:
        d = p.datum
        placement.update(
            back_face_found=d.back_face_found,
            back_face_y_mm=finite_or_none(d.back_face_y_mm),
            tape_circle_z_mm=finite_or_none(d.tape_circle_z_mm),
            tilt_back_face_rad=finite_or_none(d.tilt_back_face_rad),
            tilt_field_rad=finite_or_none(d.tilt_field_rad),
            tilt_applied_rad=d.tilt_applied_rad, notes=list(d.notes))
    check = p.reference_check
    assert check is not None
    placement["rejected_areas_mm2"] = (None if check.fits else
                                       [float(p.areas.flange_mm2), float(p.areas.tread_mm2)])
    return Processed(np.asarray(p.wear_mm, dtype=np.float32), float(grid[0]),
                     float(grid[1] - grid[0]), float(p.areas.flange_mm2),
                     float(p.areas.tread_mm2), float(p.lateral_shift_mm),
                     float(p.vertical_shift_mm), float(p.rotation_rad),
                     float(p.rms_residual_mm), float(params.sd_mm), float(params.sh_mm),
                     float(params.qr_mm), ref[0], check.fits, check.reasons, placement,
                     int(np.asarray(y_mm).size), int(p.cleaned.n_removed), p.cleaned.notes)


def process_batch(profiles: list[tuple[np.ndarray, np.ndarray, RefTuple | None, bool]]
                  ) -> list[Processed | str]:
    """:func:`process_arrays` of each (y, z, reference, datum).

    Profiles under the free rigid fit are processed together, per reference
    (:func:`wearcast.statistics.processing_batch.process_profiles_free`: the same results to
    round-off, numpy's per-call cost paid once per chunk); datum placements one by one.
    """
    from wearcast.statistics.processing_batch import flange_parameters_of, process_profiles_free

    out: list[Processed | str | None] = [None] * len(profiles)
    free: dict[RefTuple, list[int]] = {}
    for i, (y, z, ref, datum) in enumerate(profiles):
        if datum:
            out[i] = process_arrays(y, z, ref, datum)
        else:
            free.setdefault(ref if ref is not None else S1002_REF, []).append(i)
    for ref, indices in free.items():
        results = process_profiles_free([(profiles[i][0], profiles[i][1]) for i in indices],
                                        reference_height=reference_height(ref))
        done = [(i, p) for i, p in zip(indices, results, strict=True)
                if not isinstance(p, ValueError)]
        # Sd/Sh/qR of the profiles as measured (see _processed), computed together
        measured = flange_parameters_of([(p.cleaned.y_mm, p.cleaned.z_mm) for _, p in done])
        for (i, p), params in zip(done, measured, strict=True):
            out[i] = _processed(p, profiles[i][0], ref, False, params)
        for i, r in zip(indices, results, strict=True):
            if isinstance(r, ValueError):
                out[i] = str(r)
    return out  # type: ignore[return-value]
