"""The batched processing equals the per-profile one, profile by profile.

wearcast.statistics.processing_batch (and the batched cleaning, alignment, table lookup and
flange parameters under it) must give what process_profile gives to floating-point round-off:
the same cleaned points, the same alignment, wear curve, areas, parameters and reference
check, and the same ValueError for an unusable profile.
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.profiles.parameters import flange_parameters, flange_parameters_rows
from wearcast.physics.profiles.references import points_height
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import reference_table
from wearcast.statistics.cleaning import clean_profile
from wearcast.statistics.processing import ProcessedProfile, process_profile
from wearcast.statistics.processing_batch import process_profiles_free
from wearcast.statistics.ragged import pack
from wearcast.statistics.table_interp import reference_even_table

#: Agreement asked of batch and per-profile results [mm, rad, mm²]: round-off only.
ROUND_OFF = 1e-9


def _measured(rng, n=400, tread_mm=1.0, flange_mm=0.6):
    """A worn S1002 as an instrument gives it: moved, rotated, noisy, field side first."""
    y = np.linspace(-70.0, 60.0, n)
    wear = (tread_mm * np.exp(-0.5 * ((y - rng.uniform(-5, 10)) / 11.0) ** 2)
            + flange_mm * np.exp(-0.5 * ((y + 38.0) / 3.0) ** 2))
    z = s1002_height_mm(y) - wear
    theta, dy, dz = rng.normal(0.0, 0.003), rng.normal(0.0, 1.0), rng.normal(0.0, 0.5)
    c, s = np.cos(theta), np.sin(theta)
    ym, zm = c * y - s * z + dy, s * y + c * z + dz + rng.normal(0.0, 0.01, n)
    return ym[::-1].copy(), zm[::-1].copy()


def _irregular(rng):
    """Profiles each of which leaves the batch's regular path somewhere."""
    y, z = _measured(rng)
    out = [
        (y[::-1].copy(), z[::-1].copy()),  # back face first
        (y.copy(), -z),  # z downward
        (-y[::-1], z[::-1].copy()),  # mirrored
        (np.where(np.arange(y.size) == 10, np.nan, y), z.copy()),  # a NaN point
        (y.copy(), z + np.where(np.arange(z.size) == 200, 5.0, 0.0)),  # a spike
        (y[np.r_[0:100, 101, 100, 102:y.size]], z.copy()),  # a zig-zag
        (y[:100].copy(), z[:100].copy()),  # misses the tread
        (y / 1000.0, z / 1000.0),  # metres
        (y[:10].copy(), z[:10].copy()),  # too few points
        (np.repeat(y, 2), np.repeat(z, 2)),  # duplicates to merge
        (np.full(y.size, 1.0), z.copy()),  # no lateral extent
    ]
    yb = np.concatenate([y, -70.0 - np.linspace(0.001, 0.01, 10) + (y[-1] + 70.0)])
    zb = np.concatenate([z, z[-1] - np.linspace(1.0, 10.0, 10)])
    out.append((yb, zb))  # a back face run to trim
    out.append(_measured(rng, n=250))  # another length
    return out


def _assert_same(p, q):
    if isinstance(p, ValueError):
        assert isinstance(q, ValueError) and str(q) == str(p)
        return
    assert isinstance(p, ProcessedProfile) and isinstance(q, ProcessedProfile)
    assert np.array_equal(p.cleaned.y_mm, q.cleaned.y_mm)
    assert np.array_equal(p.cleaned.z_mm, q.cleaned.z_mm)
    assert (p.cleaned.n_removed, p.cleaned.notes) == (q.cleaned.n_removed, q.cleaned.notes)
    for name in ("lateral_shift_mm", "vertical_shift_mm", "rotation_rad", "rms_residual_mm"):
        assert getattr(q, name) == pytest.approx(getattr(p, name), abs=ROUND_OFF), name
    assert q.n_used == p.n_used
    np.testing.assert_allclose(q.y_aligned_mm, p.y_aligned_mm, rtol=0, atol=ROUND_OFF)
    np.testing.assert_allclose(q.z_aligned_mm, p.z_aligned_mm, rtol=0, atol=ROUND_OFF)
    np.testing.assert_allclose(q.wear_mm, p.wear_mm, rtol=0, atol=ROUND_OFF)
    assert np.array_equal(np.isnan(q.wear_mm), np.isnan(p.wear_mm))
    assert q.areas.flange_mm2 == pytest.approx(p.areas.flange_mm2, abs=ROUND_OFF)
    assert q.areas.tread_mm2 == pytest.approx(p.areas.tread_mm2, abs=ROUND_OFF)
    for name in ("sd_mm", "sh_mm", "qr_mm"):
        a, b = getattr(p.parameters, name), getattr(q.parameters, name)
        assert (np.isnan(a) and np.isnan(b)) or b == pytest.approx(a, abs=ROUND_OFF), name
    assert p.reference_check is not None and q.reference_check is not None
    assert q.reference_check.fits == p.reference_check.fits
    assert q.reference_check.reasons == p.reference_check.reasons


