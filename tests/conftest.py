"""Shared test fixtures: where the published reference data lives (``../shared``), and the
API key every test client sends.

The service refuses every request without an API key. Tests build apps as
``TestClient(create_app(Settings(...)))``; so that they keep working unchanged, this file sets
``WEARCAST_API_KEY`` to :data:`TEST_API_KEY` (the admin key of every app built in the tests)
and makes every ``TestClient`` send it by default. Tests of authentication opt out
explicitly: ``del client.headers["authorization"]`` (see ``tests/service/test_auth.py``).
Rate limits are off in tests (``WEARCAST_RATE_LIMIT_PER_SECOND=0``) unless a test's
settings turn them on.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
SHARED_DIR = REPO_ROOT.parent / "shared"
REFERENCE_DIR = SHARED_DIR / "reference"
TEST_API_KEY = "wc_test-admin-key-for-the-test-suite-only"

os.environ["WEARCAST_API_KEY"] = TEST_API_KEY
os.environ.setdefault("WEARCAST_RATE_LIMIT_PER_SECOND", "0")


def _send_test_key_by_default() -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient

    if getattr(TestClient.__init__, "_wearcast_key", False):
        return
    original = TestClient.__init__

    def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
        headers = dict(kwargs.pop("headers", None) or {})
        if not any(k.lower() == "authorization" for k in headers):
            headers["Authorization"] = f"Bearer {TEST_API_KEY}"
        original(self, *args, headers=headers, **kwargs)

    __init__._wearcast_key = True  # type: ignore[attr-defined]
    TestClient.__init__ = __init__  # type: ignore[method-assign]


_send_test_key_by_default()


def flange_face_worn_s1002(y_mm: Any, lateral_mm: float) -> Any:
    """S1002 heights z [mm] at ``y_mm`` with the flange face (field-side flank,
    -55 < y < -30 mm) moved towards the flange by ``lateral_mm``; tip, flange back and tread
    untouched."""
    import numpy as np

    from wearcast.physics.profiles.s1002 import s1002_height_mm

    z = s1002_height_mm(y_mm)
    flank = (y_mm > -55.0) & (y_mm < -30.0)
    return np.where(flank, np.minimum(z, s1002_height_mm(y_mm + lateral_mm)), z)


@pytest.fixture
def reference_dir() -> Path:
    """``../shared/reference``; the test is skipped, saying so, when it is absent."""
    if not REFERENCE_DIR.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DIR} "
                    "(needs ../shared beside the repo)")
    return REFERENCE_DIR
