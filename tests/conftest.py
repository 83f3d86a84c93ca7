"""Shared test fixtures: where the published reference data lives (``../shared``)."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DIR = REPO_ROOT.parent / "shared"
REFERENCE_DIR = SHARED_DIR / "reference"


@pytest.fixture
def reference_dir() -> Path:
    """``../shared/reference``; the test is skipped, saying so, when it is absent."""
    if not REFERENCE_DIR.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DIR} "
                    "(needs ../shared beside the repo)")
    return REFERENCE_DIR
