from __future__ import annotations

import json
from pathlib import Path

import pytest

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session")
def orca_reference():
    """Reference RVO2 runs shipped in ../shared/reference/orca (skips if the shared folder is absent)."""
    root = SHARED / "reference" / "orca"
    if not root.exists():
        pytest.skip(f"reference data not found at {root}")
    return {name: json.loads((root / f"orca_{name}.json").read_text()) for name in ("headon2", "circle8")}
