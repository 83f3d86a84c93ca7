"""Figures (matplotlib SVG strings) and a self-contained HTML report of a discrepancy-finder
diagnosis (:func:`wearcast.statistics.discrepancy.diagnose`). Pure: no I/O."""

from __future__ import annotations

import html
import io
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.discrepancy import Diagnosis


def _svg(fig: Any) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return buf.getvalue()


def diagnosis_figures(diagnosis: Diagnosis, cause: str | None = None) -> dict[str, str]:
    """SVG figures: residuals against the named covariate; predicted vs measured areas.

    ``cause`` defaults to the verdict (or the top finding when the verdict is 'none').
    Returns {'residuals': svg, 'predicted_vs_measured': svg}.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    code = cause or (diagnosis.verdict if diagnosis.verdict != "none" else
                     (diagnosis.findings[0].cause if diagnosis.findings else "none"))
    frame = diagnosis.residuals
    out: dict[str, str] = {}
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5), sharey=True)
    cov = diagnosis.covariates.get(code)
    x = np.asarray(cov if cov is not None else frame["mileage_km"].tolist(), dtype=object)
    numeric = pd.to_numeric(pd.Series(x), errors="coerce")
    for ax, region in zip(axes, REGIONS, strict=True):
        y = frame[f"logres_{region}"].to_numpy()
        if numeric.notna().all() and numeric.nunique() > 6:
            ax.plot(numeric.to_numpy(), y, ".", alpha=0.5)
        else:
            levels = sorted({str(v) for v in x})
            for i, lev in enumerate(levels):
                sel = np.array([str(v) == lev for v in x])
                ax.plot(np.full(sel.sum(), i) + np.linspace(-0.2, 0.2, sel.sum()), y[sel], ".",
                        alpha=0.5)
            ax.set_xticks(range(len(levels)), levels)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_title(f"{region}: log(measured / predicted)")
        ax.set_xlabel(code if cov is not None else "mileage_km")
    out["residuals"] = _svg(fig)
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    meas = np.asarray(diagnosis.predictions.get("measured", []), dtype=float)
    before = np.asarray(diagnosis.predictions.get("calibrated", []), dtype=float)
    after = np.asarray(diagnosis.predictions.get(code, diagnosis.predictions.get("none", [])),
                       dtype=float)
    for j, (ax, region) in enumerate(zip(axes, REGIONS, strict=True)):
        if meas.size:
            ax.plot(meas[:, j], before[:, j], ".", alpha=0.5, label="calibrated model")
            if after.size:
                ax.plot(meas[:, j], after[:, j], ".", alpha=0.5, label=f"extended ({code})")
            top = float(np.nanmax([meas[:, j].max(), before[:, j].max(), 1e-9]))
            ax.plot([0, top], [0, top], "k-", lw=0.8)
        ax.set_xlabel(f"measured {region} area [mm²]")
        ax.set_ylabel(f"predicted {region} area [mm²]")
        ax.legend(fontsize=7)
    out["predicted_vs_measured"] = _svg(fig)
    return out


def report_html(diagnosis: Diagnosis, figures_svg: Mapping[str, str]) -> str:
    """A self-contained HTML report: verdict, findings table, skipped causes, figures."""
    esc = html.escape
    rows = []
    for f in diagnosis.findings:
        g = f.gain
        rows.append(
            f"<tr><td>{esc(f.cause)}</td><td>{esc(f.summary)}</td>"
            f"<td>{g.before_error:.4g}</td><td>{g.after_error:.4g}</td>"
            f"<td>{100 * g.relative:.1f} % [{100 * g.ci95_low:.1f}, {100 * g.ci95_high:.1f}]</td>"
            f"<td>{f.evidence.get('p_value', float('nan')):.2g}</td>"
            f"<td>{'yes' if f.significant and f.material else 'no'}</td></tr>")
    skipped = "".join(f"<li><b>{esc(k)}</b>: {esc(v)}</li>"
                      for k, v in diagnosis.skipped.items())
    figs = "".join(f"<h3>{esc(name.replace('_', ' '))}</h3><div>{svg}</div>"
                   for name, svg in figures_svg.items())
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>wearcast diagnosis</title>"
        "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}"
        "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px}</style>"
        "</head><body><h1>wearcast diagnosis</h1>"
        f"<p>Verdict: <b>{esc(diagnosis.verdict)}</b> ({diagnosis.n_measurements} measurements, "
        f"{diagnosis.n_groups} groups by {esc(diagnosis.group_by)})</p>"
        + (f"<p>Runner-up: {esc(diagnosis.runner_up)}, margin "
           f"{100 * (diagnosis.margin or 0.0):.1f} % of the baseline's held-out error "
           f"(randomisation p = {diagnosis.margin_p_value:.3g})</p>"
           if diagnosis.runner_up is not None and diagnosis.margin_p_value is not None else "")
        + (f"<p>Candidates no tested margin separates: "
           f"{esc(', '.join(diagnosis.candidates))}</p>" if diagnosis.candidates else "")
        + "".join(f"<p>Residual structure outside the catalogue by {esc(u['by'])}: "
                  f"{100 * u['share_of_residual']:.1f} % of the residual "
                  f"(p = {u['p_value']:.3g})</p>" for u in diagnosis.unexplained)
        + "<table><tr><th>cause</th><th>summary</th><th>held-out error before</th>"
        "<th>after</th><th>relative gain [95 % CI]</th><th>p (max-T)</th><th>reported</th>"
        "</tr>"
        + "".join(rows) + "</table>"
        + (f"<h2>Skipped</h2><ul>{skipped}</ul>" if skipped else "")
        + f"<h2>Figures</h2>{figs}</body></html>")
