"""Every script in ``benchmarks/`` still imports: its top-level code (imports, constants,
helpers it takes from ``examples/``) runs without error: a benchmark whose imports rot is a
README figure nobody can re-measure. Only the module is loaded; ``main()`` is not run, so a
helper that moved but is only called in ``main()`` is not caught (stop 31 found
``benchmarks/physics_model_loop.py`` calling a test helper that no longer existed).
The test suite's own package is importable here, which it is not when a script runs."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
SCRIPTS = sorted(BENCHMARKS.glob("*.py"))


def test_there_are_benchmarks() -> None:
    assert len(SCRIPTS) > 10


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.stem for s in SCRIPTS])
def test_the_benchmark_imports(script: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert '__name__ == "__main__"' in script.read_text(), "runs its work on import"
    # as when run: its own folder on sys.path (benchmarks import each other)
    monkeypatch.syspath_prepend(str(BENCHMARKS))
    name = f"_benchmark_{script.stem}"
    spec = importlib.util.spec_from_file_location(name, script)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, name, module)  # dataclasses look their module up
    spec.loader.exec_module(module)
