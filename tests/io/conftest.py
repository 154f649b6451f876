"""Fixtures for volren.io tests (the shared datasets come from tests/conftest.py)."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def values_int16() -> np.ndarray:
    """A 7x5x4 (nx, ny, nz) grid, values[k, j, i], every value distinct and some negative."""
    return (np.arange(4 * 5 * 7, dtype=np.int16).reshape(4, 5, 7) * 7 - 50).astype(np.int16)


@pytest.fixture
def values_float32() -> np.ndarray:
    """Random floats with few digits: legacy ASCII .vtk files keep only 6 significant digits."""
    rng = np.random.default_rng(7)
    return np.round(rng.normal(size=(4, 5, 7)), 3).astype(np.float32)
