"""How detectable is a seasonal friction effect at all? An oracle that knows the injected effect.

Run: .venv/bin/python benchmarks/seasonal_oracle.py [--generator loop|twin] [--amplitude A]
         [--seeds N] [--first-seed S] [--loop-cache FILE]

For each seed the generator makes the same fleet twice, with and without the effect (the same
random draws: the effects are deterministic functions of the wear history), so the difference
of the finder's log residuals, t = e_effect - e_null (``FinderData.e``, log of (area + floor)),
is exactly what the effect did to every (measurement, region) row. The oracle regresses the
effect data's log residual on t: one slope, known form, known amplitude and phase -- the most
a test can know. Every wheel's rows are centred (each wheel's own rate scale removed, as the
random-effects fit does), rows weighted by the finder's robustness and precision weights
(``FinderData.set_robust_weights``), and the slope's standard error is clustered by wheel
(Liang and Zeger 1986). Prints per seed the slope (1 = the injected effect), its t and the
finder's own seasonal feature fit's share of the truth (R^2 of t on the calendar features,
mileage-weighted and wear-weighted, ``causes_calendar``); then the share of seeds whose
oracle t exceeds 1.645 (one-sided 5 %, a single test) and 2.5 (about the max-T critical value
over the catalogue at the finder's alpha 0.04). The form oracle knows the form but not the
amplitude and phase, as the finder: the Wald test (2 df, wheel-clustered) of the finder's own
wear-weighted (cos, sin) features within the wheels, at 5 % and at 0.04 / 9 (Bonferroni over
the nine causes, a bound on the finder's max-T level). It is a reference, not a bound on the
finder: its wheel fixed effects also remove the part of the season that differs between
wheels (the finder's random-effects fit keeps some of it; loop seed 110 is named by the
finder at form-oracle p 0.10).

A cell the oracle cannot separate from the null in >= 95 % of seeds at 5 % is not detectable
at that strength with that data by any test; the finder, which must also estimate the form
and beat eight other causes, cannot do better.
"""

from __future__ import annotations

import argparse
import os
import pickle
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import detection_rates as dr  # noqa: E402

from wearcast.statistics import causes as cz  # noqa: E402
from wearcast.statistics.discrepancy_data import build_data  # noqa: E402
from wearcast.statistics.generators import scenarios as sc  # noqa: E402
from wearcast.statistics.generators import twin_effects as te  # noqa: E402
from wearcast.statistics.wear_tables import compile_wear_table  # noqa: E402


def finder_data(generator: str, effects: tuple[Any, ...], seed: int) -> cz.FinderData:
    if generator == "loop":
        df, curves, routes, attrs, table, (model, cal) = dr.loop_case((effects, ()), seed)
        return build_data(model, df, curves, routes, compile_wear_table(table),
                          calibration_wheel_ids=set(df["wheel_id"][cal]),
                          route_attributes=attrs, expected_progression=dr.loop_progression())
    s = sc.twin_scenario(effects, (), seed=seed, table=dr.TABLE)
    args, kwargs = s.finder_arguments()
    return build_data(args[0], args[1], args[2], args[3], compile_wear_table(args[4]),
                      calibration_wheel_ids=kwargs["calibration_wheel_ids"],
                      route_attributes=kwargs["route_attributes"])


