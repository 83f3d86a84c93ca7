"""Smoothing of the curving contact table's vertical gap along the wheel profile.

The contact table (:mod:`wearcast.physics.curving_table`) smooths the rigid geometry's
vertical gap of every wheel point over the rail with a Gaussian (2 mm): the raw gap of a
nearly conformal tread has shallow double minima, and the Newton solve of the curving needs
contact candidates that move continuously with the shift. Wheel points with no rail below them
(the flange beyond the rail's gauge face) have no vertical gap. Two methods
(``GAP_SMOOTHING``, or ``gap_smoothing=`` of ``curving_table.build_contact_table``):

* ``masked`` (the default since stop 30): normalised convolution over the points with rail
  below (:func:`masked_gaussian`, Knutsson-Westin 1993), the certainty of each point a C1 ramp
  over ``RAIL_EDGE_RAMP_MM`` of its exact distance inside the rail's envelope
  (``contact.geometry.rigid_wheel_gap_beyond_rail``), so the weights move continuously with
  the shift; off the rail a wall rising to ``NO_RAIL_GAP_MM`` with the missing coverage. The
  loaded flange patch then matches the one contact pipeline in its own force equilibrium
  (the Manchester trailer at 150-600 m, with the candidates' contact angle from the wheel's
  slope averaged with the same weights, ``smooth_like_gap``, ``curving_table.ContactTable``:
  position 0.02-0.50 mm, angle 0.2-0.8 deg, b within 9 %, tau_max within 16 % at 250-600 m,
  b 16 % and tau_max 29 % low at 150 m; with the slope at the point 0.3-0.9 mm;
  ``benchmarks/curving_flange_table_vs_rigid.py`` block 3,
  ``tests/physics/test_curving_flange_contact.py``).
* ``gaussian`` (the default before stop 30): those points are filled with ``NO_RAIL_GAP_MM``
  and the plain Gaussian filter runs over the whole row. The fill is averaged into the flank's
  gap: the loaded flange-root patch is in place but about 10x too narrow (b 0.6 against
  5.4-5.7 mm) with tau_max 3-6x too high, and the unloaded first touch lies 4-6 mm down at
  the root (README, known gaps).

Set ``GAP_SMOOTHING`` before any table is built: the cached tables
(``curving_table.contact_table_for`` ...) do not key on it.

Both methods' Gaussian filters (and their derivatives) come from the compiled
``gap_smoothing_kernel.gaussian_rows``: scipy's ``gaussian_filter1d`` (mode ``nearest``) bit
for bit, the three orders in one pass over the rows.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.gap_smoothing_kernel import gaussian_rows, gaussian_taps

#: Methods of :func:`smooth_gap` (module docstring).
GAP_SMOOTHING_METHODS = ("gaussian", "masked")

#: The method the contact tables use unless ``gap_smoothing`` is given (module docstring).
GAP_SMOOTHING = "masked"

#: Vertical gap [mm] of wheel points with no rail below them (the flange beyond the gauge
#: face): the ``gaussian`` method's fill, the ``masked`` method's wall. They cannot touch.
NO_RAIL_GAP_MM = 100.0

#: Width [mm] (track y) of the ramp of the rail's coverage inside the rail's ends (``masked``):
#: a wheel point this far or farther inside the rail's envelope has full weight in the
#: smoothing, one beyond the envelope none. A module setting read at table build (like
#: ``GAP_SMOOTHING``; the cached tables do not key on it); the ``gaussian`` method ignores it.
#: 3 mm (the default; 1.5 x the smoothing's 2 mm standard deviation, so the normalised
#: convolution's denominator G*(m) varies on the patch scale, not below it): the smoothed gap
#: of a FLANK-WORN wheel keeps one minimum moving continuously with the shift, and the Aosta
#: whole-vehicle loop is step-converged (helper flange12c, stop 29), with the unloaded first
#: touch 1.3-1.8 mm (1:40) and 1.8-2.4 mm (1:20) root-wards of the rigid one (still on the
#: flank; the Gaussian method is 3-6 mm off). A 1 mm ramp keeps that first touch within
#: 0.1-1.0 mm but the loop is not step-converged with it.
RAIL_EDGE_RAMP_MM = 3.0


def check_gap_smoothing(method: str) -> str:
    """``method`` if it is one of ``GAP_SMOOTHING_METHODS``, else ValueError naming it."""
    if method not in GAP_SMOOTHING_METHODS:
        raise ValueError(f"gap_smoothing must be one of {GAP_SMOOTHING_METHODS}, got {method!r}")
    return method


def _gaussian_orders(values: NDArray[np.float64], sigma_samples: float
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``values`` (..., n) filtered along the last axis with a Gaussian of ``sigma_samples``
    [samples] and with its first and second derivatives, mode ``nearest`` (values per
    sample^order): scipy's ``gaussian_filter1d`` of orders 0, 1, 2, bit for bit, from the
    compiled ``gap_smoothing_kernel.gaussian_rows``."""
    v = np.asarray(values, dtype=float)
    rows = np.ascontiguousarray(v.reshape(-1, v.shape[-1]))
    taps = (gaussian_taps(float(sigma_samples), o) for o in (0, 1, 2))
    f0, f1, f2 = gaussian_rows(rows, *taps)
    return f0.reshape(v.shape), f1.reshape(v.shape), f2.reshape(v.shape)


