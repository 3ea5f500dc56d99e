"""Where numba's compiled kernels are cached: one directory, outside the package.

numba reads ``NUMBA_CACHE_DIR`` when it is imported, and writes next to the
source files (into site-packages) when it is unset. `configure` therefore runs
when `service` is imported, before the engine imports numba: it sets
``NUMBA_CACHE_DIR`` from ``AACN_NUMBA_CACHE_DIR`` (an environment variable; a
``.env`` file is read too late), or keeps a ``NUMBA_CACHE_DIR`` already set, or
takes the user's cache directory. Every worker process of `serve` and of the
batch pool shares it, so the kernels are compiled once per machine and version.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

__all__ = ["configure", "default_cache_dir"]


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/aacn-triage/numba`` (``~/.cache/...``), else a per-user temp dir."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    candidate = Path(base) / "aacn-triage" / "numba"
    try:
        candidate.mkdir(parents=True, exist_ok=True)
        if os.access(candidate, os.W_OK):
            return candidate
    except OSError:
        pass
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    return Path(tempfile.gettempdir()) / f"aacn-triage-numba-{uid}"


def configure() -> Path:
    """Set ``NUMBA_CACHE_DIR`` (see the module docstring); returns the directory."""
    chosen = os.environ.get("AACN_NUMBA_CACHE_DIR") or os.environ.get("NUMBA_CACHE_DIR")
    path = Path(chosen) if chosen else default_cache_dir()
    if os.environ.get("NUMBA_CACHE_DIR") != str(path):
        os.environ["NUMBA_CACHE_DIR"] = str(path)
        config = sys.modules.get("numba.core.config")
        if config is not None:  # imported already: kernels decorated later follow
            config.reload_config()
    return path
