"""A checksum of the code that determines an occupant simulation's numbers.

Recorded with every case and in every surrogate artifact, so that a surrogate
built from other model code is detected at load (the service is then not
ready), and an audit can tell which model code produced a case.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path

__all__ = ["MODEL_SOURCES", "lpm_code_sha256"]

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
)


@lru_cache(maxsize=1)
def lpm_code_sha256() -> str:
    """SHA-256 over the model source files (name and bytes, in a fixed order)."""
    digest = hashlib.sha256()
    for rel in MODEL_SOURCES:
        digest.update(rel.encode())
        digest.update(b"\0")
        digest.update((_MODELS / rel).read_bytes().replace(b"\r\n", b"\n"))
        digest.update(b"\0")
    return digest.hexdigest()
