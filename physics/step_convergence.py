"""Step convergence of a wear simulation: halve the step until the end result stops moving.

The wear loop integrates the profile evolution in discrete steps (seed 003 eq. 2: D_step per
step); a result is only a result of the model if it does not depend on that step. The check
runs the simulation with a step h, h/2, h/4, ... and stops when every watched end quantity
(e.g. FT and qR at the last mileage) changes by less than ``tolerance`` between two successive
halvings, measured RELATIVE TO ITS LOSS from the initial value (the change of the end FT
divided by FT_new - FT_end): FT itself moves by a few percent at most in a run, so a change
relative to FT would pass any step. A quantity that did not move (|loss| below
``min_loss``) is compared in absolute terms against ``tolerance * min_loss``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

#: Issue 12: halve until FT/qR at the end change by < 2 %.
DEFAULT_TOLERANCE = 0.02


@dataclass(frozen=True)
class StepConvergence:
    """Outcome of :func:`converge_steps`.

    steps : the steps tried, largest first; end_values : per step {quantity: end value};
    changes : per halving {quantity: relative change of the loss} (one fewer than steps);
    converged : the last change is below ``tolerance`` for every quantity; tolerance.
    """

    steps: tuple[float, ...]
    end_values: tuple[dict[str, float], ...]
    changes: tuple[dict[str, float], ...]
    converged: bool
    tolerance: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {"steps": list(self.steps), "end_values": [dict(v) for v in self.end_values],
                "changes": [dict(c) for c in self.changes], "converged": self.converged,
                "tolerance": self.tolerance}

    def summary(self) -> str:
        """One line: 'step 0.4 -> 0.2: FT 1.3 %, qR 0.8 % (converged)'."""
        if not self.changes:
            return f"step {self.steps[-1]:g}: one run, convergence not checked"
        last = self.changes[-1]
        parts = ", ".join(f"{k} {100 * v:.1f} %" for k, v in last.items())
        state = "converged" if self.converged else "NOT converged"
        return (f"step {self.steps[-2]:g} -> {self.steps[-1]:g}: {parts} ({state}, "
                f"tolerance {100 * self.tolerance:.0f} %)")


def relative_change(new: float, old: float, initial: float, min_loss: float) -> float:
    """|new - old| / |initial - new| (relative to the loss), absolute against ``min_loss``
    when the quantity did not move."""
    loss = abs(initial - new)
    return abs(new - old) / max(loss, min_loss)


def converge_steps(run: Callable[[float], Any], end_values: Callable[[Any], Mapping[str, float]],
                   initial_values: Mapping[str, float], first_step: float, *,
                   tolerance: float = DEFAULT_TOLERANCE, max_halvings: int = 3,
                   min_loss: float = 0.05) -> tuple[Any, StepConvergence]:
    """Run with ``first_step``, then halve until the end values settle.

    run : step -> result; end_values : result -> {quantity: value at the end};
    initial_values : {quantity: value of the new profile}; max_halvings : at most this many
    halvings (so at most max_halvings + 1 runs); min_loss : the loss below which a quantity
    counts as unmoved (same unit as the values).

    Returns (the result with the finest step run, StepConvergence).
    """
    if not (first_step > 0 and tolerance > 0 and min_loss > 0) or max_halvings < 1:
        raise ValueError("first_step, tolerance and min_loss must be positive and "
                         "max_halvings >= 1")
    step = float(first_step)
    result = run(step)
    steps = [step]
    values = [dict(end_values(result))]
    changes: list[dict[str, float]] = []
    converged = False
    for _ in range(max_halvings):
        step /= 2.0
        result = run(step)
        steps.append(step)
        values.append(dict(end_values(result)))
        change = {k: relative_change(values[-1][k], values[-2][k], initial_values[k], min_loss)
                  for k in values[-1]}
        changes.append(change)
        if all(v < tolerance for v in change.values()):
            converged = True
            break
    return result, StepConvergence(tuple(steps), tuple(values), tuple(changes), converged,
                                   tolerance)
