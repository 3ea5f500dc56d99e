"""A checksum of what code does, not of how it is written.

Artifacts record the checksum of the code they depend on, so that the service
refuses an artifact built from other code. Hashing the raw bytes makes a
docstring edit, a comment, a reformat or a file move look like a change of
physics; hashing the normalised syntax tree does not: the tree drops comments
and layout, and docstrings (the first string of a module, class or function)
are removed before it is dumped. A change of any statement, name or number
changes the checksum.

Parsing and dumping the trees costs a few tenths of a second per process start,
so a checksum is kept in a small file under numba's cache directory
(``NUMBA_CACHE_DIR``, which the service sets for every process and the container
image fills at build time), keyed by the SHA-256 of every file's bytes in order,
the Python version (whose ``ast.dump`` text the checksum is of) and this module's
cache format: the same bytes give the same checksum, and any change of a file
misses the cache and is parsed again. A missing, unreadable or malformed entry is
computed; an entry that cannot be written (a read-only cache) is not kept. The
directory is trusted as numba's compiled kernels in it are: who can write there
can change what the engine runs.
"""

from __future__ import annotations

import ast
import hashlib
import io
import os
import re
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

__all__ = ["cache_dir", "normalised_source", "source_tree_sha256"]

#: Version of the cache entries' key and content; a change makes every old entry miss.
CACHE_FORMAT = "1"
#: An entry's content: one hex SHA-256 digest.
_DIGEST = re.compile(r"[0-9a-f]{64}", re.ASCII)


def _strip_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if (
                body
                and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)
            ):
                # keep the body non-empty (a function of only a docstring)
                node.body = body[1:] or [ast.Pass()]
    return tree


def normalised_source(source: str) -> str:
    """The syntax tree of `source` without docstrings, comments or layout, as text.

    Parameters
    ----------
    source : str
        Python source.

    Returns
    -------
    str
        ``ast.dump`` of the tree (no line or column attributes).
    """
    return ast.dump(_strip_docstrings(ast.parse(source)), include_attributes=False)


def cache_dir() -> Path | None:
    """Where the checksums are kept: ``$NUMBA_CACHE_DIR/codehash``; None when it is unset."""
    numba_dir = os.environ.get("NUMBA_CACHE_DIR")
    return Path(numba_dir) / "codehash" if numba_dir else None


def _text(raw: bytes) -> str:
    """`raw` decoded as ``Path.read_text(encoding="utf-8")`` decodes a file (universal newlines)."""
    return io.TextIOWrapper(io.BytesIO(raw), encoding="utf-8").read()


def _computed(sources: Sequence[bytes]) -> str:
    digest = hashlib.sha256()
    for raw in sources:
        digest.update(normalised_source(_text(raw)).encode())
        digest.update(b"\0")
    return digest.hexdigest()


def _cache_key(sources: Sequence[bytes]) -> str:
    key = hashlib.sha256(f"codehash {CACHE_FORMAT} {sys.version}\0".encode())
    for raw in sources:
        key.update(hashlib.sha256(raw).digest())
    return key.hexdigest()


def _cached(entry: Path) -> str | None:
    try:
        text = entry.read_text(encoding="ascii").strip()
    except (OSError, ValueError):
        return None
    return text if _DIGEST.fullmatch(text) else None


def _keep(entry: Path, checksum: str) -> None:
    """Write the entry atomically (a temporary file renamed); nothing when it cannot be."""
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=entry.parent, prefix=".codehash-")
        try:
            with os.fdopen(fd, "w", encoding="ascii") as f:
                f.write(checksum + "\n")
            os.replace(tmp, entry)
        except OSError:
            Path(tmp).unlink(missing_ok=True)
            raise
    except OSError:
        pass


def source_tree_sha256(
    paths: Sequence[Path], *, cache: Path | None = None, use_cache: bool = True
) -> str:
    """SHA-256 over the normalised syntax trees of `paths`, in the given order.

    The file names are not hashed, so a module moved elsewhere keeps its checksum.

    Parameters
    ----------
    paths : sequence of Path
        Python source files.
    cache : Path, optional
        Directory of the kept checksums (see the module docstring); None (the
        default): :func:`cache_dir`.
    use_cache : bool, optional
        False: computed, nothing read or kept.

    Returns
    -------
    str
        Hex digest (the same with or without the cache).
    """
    sources = [path.read_bytes() for path in paths]
    directory = (cache or cache_dir()) if use_cache else None
    if directory is None:
        return _computed(sources)
    entry = directory / f"{_cache_key(sources)}.sha256"
    checksum = _cached(entry)
    if checksum is None:
        checksum = _computed(sources)
        _keep(entry, checksum)
    return checksum
