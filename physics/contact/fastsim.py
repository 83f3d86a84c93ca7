"""Kalker's FASTSIM for steady rolling on elliptic (Hertzian) contact patches, batched.

Simplified theory (Kalker, "A fast algorithm for the simplified theory of rolling contact",
Vehicle System Dynamics 11 (1982) 1-13; seed 000 §III, seed 001 §2.2): the surface
displacement is u = L p with one flexibility per traction component. In steady rolling the
material enters the patch at the leading edge x = +a_y (a_y = a sqrt(1 - y^2/b^2)) and travels
towards -x. In adhesion the traction grows by

    dpx = -dx (xi / L1 - phi y / L3),   dpy = -dx (eta / L2 + phi x / L3)

per element; where |p| would exceed the traction bound g = mu pn it is scaled back onto the
bound (slip). Signs are those of Kalker's linear theory as in the README:
Fx = -G a b C11 xi etc.

Discretisation: CONTACT's (E.A.H. Vollebregt, ``reference/contact-benchmark/fastsim.inp``) —
a uniform grid of n_x x n_y elements covering [-a, a] x [-b, b]; an element is in contact when
its centre lies inside the ellipse; the traction is evaluated at element centres, marching per
strip from the element nearest the leading edge (implicit Euler in the rolling distance);
forces are dx dy times the sums. Like CONTACT, the spin term of the lateral increment is
evaluated at x + dx/6 (CONTACT's default ``facphi`` = 1/6 of the rolling step, towards the
leading edge); with these choices the module reproduces CONTACT's fastsim.ref_out to all printed
digits (forces, moment, adhesion-element counts; tests/physics/test_fastsim.py). The march
along x is sequential, but every step is vectorised over all strips of all patches.

Traction bound: ``"parabolic"`` pn = 2 Fn/(pi a b) (1 - x^2/a^2 - y^2/b^2) (Kalker's original
choice, which makes FASTSIM's force curve closer to the exact theory) or ``"elliptic"``
(Hertz) pn = 3 Fn/(2 pi a b) sqrt(1 - x^2/a^2 - y^2/b^2).

Flexibilities: Kalker's L1, L2, L3 from C11, C22, C23 (``kalker.fastsim_flexibilities``).
By default (``combined_flexibility=True``) CONTACT's rule shifts them towards one combined
flexibility as the creepage grows (README "Kalker's linear-theory coefficients"): this is what
CONTACT's published FASTSIM numbers include. ``combined_flexibility=False`` is textbook
FASTSIM (w = 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact import fastsim_kernel
from wearcast.physics.contact.kalker import fastsim_flexibilities, kalker_coefficients

Bound = Literal["parabolic", "elliptic"]

#: Offset of the spin term's x [fraction of dx] towards the leading edge (CONTACT's facphi).
SPIN_OFFSET_FRACTION = 1.0 / 6.0


@dataclass(frozen=True)
class FastsimResult:
    """FASTSIM solution for a batch of patches.

    Totals have the broadcast shape S of the inputs; fields have shape S + (n_y, n_x), index
    [..., j, i] for the element centred at (x_mm[..., i], y_mm[..., j]).

    fx_n, fy_n : total tangential forces [N] (on body 1 by body 2, linear theory's sign)
    mz_nmm : spin moment about the patch centre [N*mm]
    px_mpa, py_mpa : surface shear tractions [MPa]
    bound_scale : factor applied to the adhesion trial traction (1 in adhesion, < 1 in slip)
    pn_peak_mpa : peak of the normal pressure used for the traction bound [MPa], shape S
    pn_shape : normalised pressure shape on the grid (0 outside the ellipse), (n_y, n_x)
    mu : coefficient of friction, shape S
    x_mm, y_mm : element centres, shape S + (n_x,) and S + (n_y,) [mm]
    dx_mm, dy_mm : element sizes [mm]
    flexibility_mm_per_mpa : the three flexibilities actually used, shape S + (3,) [mm/MPa]

    Derived fields (properties): pn_mpa, in_contact, adhesion, slipping, sx, sy,
    shear_traction_mpa, slip_area_fraction.
    """

    fx_n: NDArray[np.float64]
    fy_n: NDArray[np.float64]
    mz_nmm: NDArray[np.float64]
    px_mpa: NDArray[np.float64]
    py_mpa: NDArray[np.float64]
    bound_scale: NDArray[np.float64]
    pn_peak_mpa: NDArray[np.float64]
    pn_shape: NDArray[np.float64]
    mu: NDArray[np.float64]
    x_mm: NDArray[np.float64]
    y_mm: NDArray[np.float64]
    dx_mm: NDArray[np.float64]
    dy_mm: NDArray[np.float64]
    flexibility_mm_per_mpa: NDArray[np.float64]

    @property
    def pn_mpa(self) -> NDArray[np.float64]:
        """Normal pressure on the grid [MPa], shape S + (n_y, n_x)."""
        return self.pn_peak_mpa[..., None, None] * self.pn_shape

    @property
    def in_contact(self) -> NDArray[np.bool_]:
        """Element centre lies inside the contact ellipse, shape S + (n_y, n_x)."""
        return np.broadcast_to(self.pn_shape > 0, self.px_mpa.shape)

    @property
    def slipping(self) -> NDArray[np.bool_]:
        """Element in contact whose traction sits on the traction bound."""
        return (self.bound_scale < 1.0) & self.in_contact & (self.mu[..., None, None] > 0)

    @property
    def adhesion(self) -> NDArray[np.bool_]:
        """Element in contact that sticks."""
        return self.in_contact & ~self.slipping

    def _slip(self, p: NDArray[np.float64], flex: NDArray[np.float64]) -> NDArray[np.float64]:
        # (U_final - U_trial)/dx with U = L p and p_trial = p_final / scale (CONTACT's ss/dq).
        with np.errstate(divide="ignore", invalid="ignore"):
            ds = p * (1.0 - 1.0 / self.bound_scale)
        return np.where(self.slipping, flex[..., None, None] / self.dx_mm[..., None, None] * ds,
                        0.0)

    @property
    def sx(self) -> NDArray[np.float64]:
        """Longitudinal local slip / rolling speed [-] (0 in adhesion); x V [m/s] = velocity."""
        return self._slip(self.px_mpa, self.flexibility_mm_per_mpa[..., 0])

    @property
    def sy(self) -> NDArray[np.float64]:
        """Lateral local slip / rolling speed [-] (0 in adhesion)."""
        return self._slip(self.py_mpa, self.flexibility_mm_per_mpa[..., 1])

    @property
    def shear_traction_mpa(self) -> NDArray[np.float64]:
        """|p_t| = sqrt(px^2 + py^2) per element [MPa]."""
        return np.hypot(self.px_mpa, self.py_mpa)

    @property
    def slip_area_fraction(self) -> NDArray[np.float64]:
        """Share of the contact elements that slip [-]."""
        n_con = np.sum(self.pn_shape > 0)
        return np.sum(self.slipping, axis=(-2, -1)) / max(int(n_con), 1)


def _march(dpx: NDArray[np.float64], dpy_t: NDArray[np.float64], g_t: NDArray[np.float64]):
    """The FASTSIM march from the leading edge, vectorised over patches and strips.

    dpx (n, n_y) and dpy_t (n_x, n) are the adhesion increments, g_t (n_x, n, n_y) the traction
    bound. Returns final tractions P, Q and the bound scale S, each (n_x, n, n_y).
    """
    n_x, n, n_y = g_t.shape
    big_p = np.empty((n_x + 1, n, n_y))
    big_q = np.empty((n_x + 1, n, n_y))
    big_p[n_x] = 0.0
    big_q[n_x] = 0.0
    scale = np.empty((n_x, n, n_y))
    t1 = np.empty((n, n_y))
    t2 = np.empty((n, n_y))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i in range(n_x - 1, -1, -1):  # leading edge x = +a first
            p = big_p[i]
            q = big_q[i]
            np.add(big_p[i + 1], dpx, out=p)
            np.add(big_q[i + 1], dpy_t[i][:, None], out=q)
            np.multiply(p, p, out=t1)
            np.multiply(q, q, out=t2)
            t1 += t2
            np.sqrt(t1, out=t1)
            np.divide(g_t[i], t1, out=t1)
            s = np.fmin(t1, 1.0, out=scale[i])  # fmin: 0/0 (no traction, no bound) -> 1
            p *= s
            q *= s
    return big_p[:n_x], big_q[:n_x], scale


def contact_combined_flexibilities(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, mu,
                                   shear_modulus_mpa: float = 82_000.0,
                                   poisson: float = 0.28):
    """Flexibilities L1, L2, L3 [mm/MPa] with CONTACT's combined-flexibility rule.

    L_c = (xi^2 + eta^2 + (phi f4/f3)^2) / (xi^2/L1 + eta^2/L2 + (phi f4/f3)^2/L3) with
    f3 = 8a/3, f4 = pi a^2/4; f = max(1e-10, sqrt((xi^2+eta^2)/(c_xi^2+c_eta^2))) with the
    characteristic creepages c_xi = mu Fn/(a b G C11), c_eta = mu Fn/(a b G C22);
    w = min(1, f/3); each flexibility used is (1 - w) L_i + w L_c (README, as CONTACT applies
    it). Returns (L1, L2, L3, w).
    """
    a = np.asarray(a_mm, dtype=float)
    b = np.asarray(b_mm, dtype=float)
    xi, eta, phi, fn, mu = (np.asarray(v, dtype=float) for v in
                            (xi, eta, phi_per_mm, normal_force_n, mu))
    l1, l2, l3 = fastsim_flexibilities(a, b, shear_modulus_mpa, poisson)
    c = kalker_coefficients(a, b, poisson)
    g = shear_modulus_mpa
    c_xi = mu * fn / (a * b * g * c.c11)
    c_eta = mu * fn / (a * b * g * c.c22)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.sqrt((xi**2 + eta**2) / (c_xi**2 + c_eta**2))
    f = np.maximum(1e-10, np.nan_to_num(f, nan=0.0, posinf=0.0))
    w = np.minimum(1.0, f / 3.0)
    phis = phi * (3.0 * np.pi * a / 32.0)  # phi f4 / f3
    num = xi**2 + eta**2 + phis**2
    den = xi**2 / l1 + eta**2 / l2 + phis**2 / l3
    with np.errstate(divide="ignore", invalid="ignore"):
        lc = np.where(den > 0, num / np.where(den > 0, den, 1.0), l1)
    return ((1 - w) * l1 + w * lc, (1 - w) * l2 + w * lc, (1 - w) * l3 + w * lc, w)


def fastsim(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
            b_mm: ArrayLike, normal_force_n: ArrayLike, mu: ArrayLike,
            shear_modulus_mpa: float = 82_000.0, poisson: float = 0.28, n_x: int = 40,
            n_y: int = 40, bound: Bound = "parabolic", combined_flexibility: bool = True,
            flexibilities_mm_per_mpa: tuple[ArrayLike, ArrayLike, ArrayLike] | None = None,
            spin_offset_fraction: float = SPIN_OFFSET_FRACTION) -> FastsimResult:
    """Kalker's FASTSIM on an n_x x n_y grid, batched over any broadcast shape of patches.

    Parameters
    ----------
    xi, eta : longitudinal and lateral creepage [-]
    phi_per_mm : spin creepage [1/mm]
    a_mm, b_mm : semi-axes, a in the rolling direction [mm]
    normal_force_n : normal force [N]
    mu : coefficient of friction [-]
    shear_modulus_mpa, poisson : G [MPa] and nu of both bodies
    n_x, n_y : elements along x and y over the ellipse's bounding box (CONTACT's 40 x 40)
    bound : "parabolic" (default) or "elliptic" traction bound
    combined_flexibility : CONTACT's combined-flexibility rule (default, reproduces CONTACT);
        False gives textbook FASTSIM
    flexibilities_mm_per_mpa : optional (L1, L2, L3) [mm/MPa] overriding both rules
    spin_offset_fraction : x-offset of the spin term [dx], CONTACT's 1/6 by default

    Returns
    -------
    FastsimResult (forces, traction, slip and adhesion fields).

    Kalker 1982; discretisation as CONTACT (module docstring).  ``fastsim_forces`` gives the
    totals alone, faster (no traction fields are stored).
    """
    result = _fastsim(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, mu, shear_modulus_mpa,
                      poisson, n_x, n_y, bound, combined_flexibility, flexibilities_mm_per_mpa,
                      spin_offset_fraction, fields=True)
    assert isinstance(result, FastsimResult)
    return result


@dataclass(frozen=True)
class FastsimForces:
    """FASTSIM totals for a batch of patches (shape S of the inputs): ``fx_n``, ``fy_n`` [N]
    and ``mz_nmm`` [N mm], as ``FastsimResult``."""

    fx_n: NDArray[np.float64]
    fy_n: NDArray[np.float64]
    mz_nmm: NDArray[np.float64]


def fastsim_forces(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
                   b_mm: ArrayLike, normal_force_n: ArrayLike, mu: ArrayLike,
                   shear_modulus_mpa: float = 82_000.0, poisson: float = 0.28,
                   n_x: int = 40, n_y: int = 40, bound: Bound = "parabolic",
                   combined_flexibility: bool = True,
                   flexibilities_mm_per_mpa: tuple[ArrayLike, ArrayLike, ArrayLike] | None = None,
                   spin_offset_fraction: float = SPIN_OFFSET_FRACTION) -> FastsimForces:
    """The totals of ``fastsim`` (same arguments, same numbers) without the traction fields:
    the compiled march (``fastsim_kernel``) then only sums, which is the fast path for
    tables and curving (``benchmarks/bench_fastsim.py``)."""
    result = _fastsim(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, mu, shear_modulus_mpa,
                      poisson, n_x, n_y, bound, combined_flexibility, flexibilities_mm_per_mpa,
                      spin_offset_fraction, fields=False)
    assert isinstance(result, FastsimForces)
    return result


def _fastsim(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
             b_mm: ArrayLike, normal_force_n: ArrayLike, mu: ArrayLike,
             shear_modulus_mpa: float, poisson: float, n_x: int, n_y: int, bound: Bound,
             combined_flexibility: bool,
             flexibilities_mm_per_mpa: tuple[ArrayLike, ArrayLike, ArrayLike] | None,
             spin_offset_fraction: float, fields: bool) -> FastsimResult | FastsimForces:
    if bound not in ("parabolic", "elliptic"):
        raise ValueError(f"bound must be 'parabolic' or 'elliptic', got {bound!r}")
    if n_x < 1 or n_y < 1:
        raise ValueError("n_x and n_y must be >= 1")
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                   (xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, mu)))
    shape = arrays[0].shape
    xi, eta, phi, a, b, fn, mu = (v.reshape(-1) for v in arrays)
    if np.any(a <= 0) or np.any(b <= 0):
        raise ValueError("semi-axes a_mm and b_mm must be positive")
    if np.any(fn < 0) or np.any(mu < 0):
        raise ValueError("normal_force_n and mu must be >= 0")
    if flexibilities_mm_per_mpa is not None:
        l1, l2, l3 = (np.broadcast_to(np.asarray(v, dtype=float).reshape(-1) if np.ndim(v)
                                      else np.asarray(v, dtype=float), xi.shape)
                      for v in flexibilities_mm_per_mpa)
    elif combined_flexibility:
        l1, l2, l3, _ = contact_combined_flexibilities(xi, eta, phi, a, b, fn, mu,
                                                       shear_modulus_mpa, poisson)
    else:
        l1, l2, l3 = fastsim_flexibilities(a, b, shear_modulus_mpa, poisson)

    dx = 2.0 * a / n_x
    dy = 2.0 * b / n_y
    u = (np.arange(n_x) + 0.5) / n_x * 2.0 - 1.0  # x/a of element centres
    v = (np.arange(n_y) + 0.5) / n_y * 2.0 - 1.0  # y/b
    x = a[:, None] * u[None, :]  # (n, n_x)
    y = b[:, None] * v[None, :]  # (n, n_y)
    rho2 = v[:, None] ** 2 + u[None, :] ** 2  # (n_y, n_x), shape-independent
    inside = rho2 < 1.0
    if bound == "parabolic":
        shape_fn = np.where(inside, 1.0 - rho2, 0.0)
        peak = 2.0 * fn / (np.pi * a * b)
    else:
        shape_fn = np.sqrt(np.where(inside, 1.0 - rho2, 0.0))
        peak = 1.5 * fn / (np.pi * a * b)
    # Per-element traction increments in adhesion (constant along x for px).
    dpx = -dx[:, None] * (xi[:, None] / l1[:, None] - phi[:, None] * y / l3[:, None])  # (n,n_y)
    x_spin = x + spin_offset_fraction * dx[:, None]
    dpy = -dx[:, None] * (eta[:, None] / l2[:, None] + phi[:, None] * x_spin / l3[:, None])
    da = dx * dy
    if not fields and fastsim_kernel.march_totals is not None:
        sum_p, sum_q, sum_m = fastsim_kernel.march_totals(dpx, np.ascontiguousarray(dpy),
                                                          shape_fn, mu * peak, x, y)
        return FastsimForces((da * sum_p).reshape(shape), (da * sum_q).reshape(shape),
                             (da * sum_m).reshape(shape))
    # numpy march (reference implementation), layout (n_x, n, n_y)
    g_t = (mu * peak)[None, :, None] * np.ascontiguousarray(shape_fn.T)[:, None, :]
    p_t, q_t, s_t = _march(dpx, np.ascontiguousarray(dpy.T), g_t)
    fx = da * p_t.sum(axis=(0, 2))
    fy = da * q_t.sum(axis=(0, 2))
    mz = da * (np.einsum("ikj,ki->k", q_t, x) - np.einsum("ikj,kj->k", p_t, y))
    if not fields:
        return FastsimForces(fx.reshape(shape), fy.reshape(shape), mz.reshape(shape))
    big_p, big_q, scale = (np.moveaxis(v, 0, -1) for v in (p_t, q_t, s_t))  # (n, n_y, n_x)

    def tot(val):
        return val.reshape(shape)

    def fld(val):
        return val.reshape(shape + val.shape[1:])

    def grid(val):  # (n, n_y, n_x) -> S + (n_y, n_x)
        return fld(val)

    return FastsimResult(
        fx_n=tot(fx), fy_n=tot(fy), mz_nmm=tot(mz),
        px_mpa=grid(big_p), py_mpa=grid(big_q), bound_scale=grid(scale),
        pn_peak_mpa=tot(peak), pn_shape=shape_fn, mu=tot(mu),
        x_mm=fld(x), y_mm=fld(y), dx_mm=tot(dx), dy_mm=tot(dy),
        flexibility_mm_per_mpa=fld(np.stack([l1, l2, l3], axis=-1)),
    )
