"""Shared test fixtures: where the benchmark meshes live."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]


def models_path() -> Path | None:
    """The benchmark models: $POLYFOLD_MODELS, else ../shared/models beside the checkout (as in CI)."""
    env = os.environ.get("POLYFOLD_MODELS")
    path = Path(env) if env else REPO_ROOT.parent / "shared" / "models"
    return path if path.is_dir() else None


def closed_meshes() -> list[Path]:
    """All closed meshes: the *.obj files directly in the models directory (for parametrize)."""
    root = models_path()
    return sorted(root.glob("*.obj")) if root else []


@pytest.fixture(scope="session")
def models_dir() -> Path:
    root = models_path()
    if root is None:
        pytest.skip("benchmark models not found (set POLYFOLD_MODELS or put them in ../shared/models)")
    return root
