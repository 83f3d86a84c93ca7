"""The documentation is self-contained and current: no source cites a file outside the
repository, the equation index matches the docstrings, and the layers point one way."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCE_DIRS = ("physics", "statistics", "service", "benchmarks", "examples", "migrations", "tests")
#: Documents that are not in the repository (the founding notes and the shared reference notes
#: lived outside it; the data files under ../shared may still be read, not cited).
OUTSIDE = re.compile(r"DESIGN\.md|STYLE\.md|\.\./shared/DESIGN|shared/seeds/|reference/README\.md")


def _sources() -> list[Path]:
    return [p for d in SOURCE_DIRS for p in sorted((ROOT / d).rglob("*.py"))
            if p != Path(__file__).resolve()]


def test_no_source_cites_a_document_outside_the_repository() -> None:
    offenders = [f"{p.relative_to(ROOT)}:{i}" for p in _sources()
                 for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
                 if OUTSIDE.search(line)]
    assert offenders == [], f"cite docs/ instead of outside files: {offenders[:10]}"


def test_documents_the_code_cites_exist() -> None:
    for name in ("architecture.md", "conventions.md", "references.md", "equations.md"):
        assert (ROOT / "docs" / name).is_file(), name


def test_equation_index_is_current() -> None:
    result = subprocess.run([sys.executable, str(ROOT / "docs" / "equation_index.py"), "--check"],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
        elif isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
    return names


def test_layers_point_one_way() -> None:
    """physics imports neither statistics nor service; statistics does not import service."""
    forbidden = {"physics": ("wearcast.statistics", "wearcast.service"),
                 "statistics": ("wearcast.service",)}
    bad = []
    for layer, prefixes in forbidden.items():
        for path in sorted((ROOT / layer).rglob("*.py")):
            bad += [f"{path.relative_to(ROOT)} imports {m}" for m in _imports(path)
                    if m.startswith(prefixes)]
    assert bad == []


def test_pure_cores_do_no_http_or_sql() -> None:
    io_modules = ("fastapi", "sqlalchemy", "httpx", "requests", "alembic", "uvicorn")
    bad = [f"{p.relative_to(ROOT)} imports {m}" for layer in ("physics", "statistics")
           for p in sorted((ROOT / layer).rglob("*.py")) for m in _imports(p)
           if m.split(".")[0] in io_modules]
    assert bad == []
