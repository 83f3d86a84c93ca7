"""Data-driven calibration of wear-law coefficients (seed 000), exact and heuristic.

Seed 000 fits the Jendel wear coefficients k1, k2, k3 (zones by sliding speed) so that the
simulated wear at one mileage matches the measured wear in the least-squares sense (its eq. 16
RMSE), with four metaheuristics (GA, PSO, tabu search, simulated annealing) that each call the
whole wear simulation many times (PSO 212 s, GA 2117 s in its Table 2), then predicts the wear at
a later mileage with the fitted k.

The structure they ignore: within a step of the wear loop, the zone of each contact depends only
on its sliding speed and pressure, never on k, so the worn depth of the step is LINEAR in the
zone coefficients (``physics.wear_loop`` returns each step's depth per unit coefficient,
``WearSimulation.step_basis_mm``). Only the profile feedback (the next step's contact sees the
worn profile) and the second-order terms of the normal update make the whole simulation
nonlinear in k. Hence the exact method:

1. run the loop at the current k_j; B_j = sum of the steps' bases at the measured positions,
   r_j = W(k_j) - B_j k_j the nonlinear remainder;
2. solve the bounded linear least squares min ||B_j k + r_j - w_measured|| over the box
   (``scipy.optimize.lsq_linear``);
3. repeat until k stops changing (a fixed point is an exact least-squares solution of the full
   simulation up to the remainder's dependence on k; typically 2-3 loop runs).

Two savings that leave the result unchanged: the first linearisation uses a loop run without
profile feedback (one contact solve, on the initial profile; the start of a fixed-point
iteration is free, and the full runs that follow decide where it converges), and the runs of one
fit share a contact cache that reuses a contact solution only for a bit-identical profile (the
initial one), so every full run, the reported one included, equals a fresh uncached run.

The metaheuristics solve the SAME inner problem (the same model evaluations, the same outer
loop), so their differences are the optimisers' alone; :func:`calibrate_full_loop` runs them
the seed's way instead, one whole loop run per objective evaluation, to time that set-up too.
The metaheuristics are :mod:`wearcast.statistics.coefficient_search`. Every method's reported
RMSE is that of a full loop run at its final k, against the measurements (seed 000 eq. 16).

Coefficients whose zone never occurs in the simulation are not identifiable; they keep their
starting value and are reported as such.

The same method fits the one coefficient of the tau_max law (seed 001's hypothesis,
``physics.wear_laws.tau_max_rate``: rate = c_tau (tau_max - tau_0)_+ A [mm^3/m]) with the
threshold tau_0 given: the loop's basis for a single-coefficient law is the depth at the law's
own coefficient (its coefficient vector is [1]), so the depth per unit c_tau is that basis
divided by the c_tau it ran with; the inner problem has one column (bounded least squares in
closed form, which ``lsq_linear`` returns). The metaheuristics solve the same one-column problem.
Krause-Poll and USFD have no coefficient in ``WearLaw`` to scale, so they are not fitted here.

Twin measurements with known coefficients are :mod:`wearcast.statistics.coefficient_fit_twin`;
the comparison of the methods (seed 000 Table 2) is
:mod:`wearcast.statistics.coefficient_fit_comparison`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import lsq_linear

from wearcast.physics.vehicles import BogieVehicle
from wearcast.physics.wear_distribution import Smoothing
from wearcast.physics.wear_laws import (
    TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA,
    ArchardKTH,
    WearLaw,
)
from wearcast.physics.wear_loop import WearSteps, simulate_wear
from wearcast.physics.wear_simulation import WearSimulation
from wearcast.statistics.coefficient_search import FULL_LOOP_BUDGETS, SEARCHES, objective

#: Seed 000 §V: bounds of k1, k2, k3 used by its optimisers (zone 4 not fitted) [-].
SEED_000_BOUNDS = ((1e-4, 10e-4), (30e-4, 40e-4), (1e-4, 10e-4))
#: Seed 000 §VI "traditional" method: the means of the ranges [-].
SEED_000_MEAN_K = (5e-4, 35e-4, 5e-4, 350e-4)
#: Fitting methods: exact bounded least squares and the searches of seed 000 (GA, PSO, TS, SA,
#: DE; ``coefficient_search.SEARCHES``).
FitMethod = Literal["exact", "GA", "PSO", "TS", "SA", "DE"]
METHODS: tuple[FitMethod, ...] = get_args(FitMethod)
#: Laws whose coefficients :func:`calibrate` fits.
FitLaw = Literal["archard_kth", "tau_max"]
FIT_LAWS: tuple[FitLaw, ...] = get_args(FitLaw)
#: Default search box of the tau_max coefficient c_tau [mm/(m MPa)]: two decades either side of
#: the placeholder 1e-6 of ``WearLaw`` (no paper publishes c_tau; seed 001 only ranks tau_max).
TAU_MAX_BOUNDS = ((1e-8, 1e-4),)
#: Default start of c_tau [mm/(m MPa)]: ``WearLaw``'s placeholder.
TAU_MAX_START = (TAU_COEFFICIENT_PLACEHOLDER_MM_PER_M_MPA,)
#: Names of each law's coefficient vector (table columns, service results).
COEFFICIENT_NAMES = {"archard_kth": ("k1", "k2", "k3", "k4"),
                     "tau_max": ("c_tau_mm_per_m_mpa",)}
_DEFAULTS = {"archard_kth": ((0, 1, 2), SEED_000_BOUNDS, SEED_000_MEAN_K),
             "tau_max": ((0,), TAU_MAX_BOUNDS, TAU_MAX_START)}


def fit_law(law: str, coefficients: ArrayLike, tau_threshold_mpa: float = 0.0) -> WearLaw:
    """The ``WearLaw`` of a coefficient vector: KTH zones k1..k4 [-] for ``archard_kth``, (c_tau,)
    [mm/(m MPa)] with threshold tau_0 [MPa] for ``tau_max``."""
    k = np.asarray(coefficients, dtype=float).ravel()
    if law == "archard_kth":
        return WearLaw("archard_kth", ArchardKTH().with_coefficients(k))
    if law == "tau_max":
        if k.size != 1:
            raise ValueError("tau_max has one coefficient (c_tau)")
        return WearLaw("tau_max", tau_coefficient_mm_per_m_mpa=float(k[0]),
                       tau_threshold_mpa=float(tau_threshold_mpa))
    raise ValueError(f"law: cannot fit {law!r}; fitted laws: {', '.join(FIT_LAWS)}")


@dataclass(frozen=True)
class CalibrationProblem:
    """Measured wear of one wheel at one mileage and the model to fit to it.

    vehicle, classes : as ``simulate_wear``
    y_mm, wear_mm : measured vertical wear w(y) [mm] at ``mileage_km``
    mileage_km : mileage of the measurement [km]
    step_km : fixed step of the loop [km] (seed 000: 5,000 km; the last step is shortened)
    free : indices of the fitted coefficients (Archard/KTH: 0-based zones, seed 000 fits 0, 1, 2;
        tau_max: (0,), c_tau); () (default): the law's default
    bounds : (lower, upper) per free coefficient, 0 < lower < upper; (): the law's default
        (seed 000's ranges; c_tau in ``TAU_MAX_BOUNDS`` [mm/(m MPa)])
    start : full coefficient vector used as start and for the coefficients not fitted ((4,) k
        for Archard/KTH, (c_tau,) for tau_max); (): seed 000's map means, or c_tau = 1e-6
    application, smoothing, axle, side, contact_update_depth_mm : loop options
    law : ``archard_kth`` (default) or ``tau_max`` (``FIT_LAWS``)
    tau_threshold_mpa : tau_0 of the tau_max law [MPa], fixed (not fitted)
    """

    vehicle: BogieVehicle | str
    classes: Any
    y_mm: NDArray
    wear_mm: NDArray
    mileage_km: float
    step_km: float = 5000.0
    free: tuple[int, ...] = ()
    bounds: tuple[tuple[float, float], ...] = ()
    start: tuple[float, ...] = ()
    application: str = "global"
    smoothing: Smoothing = field(default_factory=Smoothing)
    axle: int = 1
    side: str = "right"
    contact_update_depth_mm: float = 0.0
    law: str = "archard_kth"
    tau_threshold_mpa: float = 0.0

    def __post_init__(self) -> None:
        if self.law not in FIT_LAWS:
            raise ValueError(f"law: cannot fit {self.law!r}; fitted laws: {', '.join(FIT_LAWS)}")
        free, bounds, start = _DEFAULTS[self.law]
        for name, default in (("free", free), ("bounds", bounds), ("start", start)):
            if len(getattr(self, name)) == 0:  # () means the law's default
                object.__setattr__(self, name, tuple(default))
        n = self.n_coefficients
        if len(self.free) != len(self.bounds):
            raise ValueError("free and bounds must have the same length")
        if len(set(self.free)) != len(self.free):
            raise ValueError("free must name each coefficient once")
        if any(not 0 <= i < n for i in self.free):
            raise ValueError(f"free coefficient indices must be in 0..{n - 1} for {self.law}")
        if any(not 0 < lo < hi for lo, hi in self.bounds):
            raise ValueError("each bound must satisfy 0 < lower < upper")
        if len(self.start) != n or any(not v >= 0 for v in self.start):
            raise ValueError(f"start must hold {n} non-negative coefficients for {self.law}")
        if not self.tau_threshold_mpa >= 0:
            raise ValueError("tau_threshold_mpa must be >= 0")
        if self.law != "tau_max" and self.tau_threshold_mpa != 0:
            raise ValueError("tau_threshold_mpa applies to the tau_max law only")
        if self.law != "archard_kth" and self.application != "global":
            raise ValueError("the local application is defined for Archard/KTH only (seed 002)")
        if np.shape(self.y_mm) != np.shape(self.wear_mm) or np.ndim(self.y_mm) != 1:
            raise ValueError("y_mm and wear_mm must be 1-D arrays of the same length")
        if not self.mileage_km > 0 or not self.step_km > 0:
            raise ValueError("mileage_km and step_km must be positive")

    @property
    def n_coefficients(self) -> int:
        """Length of the law's coefficient vector (4 KTH zones, or 1 for tau_max)."""
        return len(COEFFICIENT_NAMES[self.law])

    @property
    def coefficient_names(self) -> tuple[str, ...]:
        """Names of the coefficient vector's entries (``k1``..``k4`` or ``c_tau_mm_per_m_mpa``)."""
        return COEFFICIENT_NAMES[self.law]

    def coefficients(self, free_values: ArrayLike) -> NDArray[np.float64]:
        """Full coefficient vector ((4,) or (1,)) with the free ones replaced."""
        k = np.asarray(self.start, dtype=float).copy()
        k[list(self.free)] = np.asarray(free_values, dtype=float)
        return k

    def wear_law(self, coefficients: ArrayLike) -> WearLaw:
        """The loop's ``WearLaw`` at a full coefficient vector."""
        return fit_law(self.law, coefficients, self.tau_threshold_mpa)


def run_model(problem: CalibrationProblem, coefficients: ArrayLike,
              mileage_km: float | None = None, *, feedback: bool = True,
              contact_cache: dict | None = None) -> WearSimulation:
    """The wear loop with fixed steps up to ``mileage_km`` (default the measurement's).

    feedback : False runs the loop without profile feedback (the contact of the initial
        profile for every step: one contact solve), the cheap predictor of :func:`calibrate`
    contact_cache : shared by runs on the same problem (``simulate_wear``; exact reuse of
        contact solutions on bit-identical profiles)
    """
    target = problem.mileage_km if mileage_km is None else mileage_km
    n = max(1, int(np.ceil(target / problem.step_km - 1e-9)))
    law = problem.wear_law(coefficients)
    steps = WearSteps(mode="fixed", n_steps=n, step_km=target / n,
                      contact_update_depth_mm=problem.contact_update_depth_mm if feedback
                      else float("inf"))
    return simulate_wear(problem.vehicle, problem.classes, law=law,
                         application=problem.application, steps=steps, axle=problem.axle,
                         side=problem.side, smoothing=problem.smoothing,
                         contact_cache=contact_cache)


def _at(sim: WearSimulation, values: NDArray, y_mm: NDArray) -> NDArray:
    return np.stack([np.interp(y_mm, sim.y_mm, v) for v in np.atleast_2d(values)])


def _depth_per_coefficient(problem: CalibrationProblem, sim: WearSimulation,
                           coefficients: NDArray, y_mm: NDArray) -> NDArray[np.float64]:
    """Linearised depth at the measured positions per unit coefficient [mm per unit], shape
    (n_coefficients, n_meas): the loop's summed step basis, which for a single-coefficient law
    is per unit multiplier of the law AS RUN, i.e. divided by its coefficient (c_tau > 0)."""
    basis = _at(sim, sim.step_basis_mm.sum(axis=0), y_mm)
    if problem.law == "archard_kth":
        return basis
    return basis / coefficients[0]


def rmse_mm(model_mm: ArrayLike, measured_mm: ArrayLike) -> float:
    """Seed 000 eq. (16): sqrt(mean((measured - simulated)^2)) [mm]."""
    d = np.asarray(measured_mm, dtype=float) - np.asarray(model_mm, dtype=float)
    return float(np.sqrt(np.mean(d * d)))


@dataclass(frozen=True)
class FitResult:
    """Outcome of one calibration method.

    method, coefficients (full vector: (4,) KTH zones or (1,) c_tau), rmse_mm (full loop at the
    final k vs the measurement), max_depth_mm (model), re_max_depth_pct (relative error of the
    maximum depth vs measured), time_s, model_runs (loop runs), evaluations (inner objective
    calls), identifiable (bool per free coefficient), simulation (the final loop run)
    """

    method: str
    coefficients: NDArray
    rmse_mm: float
    max_depth_mm: float
    re_max_depth_pct: float
    time_s: float
    model_runs: int
    evaluations: int
    identifiable: NDArray
    simulation: WearSimulation


InnerSolver = Callable[[NDArray, NDArray, NDArray, NDArray, NDArray, np.random.Generator],
                       tuple[NDArray, int]]


def _solve_exact(a, rhs, lo, hi, x0, rng):
    res = lsq_linear(a, rhs, bounds=(lo, hi), method="bvls")
    return res.x, 1


def _on_frozen_basis(search: Callable[..., tuple[NDArray, int]]) -> InnerSolver:
    """A metaheuristic as an inner solver: it minimises the frozen-basis objective."""
    def solve(a, rhs, lo, hi, x0, rng):
        return search(objective(a, rhs), lo, hi, x0, rng)
    return solve


_SOLVERS: dict[str, InnerSolver] = {"exact": _solve_exact, **{
    name: _on_frozen_basis(search) for name, search in SEARCHES.items()}}


def _free_box(problem: CalibrationProblem) -> tuple[list[int], NDArray, NDArray, NDArray]:
    """Free coefficient indices, their bounds and the start clipped into them."""
    free = list(problem.free)
    lo = np.array([b[0] for b in problem.bounds])
    hi = np.array([b[1] for b in problem.bounds])
    return free, lo, hi, np.clip(np.asarray(problem.start, dtype=float)[free], lo, hi)


def _fit_result(method: str, problem: CalibrationProblem, x: NDArray, sim: WearSimulation,
                t0: float, runs: int, evals: int, identifiable: NDArray) -> FitResult:
    """FitResult of the final loop run ``sim`` at the free values ``x`` (seed 000 eq. 16)."""
    w_meas = np.asarray(problem.wear_mm, dtype=float)
    model = _at(sim, sim.wear_mm[-1], np.asarray(problem.y_mm, dtype=float))[0]
    measured_max = float(np.max(w_meas))
    model_max = float(np.max(model))
    return FitResult(method=method, coefficients=problem.coefficients(x),
                     rmse_mm=rmse_mm(model, w_meas), max_depth_mm=model_max,
                     re_max_depth_pct=100.0 * (model_max - measured_max) / measured_max,
                     time_s=time.perf_counter() - t0, model_runs=runs, evaluations=evals,
                     identifiable=identifiable, simulation=sim)


def calibrate(problem: CalibrationProblem, method: str = "exact", *, max_runs: int = 5,
              rtol: float = 1e-4, seed: int = 0, predictor: bool = True) -> FitResult:
    """Fit the free coefficients (KTH zones, or c_tau of tau_max) to the measured wear.

    Parameters
    ----------
    problem : CalibrationProblem
    method : ``exact`` (bounded linear least squares), ``GA``, ``PSO``, ``TS`` (tabu search),
        ``SA`` (dual annealing) or ``DE`` (differential evolution)
    max_runs : maximum loop runs of the outer (profile-feedback) iteration
    rtol : stop when no free coefficient changes by more than rtol (relative)
    seed : random seed of the metaheuristics
    predictor : linearise the first iteration on a loop run WITHOUT profile feedback (one
        contact solve, on the initial profile) instead of a full run at the start values; the
        full runs that follow converge to the same fixed point (the start of a fixed-point
        iteration is free), and the initial profile's contact is reused exactly by them.
        Counted in ``model_runs``.

    Returns
    -------
    FitResult (its RMSE from a full loop run at the final coefficients)
    """
    if method not in _SOLVERS:
        raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    solver = _SOLVERS[method]
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    free, lo, hi, x = _free_box(problem)
    y_meas = np.asarray(problem.y_mm, dtype=float)
    w_meas = np.asarray(problem.wear_mm, dtype=float)
    runs = evals = 0
    identifiable = np.ones(len(free), dtype=bool)
    # One cache per fit: the contacts of bit-identical profiles (the initial one in every run)
    # are solved once; everything else is recomputed, so each run equals a fresh run.
    cache: dict = {}
    sim = run_model(problem, problem.coefficients(x), feedback=not predictor,
                    contact_cache=cache)
    runs += 1
    for _ in range(max_runs - 1):
        k_full = problem.coefficients(x)
        basis = _depth_per_coefficient(problem, sim, k_full, y_meas)      # (n_coef, n_meas)
        model = _at(sim, sim.wear_mm[-1], y_meas)[0]
        remainder = model - basis.T @ k_full
        fixed = [i for i in range(problem.n_coefficients) if i not in free]
        rhs = w_meas - remainder - basis[fixed].T @ k_full[fixed]
        a = basis[free].T
        identifiable = np.linalg.norm(a, axis=0) > 1e-12 * max(float(np.linalg.norm(a)), 1e-300)
        x_new = x.copy()
        if np.any(identifiable):
            sub, n_eval = solver(a[:, identifiable], rhs, lo[identifiable], hi[identifiable],
                                 x[identifiable], rng)
            x_new[identifiable] = sub
            evals += n_eval
        change = np.max(np.abs(x_new - x) / x)
        x = x_new
        sim = run_model(problem, problem.coefficients(x), contact_cache=cache)
        runs += 1
        if change <= rtol:
            break
    return _fit_result(method, problem, x, sim, t0, runs, evals, identifiable)


def calibrate_full_loop(problem: CalibrationProblem, method: str = "PSO", *, seed: int = 0,
                        budget: dict[str, int] | None = None) -> FitResult:
    """Seed 000's own set-up: a metaheuristic whose EVERY objective evaluation is a whole loop
    run (profile feedback included) at the candidate coefficients, scored by the squared error
    against the measured wear (seed 000 eqs. 3 and 16). No linearisation, no outer iteration.

    method : ``GA``, ``PSO``, ``TS``, ``SA`` or ``DE``; budget : the search's size keywords
    (default :data:`FULL_LOOP_BUDGETS`). ``model_runs`` = ``evaluations`` + the final run.
    The runs share one contact cache (bit-identical profiles only: the initial one), so each
    evaluation equals a fresh run.
    """
    if method not in SEARCHES:
        raise ValueError(f"unknown full-loop method {method!r}; known: {', '.join(SEARCHES)}")
    search = SEARCHES[method]
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    free, lo, hi, x0 = _free_box(problem)
    y_meas = np.asarray(problem.y_mm, dtype=float)
    w_meas = np.asarray(problem.wear_mm, dtype=float)
    cache: dict = {}
    runs = 0

    def objective(x: NDArray) -> float:
        nonlocal runs
        runs += 1
        sim = run_model(problem, problem.coefficients(x), contact_cache=cache)
        r = _at(sim, sim.wear_mm[-1], y_meas)[0] - w_meas
        return float(r @ r)

    x, evals = search(objective, lo, hi, x0, rng, **(budget or FULL_LOOP_BUDGETS[method]))
    sim = run_model(problem, problem.coefficients(x), contact_cache=cache)
    runs += 1
    return _fit_result(f"{method} (full loop)", problem, x, sim, t0, runs, evals,
                       np.ones(len(free), dtype=bool))