def _per_profile(profiles, reference_height=s1002_height_mm):
    out = []
    for y, z in profiles:
        try:
            out.append(process_profile(y, z, reference_height=reference_height))
        except ValueError as exc:
            out.append(exc)
    return out


def test_batch_equals_per_profile_on_regular_and_irregular_profiles():
    rng = np.random.default_rng(14)
    profiles = [_measured(rng, tread_mm=rng.uniform(0, 2), flange_mm=rng.uniform(0, 1))
                for _ in range(150)]
    profiles[40:40] = _irregular(rng)  # mixed in, across the 128-profile blocks
    batch = process_profiles_free(profiles)
    single = _per_profile(profiles)
    assert len(batch) == len(profiles)
    assert sum(isinstance(p, ValueError) for p in single) >= 4  # the unusable ones
    for p, q in zip(single, batch, strict=True):
        _assert_same(p, q)


def test_batch_equals_per_profile_against_another_reference():
    """A points reference with a hollow tread: about half the worn S1002s keep material
    above it over a stretch, which the check flags (in the batch as per profile)."""
    y_ref = np.linspace(-70.0, 60.0, 600)
    hollow = points_height(y_ref, s1002_height_mm(y_ref)
                           - 1.2 * np.exp(-0.5 * ((y_ref - 12.0) / 8.0) ** 2))
    rng = np.random.default_rng(7)
    profiles = [_measured(rng) for _ in range(40)]
    batch = process_profiles_free(profiles, reference_height=hollow)
    flagged = [p for p in batch if isinstance(p, ProcessedProfile) and p.reference_check
               and not p.reference_check.fits]
    assert 5 <= len(flagged) <= 35
    assert all(any(r.startswith("material up to") for r in p.reference_check.reasons)
               for p in flagged if p.reference_check)
    for p, q in zip(_per_profile(profiles, hollow), batch, strict=True):
        _assert_same(p, q)


def test_the_block_cleans_irregular_profiles_as_clean_profile_says():
    """The block processing cleans with ``clean_profile`` itself (the cleaning rules are
    written once): each irregular input gets that function's note."""
    rng = np.random.default_rng(3)
    profiles = _irregular(rng)
    notes = {i: clean_profile(*profiles[i - 20]).notes for i in (21, 22, 23, 24, 25, 29)}
    assert notes[21][0].startswith("z was given downward")
    assert notes[22][0].startswith("y was mirrored")
    assert any("non-finite" in n or "NaN" in n for n in notes[23]), notes[23]
    assert notes[24][0].startswith("removed 1 spikes")
    assert notes[25][0].startswith("removed 1 points stepping")
    assert notes[29][0].startswith("merged 400 points")


def test_flange_parameters_rows_equal_flange_parameters():
    rng = np.random.default_rng(5)
    cleaned = [clean_profile(*_measured(rng)) for _ in range(30)]
    rows = [(c.y_mm, c.z_mm) for c in cleaned]
    y0, z0 = rows[0]
    rows += [(y0[:150], z0[:150]),  # ends before the tape circle
             (y0[y0 > -40], z0[y0 > -40]),  # no flange tip region
             (y0[:3], z0[:3]), (y0[y0 < -45], z0[y0 < -45])]
    y, valid = pack([r[0] for r in rows], 0.0)
    z, _ = pack([r[1] for r in rows], 0.0)
    got = flange_parameters_rows(y, z, valid)
    want = np.array([[f.sd_mm, f.sh_mm, f.qr_mm] for f in
                     (flange_parameters(a, b) for a, b in rows)])
    assert np.array_equal(got, want, equal_nan=True)
    assert np.isnan(got[-4:]).all() and np.isfinite(got[:30]).all()


def test_even_table_lookup_equals_np_interp():
    table = reference_table(s1002_height_mm)
    even = reference_even_table(s1002_height_mm)
    rng = np.random.default_rng(2)
    x = np.concatenate([rng.uniform(-90.0, 90.0, 20_000), table.y_mm,
                        np.nextafter(table.y_mm, 100.0), np.nextafter(table.y_mm, -100.0),
                        [np.nan, -np.inf, np.inf]])
    at = even.locate(x)
    for column, values in ((0, table.z_mm), (1, table.slope)):
        assert np.array_equal(even.interp(x, at, column), np.interp(x, table.y_mm, values),
                              equal_nan=True)
        assert np.array_equal(
            even.interp(x, at, column, left=np.nan, right=np.nan),
            np.interp(x, table.y_mm, values, left=np.nan, right=np.nan), equal_nan=True)
