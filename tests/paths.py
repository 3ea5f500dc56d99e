"""The repository root, for tests that read shipped files (docs/, data)."""

from __future__ import annotations

from pathlib import Path
from typing import Final

#: The repository (the directory holding pyproject.toml).
ROOT: Final[Path] = Path(__file__).resolve().parents[1]
