"""A checksum of the code that determines an occupant simulation's numbers.

Recorded with every case and in every surrogate artifact, so that an audit can
tell which model code produced a case. It is the checksum of the code's
normalised syntax tree (:mod:`models.codehash`): a docstring, a comment or a
reformat do not change it. Whether the shipped surrogates still fit the
occupant models is not decided by this checksum but by rerunning their golden
cases (:mod:`models.surrogate.golden`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

from models.codehash import source_tree_sha256

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
    "injury/batch_compiled.py",
    "injury/measures.py",
)


def sources_sha256(sources: Sequence[str], root: Path = _MODELS) -> str:
    """SHA-256 over the normalised syntax trees of source files, in the given order.

    Parameters
    ----------
    sources : sequence of str
        Paths relative to `root` (default: the ``models`` package).
    """
    return source_tree_sha256([root / rel for rel in sources])


@lru_cache(maxsize=1)
def lpm_code_sha256() -> str:
    """SHA-256 over the model source files :data:`MODEL_SOURCES`."""
    return sources_sha256(MODEL_SOURCES)
