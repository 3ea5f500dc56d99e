"""aacn-triage HTTP and audit shell: FastAPI app, wire schemas, auth, persistence.

Depends on `models` (the engine); the engine never imports this package.
"""

__version__ = "0.1.0"
