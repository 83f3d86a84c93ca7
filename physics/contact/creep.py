"""Creep forces with saturation for the curving model, and a FASTSIM wrapper for final states.

``creep_forces`` is the fast, smooth law used inside the nonlinear equilibrium solver:
Kalker's linear theory with spin (``kalker.linear_creep_forces``) saturated by the
Shen-Hedrick-Elkins rule (Shen, Hedrick, Elkins, "A comparison of alternative creep force
models for rail vehicle dynamic analysis", Proc. 8th IAVSD Symposium, 1983):

    F_lin = sqrt(Fx_lin^2 + Fy_lin^2),  u = F_lin / (mu Fn)
    F_sat = mu Fn (u - u^2/3 + u^3/27)  for u < 3,   mu Fn  for u >= 3
    (Fx, Fy, Mz) = (F_sat / F_lin) (Fx_lin, Fy_lin, Mz_lin)

The saturation curve has f'(3) = f''(3) = 0, so the law is twice continuously differentiable
in the creepages (the ratio F_sat/F_lin = 1 - u/3 + u^2/27 is a polynomial), and costs a few
array operations per contact. Agreement with FASTSIM (CONTACT rule, parabolic bound, 60x60;
a = 6, b = 4 mm, Fn = 80 kN, mu = 0.3; tests/physics/test_creep.py): pure xi or eta up to 8x
the characteristic creepage mu Fn/(G a b C11): |dF| <= 0.006 mu Fn; random xi, eta within 4x
with spin |phi a| within 1x: max 0.083, mean 0.026 mu Fn. Large spin is SHE's weakness: pure
spin with phi a = 2x / 4x / 8x the characteristic creepage gives 0.08 / 0.21 / 0.51 mu Fn
(SHE saturates the linear spin force to mu Fn; FASTSIM's spin force stays below ~0.75 mu Fn).

``creep_forces_fastsim`` runs FASTSIM for a converged state, when traction and slip fields are
wanted (wear measures).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.fastsim import Bound, FastsimResult, fastsim
from wearcast.physics.contact.kalker import KALKER_ROW_SHAPE, KALKER_TABLE, linear_creep_forces
from wearcast.physics.contact.kalker_kernel import saturated_creep_flat


@dataclass(frozen=True)
class CreepForces:
    """Saturated creep forces; arrays of the broadcast input shape.

    fx_n, fy_n : longitudinal and lateral creep force [N]
    mz_nmm : spin moment [N*mm]
    saturation : F_sat / F_lin in (0, 1] (1 = linear theory)
    """

    fx_n: NDArray[np.float64]
    fy_n: NDArray[np.float64]
    mz_nmm: NDArray[np.float64]
    saturation: NDArray[np.float64]


def she_saturation(u: ArrayLike) -> NDArray[np.float64]:
    """Shen-Hedrick-Elkins ratio F_sat/F_lin for u = F_lin/(mu Fn) >= 0 (C2-smooth).

    1 - u/3 + u^2/27 for u < 3, 1/u beyond (SHE 1983).
    """
    ua = np.abs(np.asarray(u, dtype=float))
    uc = np.minimum(ua, 3.0)
    poly = 1.0 - uc / 3.0 + uc**2 / 27.0
    with np.errstate(divide="ignore"):
        return np.where(ua < 3.0, poly, 1.0 / np.maximum(ua, 3.0))


def creep_forces(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
                 b_mm: ArrayLike, normal_force_n: ArrayLike, mu: ArrayLike,
                 shear_modulus_mpa: float = 82_000.0, poisson: float = 0.28) -> CreepForces:
    """Saturated creep forces: Kalker's linear theory with spin + Shen-Hedrick-Elkins.

    Parameters
    ----------
    xi, eta : longitudinal and lateral creepage [-]
    phi_per_mm : spin creepage [1/mm]
    a_mm, b_mm : contact semi-axes, a in the rolling direction [mm]
    normal_force_n : normal force Fn [N], >= 0
    mu : coefficient of friction [-], >= 0
    shear_modulus_mpa, poisson : G [MPa] and nu

    Returns
    -------
    CreepForces (Fx, Fy [N], Mz [N*mm], saturation factor); vectorised, smooth. Evaluated per
    contact by the compiled kernel ``kalker_kernel.saturated_creep_flat``
    (``_creep_forces_numpy`` is its numpy reference).
    """
    fn = np.asarray(normal_force_n, dtype=float)
    mu = np.asarray(mu, dtype=float)
    if np.any(fn < 0) or np.any(mu < 0):
        raise ValueError("normal_force_n and mu must be >= 0")
    if not 0.0 <= poisson <= 0.5:
        raise ValueError(f"poisson must lie in [0, 0.5] for Kalker's table, got {poisson}")
    args = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                 (xi, eta, phi_per_mm, a_mm, b_mm)), fn, mu)
    if np.any(args[3] <= 0) or np.any(args[4] <= 0):
        raise ValueError("semi-axes a_mm and b_mm must be positive")
    shape = args[0].shape
    flat = [np.ascontiguousarray(v.reshape(-1)) for v in args]
    out = saturated_creep_flat(flat[0], flat[1], flat[2], flat[3], flat[4], flat[5], flat[6],
                               float(shear_modulus_mpa), float(poisson), KALKER_TABLE,
                               KALKER_ROW_SHAPE)
    fx, fy, mz, ratio = (out[:, i].reshape(shape) for i in range(4))
    return CreepForces(fx_n=fx, fy_n=fy, mz_nmm=mz, saturation=ratio)


def _creep_forces_numpy(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
                        b_mm: ArrayLike, normal_force_n: ArrayLike, mu: ArrayLike,
                        shear_modulus_mpa: float = 82_000.0, poisson: float = 0.28
                        ) -> CreepForces:
    """Reference (numpy) implementation of :func:`creep_forces` (same arguments and result),
    the check of the compiled kernel ``kalker_kernel.saturated_creep_flat``."""
    fn = np.asarray(normal_force_n, dtype=float)
    mu = np.asarray(mu, dtype=float)
    lin = linear_creep_forces(xi, eta, phi_per_mm, a_mm, b_mm, shear_modulus_mpa, poisson)
    f_lin = np.hypot(lin.fx_n, lin.fy_n)
    limit = mu * fn
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(limit > 0, f_lin / np.where(limit > 0, limit, 1.0), np.inf)
    ratio = np.where(f_lin > 0, she_saturation(u), np.where(limit > 0, 1.0, 0.0))
    return CreepForces(fx_n=ratio * lin.fx_n, fy_n=ratio * lin.fy_n,
                       mz_nmm=ratio * lin.mz_nmm, saturation=ratio)


def creep_forces_fastsim(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
                         b_mm: ArrayLike, normal_force_n: ArrayLike, mu: ArrayLike,
                         shear_modulus_mpa: float = 82_000.0, poisson: float = 0.28,
                         n_x: int = 40, n_y: int = 40, bound: Bound = "parabolic",
                         combined_flexibility: bool = True) -> FastsimResult:
    """FASTSIM for the final state of a curving solution (traction, slip, forces).

    Same inputs as ``creep_forces``; grid, traction bound and flexibility rule as
    ``fastsim.fastsim`` (CONTACT's choices by default).
    """
    return fastsim(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, mu,
                   shear_modulus_mpa=shear_modulus_mpa, poisson=poisson, n_x=n_x, n_y=n_y,
                   bound=bound, combined_flexibility=combined_flexibility)
