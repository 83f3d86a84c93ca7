"""The metaheuristics of seed 000's coefficient fit (GA, PSO, tabu search, simulated annealing)
and differential evolution, searching log10(k) within the box for the least-squares
objective of a wear-coefficient fit.

GA, PSO and tabu search are short hand-written versions; simulated annealing is
``scipy.optimize.dual_annealing`` and differential evolution
``scipy.optimize.differential_evolution``. :mod:`wearcast.statistics.coefficient_fit` runs
them on its frozen-basis inner problem or, the seed's way, on whole loop runs
(:data:`FULL_LOOP_BUDGETS`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import differential_evolution, dual_annealing


def objective(a, rhs):
    def f(x):
        r = a @ np.asarray(x) - rhs
        return float(r @ r)
    return f


Objective = Callable[[NDArray], float]


def _log_box(lo, hi):
    return np.log10(lo), np.log10(hi)


#: Seed 000 §IV.C prints its PSO: a swarm of 40, 30 iterations, learning factors
#: c1 = c2 = 2, inertia weight "between 0.5-1.2" (taken as falling linearly from 1.2 to 0.5).
SEED_000_PSO = {"n_particles": 40, "n_iter": 30, "c1": 2.0, "c2": 2.0,
                "inertia": (1.2, 0.5)}


def _search_pso(f: Objective, lo, hi, x0, rng, n_particles=40, n_iter=30, c1=2.0, c2=2.0,
                inertia=(1.2, 0.5)):
    """PSO in log10(k) with seed 000's settings by default (:data:`SEED_000_PSO`), seed 000
    eq. (6): v <- w v + c1 r1 (P_i - x) + c2 r2 (P_g - x), w falling linearly over the
    iterations from inertia[0] to inertia[1]."""
    llo, lhi = _log_box(lo, hi)
    pos = rng.uniform(llo, lhi, (n_particles, lo.size))
    vel = np.zeros_like(pos)
    val = np.array([f(10 ** p) for p in pos])
    best_p, best_v = pos.copy(), val.copy()
    g = best_p[np.argmin(best_v)]
    for it in range(n_iter):
        w = inertia[0] + (inertia[1] - inertia[0]) * it / max(n_iter - 1, 1)
        r1, r2 = rng.random(pos.shape), rng.random(pos.shape)
        vel = w * vel + c1 * r1 * (best_p - pos) + c2 * r2 * (g - pos)
        pos = np.clip(pos + vel, llo, lhi)
        val = np.array([f(10 ** p) for p in pos])
        better = val < best_v
        best_p[better], best_v[better] = pos[better], val[better]
        g = best_p[np.argmin(best_v)]
    return 10 ** g, n_particles * (n_iter + 1)


def _search_ga(f: Objective, lo, hi, x0, rng, n_pop=30, n_gen=60, mutation=0.1):
    llo, lhi = _log_box(lo, hi)
    pop = rng.uniform(llo, lhi, (n_pop, lo.size))
    fit = np.array([f(10 ** p) for p in pop])
    for _ in range(n_gen):
        elite = pop[np.argmin(fit)].copy()
        # Tournament selection of parents, blend crossover, Gaussian mutation, elitism.
        pairs = rng.integers(0, n_pop, (n_pop, 2, 2))
        parents = np.where(fit[pairs[..., 0]] < fit[pairs[..., 1]], pairs[..., 0],
                           pairs[..., 1])
        w = rng.random((n_pop, lo.size))
        child = w * pop[parents[:, 0]] + (1 - w) * pop[parents[:, 1]]
        child += rng.normal(0.0, mutation * (lhi - llo), child.shape) * (
            rng.random(child.shape) < 0.3)
        pop = np.clip(child, llo, lhi)
        pop[0] = elite
        fit = np.array([f(10 ** p) for p in pop])
    return 10 ** pop[np.argmin(fit)], n_pop * (n_gen + 1)


def _search_tabu(f: Objective, lo, hi, x0, rng, n_iter=200, n_neighbours=5, tabu_len=8,
                 radius=0.25, shrink=0.98):
    # Seed 000 §V.C: 5 neighbours, tabu length 5-11, 200 iterations; the seed shrinks the radius
    # by 0.2 % per update, too slow to reach 1 % in 200 iterations: we shrink by 2 %.
    llo, lhi = _log_box(lo, hi)
    cur = np.clip(np.log10(x0), llo, lhi)
    best, best_v = cur.copy(), f(10 ** cur)
    tabu: list[NDArray] = []
    evals = 1
    cell = 0.02 * (lhi - llo)
    for _ in range(n_iter):
        cand = np.clip(cur + rng.normal(0.0, radius * (lhi - llo), (n_neighbours, lo.size)),
                       llo, lhi)
        vals = np.array([f(10 ** c) for c in cand])
        evals += n_neighbours
        for j in np.argsort(vals):
            key = np.round(cand[j] / cell)
            if vals[j] < best_v or not any(np.array_equal(key, t) for t in tabu):
                cur = cand[j]
                tabu.append(key)
                tabu = tabu[-tabu_len:]
                if vals[j] < best_v:
                    best, best_v = cand[j].copy(), vals[j]
                break
        radius *= shrink
    return 10 ** best, evals


def _search_sa(f: Objective, lo, hi, x0, rng, maxiter=300, maxfun=10_000_000):
    llo, lhi = _log_box(lo, hi)
    res = dual_annealing(lambda p: f(10 ** p), list(zip(llo, lhi, strict=True)), maxiter=maxiter,
                         maxfun=maxfun, seed=int(rng.integers(2**31)),
                         x0=np.clip(np.log10(x0), llo, lhi))
    return 10 ** res.x, int(res.nfev)


def _search_de(f: Objective, lo, hi, x0, rng, maxiter=1000, popsize=15, polish=True):
    llo, lhi = _log_box(lo, hi)
    res = differential_evolution(lambda p: f(10 ** p), list(zip(llo, lhi, strict=True)),
                                 seed=int(rng.integers(2**31)), tol=1e-10, polish=polish,
                                 maxiter=maxiter, popsize=popsize)
    return 10 ** res.x, int(res.nfev)


SEARCHES: dict[str, Callable[..., tuple[NDArray, int]]] = {
    "GA": _search_ga, "PSO": _search_pso, "TS": _search_tabu, "SA": _search_sa, "DE": _search_de}


#: Budgets of the full-loop metaheuristics (every evaluation is a whole loop run, ~0.3 s on
#: the benchmark's twin): PSO as seed 000 printed it (swarm 40, 30 iterations: 1,240 runs);
#: the seed prints no sizes for the others, which are kept near 200 loop runs.
FULL_LOOP_BUDGETS: dict[str, dict[str, int]] = {
    "GA": {"n_pop": 12, "n_gen": 15}, "PSO": {"n_particles": 40, "n_iter": 30},
    "TS": {"n_iter": 40}, "SA": {"maxiter": 50, "maxfun": 200},
    "DE": {"maxiter": 4, "popsize": 10}}
