"""Where the offline tools read their data and write their reports."""

from __future__ import annotations

from pathlib import Path
from typing import Final

__all__ = ["DATA_DIR", "docs_dir"]

#: Real crash data the offline fits use (provenance files beside each).
DATA_DIR: Final[Path] = Path(__file__).resolve().parent / "data"


def docs_dir(*parts: str) -> Path:
    """A report directory under ``docs/``.

    The repository's ``docs/`` when run from a checkout (a ``pyproject.toml``
    two levels above this package), else ``./docs`` of the working directory:
    reports never go into the installed package.
    """
    repo = Path(__file__).resolve().parents[2]
    root = repo if (repo / "pyproject.toml").is_file() else Path.cwd()
    return root.joinpath("docs", *parts)
