"""aacn-triage HTTP and audit shell: FastAPI app, wire schemas, auth, persistence.

Depends on `models` (the engine); the engine never imports this package.
Importing it sets numba's kernel cache directory first (`service.numba_cache`).

Where each part lives, and the way of one notification: ``docs/layout.md``.
"""

from service import numba_cache as _numba_cache

_numba_cache.configure()

__version__ = "0.1.0"
