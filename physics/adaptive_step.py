"""Adaptive discrete steps of the wear loops: the step that removes D_step at its deepest point.

Seed 003 eq. 2-4 (seed 003 in docs/references.md): each discrete step scales the
removed-material distribution so that its maximum over the profile's natural abscissa is the
threshold, km_step = D_step^w / max_s Delta^w(s) for the wheel (eq. 2-3) and N_step = D_step^r /
max_s Delta^r(s) vehicles for the rail (eq. 4). Delta(s) is a depth **normal to the profile**
(the worn material is removed in the normal direction, seed 003 §4.3; seed 004 eq. 9), so the
threshold bounds the normal depth, not the vertical change of z(y): on a flange face at 80 deg
a normal depth d moves z by d / cos 80 deg = 5.8 d, and a vertical bound would shorten the
steps by that factor wherever the steep flank wears most (before stop 32 the wheel loops did
that; the rail steps always bounded the normal depth).

On a profile stored as z(y) the wheel loops also bound the vertical change of a step
(``MAX_VERTICAL_STEP_FACTOR``), a numerical limit of that representation.

One implementation for the wheel loops (``wear_loop.simulate_wear`` in its adaptive mode,
``vehicle_wear_simulation.simulate_vehicle_wear``) and the rail steps
(``rail_wear_per_vehicle.rail_step_rows``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Largest vertical change of z(y) in one wheel step, in D_step [-]. The wheel loops store a
#: profile as z on a fixed y grid and remove the normal depth by moving each point along its
#: normal and re-sampling (``wear_distribution.apply_normal_wear``; where the moved points
#: fold back, the vertical equivalent d / cos(delta) at every point). On a near-vertical
#: flange face (slope factor 1 / cos(delta) up to ~47 on the Aosta wheels by 8,000 km) a
#: normal depth of D_step is a vertical change of up to 47 D_step at a fixed y, which that
#: re-sampling does not follow: with the normal bound alone (this factor inf) the whole-vehicle
#: Aosta run of ``tests/physics/test_contact_slots.py`` (every trip forward, D_step 0.8 mm)
#: diverged (a flange face 44 mm below the new profile vertically near 6,200 km, 69 mm
#: normal to it near 6,700 km when the run goes on to that check); with
#: 4 it runs to 8,000 km. A numerical bound of the representation, binding only on flanks
#: steeper than acos(1/4) = 75.5 deg; the seed's threshold is the normal one.
MAX_VERTICAL_STEP_FACTOR = 4.0


def deepest_normal_depth(normal_depth: ArrayLike) -> float:
    """max_s Delta(s) of a normal-depth distribution (any shape, any unit of depth per unit
    of exposure: mm per km of the wheel, mm per vehicle of the rail); 0 where nothing wears."""
    d = np.asarray(normal_depth, dtype=float)
    return max(float(np.max(d)), 0.0) if d.size else 0.0


def deepest_vertical_change(normal_depth: ArrayLike, slope: ArrayLike) -> float:
    """The largest change of z at a fixed y that a normal-depth distribution makes on a profile
    of slope dz/dy (same shape): max d sqrt(1 + z'^2) = max d / cos(delta) [mm, or mm per unit
    of exposure]; 0 where nothing wears. Exact where the moved points do not fold back
    (``wear_distribution.apply_normal_wear``)."""
    g = np.asarray(slope, dtype=float)
    return deepest_normal_depth(np.asarray(normal_depth, dtype=float) * np.sqrt(1.0 + g * g))


def adaptive_step(normal_depth_rate: ArrayLike, depth_per_step_mm: float,
                  slope: ArrayLike | None = None) -> float:
    """The exposure of one adaptive step, D_step / max_s Delta(s) (seed 003 eq. 2, 4), at
    most ``MAX_VERTICAL_STEP_FACTOR`` D_step of vertical change where ``slope`` is given.

    Parameters
    ----------
    normal_depth_rate : normal wear depth per unit of exposure over the profile [mm/km for a
        wheel, mm per vehicle passage for a rail]; of every profile the step advances together
        (a whole vehicle's wheels share one step)
    depth_per_step_mm : the threshold D_step [mm], positive
    slope : dz/dy of the profiles on the same grid (same shape) [-], for the wheel loops that
        re-sample the worn profile z(y) on a fixed y grid (``apply_normal_wear``); None: the
        normal bound alone (the rail steps)

    Returns
    -------
    exposure [km or vehicles] at which the deepest point has lost ``depth_per_step_mm``
    normal to the profile (or, on a flank steeper than acos(1 / MAX_VERTICAL_STEP_FACTOR),
    the point changing most vertically has changed by MAX_VERTICAL_STEP_FACTOR D_step);
    inf where nothing wears.
    """
    if not depth_per_step_mm > 0:
        raise ValueError(f"depth_per_step_mm must be positive, got {depth_per_step_mm}")
    rate = np.asarray(normal_depth_rate, dtype=float)
    peak = deepest_normal_depth(rate)
    step = depth_per_step_mm / peak if peak > 0 else float("inf")
    if slope is not None:
        vertical = deepest_vertical_change(rate, slope)
        if vertical > 0:
            step = min(step, MAX_VERTICAL_STEP_FACTOR * depth_per_step_mm / vertical)
    return step
