"""A checksum of the code that determines an occupant simulation's numbers.

Recorded with every case and in every surrogate artifact, so that a surrogate
built from other model code is detected at load (the service is then not
ready), and an audit can tell which model code produced a case.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

__all__ = ["MODEL_SOURCES", "lpm_code_sha256", "sources_sha256"]

_MODELS = Path(__file__).resolve().parents[1]

#: Source files whose content changes simulation results (paths under models/).
MODEL_SOURCES = (
    "lpm/kernel.py",
    "lpm/assemble.py",
    "lpm/simulate.py",
    "lpm/pulses.py",
    "lpm/params.py",
    "injury/filters.py",
    "injury/criteria.py",
    "injury/risk.py",
    "injury/scores.py",
    "injury/assessment.py",
    "injury/batch.py",
    "injury/measures.py",
)


def sources_sha256(sources: Sequence[str], root: Path = _MODELS) -> str:
    """SHA-256 over source files (name and bytes, in the given order; line ends as LF).

    Parameters
    ----------
    sources : sequence of str
        Paths relative to `root` (default: the ``models`` package).
    """
    digest = hashlib.sha256()
    for rel in sources:
        digest.update(rel.encode())
        digest.update(b"\0")
        digest.update((root / rel).read_bytes().replace(b"\r\n", b"\n"))
        digest.update(b"\0")
    return digest.hexdigest()


@lru_cache(maxsize=1)
def lpm_code_sha256() -> str:
    """SHA-256 over the model source files :data:`MODEL_SOURCES`."""
    return sources_sha256(MODEL_SOURCES)