def masked_gaussian(weighted_values: NDArray[np.float64], mask: NDArray[np.float64],
                    sigma_samples: float
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gaussian smoothing along the last axis over the masked samples only (normalised
    convolution, Knutsson-Westin 1993), with certainty m in [0, 1] per sample and the values
    already weighted by it (m v): S = G*(m v) / G*(m), and its second derivative
    S'' = (N'' - 2 S' D' - S D'') / D with N = G*(m v), D = G*(m), S' = (N' - S D') / D
    [per sample^2] (D', D'' taken relative to a full mask). Where the whole kernel lies on the
    mask it is the plain Gaussian filter and its second derivative (D = 1, D' = D'' = 0).
    Off the mask the returned values are meaningless (D may vanish); the caller replaces them.

    Parameters
    ----------
    weighted_values : (..., n) the samples times their certainty, m v (finite; 0 where m = 0)
    mask : (..., n) certainty m of each sample in [0, 1] (0: takes no part)
    sigma_samples : standard deviation of the Gaussian [samples]

    Returns
    -------
    (smoothed, second derivative per sample^2), each (..., n)
    """
    m = np.asarray(mask, dtype=float)
    n0, n1, n2 = _gaussian_orders(weighted_values, sigma_samples)
    # the derivatives of D relative to a full mask: scipy's truncated derivative kernels do not
    # sum to exactly zero, and the plain filter's second derivative keeps that (so does this
    # one where the mask is full: D' = D'' = 0 there)
    _, full1, full2 = _gaussian_orders(np.ones(m.shape[-1]), sigma_samples)
    d0, d1, d2 = _gaussian_orders(m, sigma_samples)
    d1, d2 = d1 - full1, d2 - full2
    d0 = np.where(d0 > 1e-12, d0, 1.0)
    s0 = n0 / d0
    s1 = (n1 - s0 * d1) / d0
    s2 = (n2 - 2.0 * s1 * d1 - s0 * d2) / d0
    return s0, s2


def smoothstep(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """The C1 step 3 t^2 - 2 t^3 of t = clip(x, 0, 1): 0 for x <= 0, 1 for x >= 1 (also the
    contact table's candidate maturity and slot fades, ``curving_table``)."""
    t = np.clip(x, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def smooth_gap(raw_mm: NDArray[np.float64], inside_mm: NDArray[np.float64] | None,
               scales: tuple[tuple[NDArray[np.float64] | float, float], ...],
               wheel_step_mm: float, method: str
               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The smoothed gap (n_shift, n_wheel) [mm] and its second derivative along the wheel
    [1/mm].

    raw_mm : the rigid gap on the wheel grid, ``NO_RAIL_GAP_MM`` (``gaussian``) or the rail's
        end faces continued (``masked``) where no rail lies below [mm]
    inside_mm : each wheel point's distance inside the rail's envelope (``masked`` only) [mm]
    scales : (weight, standard deviation [mm]) of each Gaussian, the weights summing to 1 at
        every wheel point (the tread and flange scales blended)
    method : ``gaussian`` or ``masked`` (module docstring)
    """
    gap, gap2, coverage = _smooth_rows(raw_mm, inside_mm, scales, wheel_step_mm, method)
    if coverage is None:
        return gap, gap2
    # no rail below: no contact, a wall of NO_RAIL_GAP_MM rising continuously with the missing
    # coverage (the candidates cannot sit on it, and the gap stays continuous in the shift)
    return coverage * gap + (1.0 - coverage) * NO_RAIL_GAP_MM, coverage * gap2


def smooth_like_gap(values: NDArray[np.float64], n_shift: int,
                    inside_mm: NDArray[np.float64] | None,
                    scales: tuple[tuple[NDArray[np.float64] | float, float], ...],
                    wheel_step_mm: float, method: str) -> NDArray[np.float64]:
    """A quantity of the wheel points ``values`` (n_wheel,) averaged with the weights of
    :func:`smooth_gap` (same Gaussians; ``masked``: the same normalised convolution over the
    points with rail below at each shift), (n_shift, n_wheel). Where the gap is a wall (no
    rail below) the point value, blended with the rail's coverage like the wall.

    The contact table's candidates take their contact angle from the wheel's slope averaged
    so (``curving_table.ContactTable``): at a minimum of the smoothed gap S = G*(m g)/G*(m)
    the m-weighted kernel means of the wheel's and the rail's slopes agree up to the mask's
    edge term G*(m' (g - S))/G*(m), so the common tangent at the patch scale is the wheel's
    slope averaged with the weights m G, not with the plain G (which mixes in wheel points
    beyond the rail's gauge corner that the gap does not see).
    """
    v = np.asarray(values, dtype=float)
    rows = np.ascontiguousarray(np.broadcast_to(v, (n_shift, v.size)))
    mean, _, coverage = _smooth_rows(rows, inside_mm, scales, wheel_step_mm, method)
    if coverage is None:
        return mean
    return coverage * mean + (1.0 - coverage) * v


def _smooth_rows(rows: NDArray[np.float64], inside_mm: NDArray[np.float64] | None,
                 scales: tuple[tuple[NDArray[np.float64] | float, float], ...],
                 wheel_step_mm: float, method: str
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64],
                            NDArray[np.float64] | None]:
    """``rows`` (n_shift, n_wheel) smoothed by ``method`` with the blended ``scales``, its
    second derivative along the wheel [per mm^2], and the rail's coverage of each point
    (``masked``; None for ``gaussian``) (:func:`smooth_gap`; off the coverage the ``masked``
    values are meaningless, the callers blend them out)."""
    check_gap_smoothing(method)
    out = np.zeros_like(rows)
    out2 = np.zeros_like(rows)
    if method == "gaussian":
        for weight, sd in scales:
            g0, _, g2 = _gaussian_orders(rows, sd / wheel_step_mm)
            out += weight * g0
            out2 += weight * g2 / wheel_step_mm**2
        return out, out2, None
    if inside_mm is None:
        raise ValueError("the masked gap smoothing needs each point's distance inside the rail")
    coverage = smoothstep(inside_mm / RAIL_EDGE_RAMP_MM)
    for weight, sd in scales:
        g0, g2 = masked_gaussian(coverage * rows, coverage, sd / wheel_step_mm)
        out += weight * g0
        out2 += weight * g2 / wheel_step_mm**2
    return out, out2, coverage
