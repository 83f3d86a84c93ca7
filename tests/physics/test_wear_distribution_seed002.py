"""Seed 002's mechanism on one synthetic contact patch: local vs global Archard application.

Seed 002 §3: in the local application (Archard per FASTSIM element, eqs. 4-5) only the slip area
wears, so it removes less than the global application (whole patch, semi-elliptic, eq. 3) and
peaks higher where it does wear. On one patch with pure longitudinal creepage xi (no spin) this
is analytic in the continuum:

* Volume. In the slip area the traction is mu p_n along the slip, so sum p_n |s| dA =
  (traction . slip) / mu = F . w / mu (steady rolling: the dissipation equals F . w). With one
  wear coefficient the local volume is k F.w / (mu H) against the global k N |w| / H, so
  local / global = F . w / (mu N |w|) = |Fx| / (mu N) <= 1, equal only at full sliding.
* Shape at full sliding. Local: each strip wears in proportion to its load; with FASTSIM's
  parabolic pressure that is (1 - u^2)^(3/2), u = y / b, whose area is 3 pi / 8. Global: the
  semi-ellipse (1 - u^2)^(1/2), area pi / 2. Same volume, so the local peak is
  (pi / 2) / (3 pi / 8) = 4/3 of the global one.
* In partial slip the local wear sits in the central strips only (FASTSIM with a parabolic
  bound has the same adhesion length in every strip, so the short edge strips stick): the
  local depth is always more concentrated (peak per unit volume), but it is higher than the
  global peak in absolute terms only once most of the patch slides.
* KTH zones. The global application classifies the patch by its mean pressure N / (pi a b) and
  rigid sliding speed; the local one by each element's pressure (parabolic peak = 2x mean) and
  slip speed, which exceeds the rigid one near the trailing edge. Local elements can so enter
  the catastrophic (p > 0.8 H) or severe zone where the global patch stays mild (seed 002
  Fig. 5a: one catastrophic element gives the flange peak).
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.contact.fastsim import fastsim
from wearcast.physics.wear_distribution import local_archard_depth, semi_elliptic_depth
from wearcast.physics.wear_laws import ArchardKTH, archard_basis

A_MM, B_MM, N_N, MU, R_MM, V_M_S = 5.0, 6.0, 50e3, 0.4, 460.0, 20.0
LAW = ArchardKTH()


def _patch(xi: float, n: int = 40, a_mm: float = A_MM, b_mm: float = B_MM,
           speed_m_s: float = V_M_S):
    """Local and global depth per metre rolled per unit coefficient, by zone: (4, ny) each,
    on a y grid whose spacing equals the FASTSIM strip width (no aliasing), plus the FASTSIM
    result and the grid."""
    fs = fastsim(np.array([xi]), 0.0, 0.0, a_mm, b_mm, N_N, MU, n_x=n, n_y=n,
                 combined_flexibility=False)
    h = 2.0 * b_mm / n
    half = int(0.75 * n) + 1                       # grid spans +-1.5 b
    y = np.arange(-half, half + 1) * h
    local = local_archard_depth(fs, speed_m_s, 0.0, R_MM, 0.0, y, LAW)[0]   # (4, ny)
    vol = archard_basis(N_N, speed_m_s * xi, speed_m_s, N_N / (np.pi * a_mm * b_mm), LAW)
    shape = semi_elliptic_depth(y, 0.0, b_mm, 1.0, R_MM, 0.0)              # (ny,)
    glob = vol[:, None] * shape[None, :]
    return local, glob, fs, y


def _volume(depth: np.ndarray, y: np.ndarray) -> float:
    """Worn volume per metre rolled [mm^3/m] of a normal depth [mm/m] (flat patch, delta 0)."""
    return float(np.sum(depth) * (y[1] - y[0]) * 2.0 * np.pi * R_MM)


def test_full_sliding_same_volume_and_four_thirds_peak():
    local, glob, fs, y = _patch(0.03)
    lo, gl = local.sum(axis=0), glob.sum(axis=0)    # one coefficient for every zone
    assert fs.slip_area_fraction[0] == pytest.approx(1.0)
    # Discretisation of the 40x40 grid: measured 0.9945 (0.9966 on 200x200).
    assert _volume(lo, y) / _volume(gl, y) == pytest.approx(1.0, abs=0.01)
    # Analytic 4/3 (parabolic strip load vs semi-ellipse); measured 1.33 on the matched grid.
    assert lo.max() / gl.max() == pytest.approx(4.0 / 3.0, rel=0.03)


@pytest.mark.parametrize("xi", [0.0005, 0.001, 0.002, 0.003, 0.005])
def test_partial_slip_removes_less_than_global(xi):
    local, glob, fs, y = _patch(xi)
    assert 0.0 < fs.slip_area_fraction[0] < 1.0
    ratio = _volume(local.sum(axis=0), y) / _volume(glob.sum(axis=0), y)
    assert ratio < 1.0
    # ... and never more than the continuum bound |Fx| / (mu N) (dissipation identity).
    assert ratio < abs(float(fs.fx_n[0])) / (MU * N_N)


def test_volume_ratio_converges_to_dissipation_identity():
    """local / global -> |Fx| / (mu N) as the FASTSIM grid is refined (xi = 0.001, 20 % slip)."""
    errors = []
    for n in (50, 200):
        local, glob, fs, y = _patch(0.001, n=n)
        ratio = _volume(local.sum(axis=0), y) / _volume(glob.sum(axis=0), y)
        errors.append(abs(ratio / (abs(float(fs.fx_n[0])) / (MU * N_N)) - 1.0))
    assert errors[1] < errors[0]
    assert errors[1] < 0.05   # measured 3.4 % on 200x200 (7 % on 100x100)


def test_local_is_more_concentrated_and_peaks_higher_only_when_most_slides():
    conc, peak = [], []
    for xi in (0.0005, 0.001, 0.003, 0.005):
        local, glob, _, y = _patch(xi)
        lo, gl = local.sum(axis=0), glob.sum(axis=0)
        conc.append((lo.max() / _volume(lo, y)) / (gl.max() / _volume(gl, y)))
        peak.append(lo.max() / gl.max())
        # The edge strips (shorter than the adhesion length) do not wear locally.
        assert lo[np.abs(y) > 0.9 * B_MM].sum() < 0.02 * lo.sum()
    assert min(conc) > 1.15                     # measured 1.21-1.33
    assert np.all(np.diff(peak) > 0)
    assert peak[0] < 1.0 < peak[-1]              # measured 0.20 (10 % slip) .. 1.27 (87 %)


def test_local_elements_reach_catastrophic_zone_where_global_patch_is_mild():
    """Mean pressure 0.64 x 0.8 H (global: mild), parabolic peak 1.29 x 0.8 H (local: zone 4)."""
    a, b = 3.0, 3.5
    local, glob, fs, y = _patch(0.008, a_mm=a, b_mm=b)   # rigid speed 0.16 m/s < v1: zone 1
    assert 0.3 < fs.slip_area_fraction[0] < 0.8                # partial slip (measured 0.53)
    limit = LAW.pressure_fraction * LAW.hardness_mpa
    assert N_N / (np.pi * a * b) < limit < float(fs.pn_peak_mpa[0])
    assert glob[3].sum() == 0.0 and glob[0].sum() > 0.0
    assert local[3].sum() > 0.0
    k = LAW.effective_coefficients
    # With KTH's k4 = 70 k1 the few catastrophic elements outweigh the smaller slip volume.
    assert _volume(k @ local, y) > _volume(k @ glob, y)
    assert (k @ local).max() > (k @ glob).max()


def test_element_slip_speed_exceeds_rigid_sliding_speed():
    """Near the trailing edge the slip exceeds the creepage (s = w + L dp/dx with the bound
    falling): a patch whose rigid sliding speed is just under v1 gets severe-zone elements."""
    v1 = LAW.velocity_limits_m_s[0]
    xi = 0.004
    speed = 0.9 * v1 / xi                         # rigid sliding speed 0.9 v1: global zone 1
    local, glob, fs, _ = _patch(xi, speed_m_s=speed)
    assert float(np.max(np.hypot(fs.sx, fs.sy))) > xi
    assert glob[1].sum() == 0.0 and glob[0].sum() > 0.0
    assert local[1].sum() > 0.0
