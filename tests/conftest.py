from __future__ import annotations

import json
from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="session")
def orca_reference():
    """Reference RVO2 runs (copied from ../shared/reference/orca into tests/data, with its README)."""
    return {name: json.loads((DATA / f"orca_{name}.json").read_text()) for name in ("headon2", "circle8")}
