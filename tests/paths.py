"""The repository root, for tests that read shipped files (docs/, data)."""

from __future__ import annotations

from pathlib import Path
from typing import Final

#: The repository (the directory holding pyproject.toml).
ROOT: Final[Path] = Path(__file__).resolve().parents[1]
#: The VEDS test documents (``tests/service/cases/veds/``, with their provenance).
VEDS_DOCS: Final[Path] = ROOT / "tests" / "service" / "cases" / "veds"