def _centred(values: np.ndarray, weights: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """Each wheel's weighted mean removed, per region."""
    g = int(codes.max()) + 1
    out = np.array(values, dtype=float)
    for j in range(values.shape[1]):
        num = np.bincount(codes, weights=weights[:, j] * values[:, j], minlength=g)
        den = np.bincount(codes, weights=weights[:, j], minlength=g)
        out[:, j] -= (num / np.where(den > 0, den, 1.0))[codes]
    return out


def oracle(generator: str, amplitude: float, seed: int) -> dict[str, float]:
    with_effect = finder_data(generator, (te.seasonal_friction(amplitude),), seed)
    without = finder_data(generator, (), seed)
    truth = with_effect.e - without.e
    everything = np.ones(with_effect.n, dtype=bool)
    null = cz.NullArea().fit(with_effect, everything)
    residual = with_effect.e - with_effect.phi * null.log_scale_[None, :]
    with_effect.set_robust_weights(residual)
    w = with_effect.weights
    wheel = with_effect.frame["wheel_id"].astype(str).to_numpy()
    codes = np.unique(wheel, return_inverse=True)[1]
    x = _centred(truth, w, codes)
    y = _centred(residual, w, codes)
    sxx = float(np.sum(w * x * x))
    slope = float(np.sum(w * x * y)) / sxx
    score = np.bincount(codes, weights=np.sum(w * x * (y - slope * x), axis=1))
    se = float(np.sqrt(np.sum(score ** 2))) / sxx
    out = {"slope": slope, "t": slope / se}
    mileage_x = with_effect.season()
    area_x = with_effect.season_by_region()
    if area_x is not None:
        # the form oracle: the finder's own wear-weighted (cos, sin) features, amplitude and
        # phase unknown (2 df), within the wheels, Wald test with wheel-clustered covariance
        f = np.stack([_centred(area_x[:, :, k], w, codes) for k in range(2)], axis=2)
        xtx = np.einsum("nr,nrk,nrl->kl", w, f, f)
        beta = np.linalg.solve(xtx, np.einsum("nr,nrk,nr->k", w, f, y))
        u = np.einsum("nr,nrk,nr->nk", w, f, y - np.einsum("nrk,k->nr", f, beta))
        scores = np.stack([np.bincount(codes, weights=u[:, k]) for k in range(2)], axis=1)
        inv = np.linalg.inv(xtx)
        cov = inv @ (scores.T @ scores) @ inv
        out["wald"] = float(beta @ np.linalg.solve(cov, beta))
        out["p_form"] = float(np.exp(-out["wald"] / 2.0))     # chi^2, 2 df
    for j, region in enumerate(("flange", "tread")):
        for name, feats in (("mileage", mileage_x), ("wear", None if area_x is None
                                                     else area_x[:, j, :])):
            if feats is None:
                continue
            design = np.column_stack([np.ones(with_effect.n), feats])
            beta, *_ = np.linalg.lstsq(design, truth[:, j], rcond=None)
            out[f"r2_{name}_{region}"] = float(
                1.0 - np.var(truth[:, j] - design @ beta) / max(np.var(truth[:, j]), 1e-300))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--generator", default="loop", choices=("loop", "twin"))
    ap.add_argument("--amplitude", type=float, default=0.1)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--loop-cache", default="")
    args = ap.parse_args()
    if args.loop_cache and os.path.exists(args.loop_cache):
        with open(args.loop_cache, "rb") as fh:
            dr._LOOP_CACHE.update(pickle.load(fh))
    rows = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        n_loop = len(dr._LOOP_CACHE)
        r = oracle(args.generator, args.amplitude, seed)
        if args.loop_cache and len(dr._LOOP_CACHE) > n_loop:
            with open(args.loop_cache, "wb") as fh:
                pickle.dump(dr._LOOP_CACHE, fh)
        rows.append(r)
        r2 = " ".join(f"{k[3:]}={v:.2f}" for k, v in r.items() if k.startswith("r2_"))
        print(f"{args.generator} seasonal {args.amplitude} seed {seed}: oracle slope "
              f"{r['slope']:.2f}, t {r['t']:.2f}; form oracle p {r.get('p_form', np.nan):.4f}; "
              f"R^2 of the truth on the features: {r2}", flush=True)
    t = np.array([r["t"] for r in rows])
    p_form = np.array([r.get("p_form", np.nan) for r in rows])
    print(f"{args.generator} seasonal {args.amplitude}: oracle t median {np.median(t):.2f} "
          f"(range {t.min():.2f}-{t.max():.2f}); t > 1.645 (one-sided 5 %) in "
          f"{int(np.sum(t > 1.645))}/{t.size}, t > 2.5 in {int(np.sum(t > 2.5))}/{t.size}; "
          f"form oracle (2 df) p < 0.05 in {int(np.sum(p_form < 0.05))}/{t.size}, "
          f"p < 0.04/9 (Bonferroni over the catalogue) in "
          f"{int(np.sum(p_form < 0.04 / 9))}/{t.size}")


if __name__ == "__main__":
    main()
