"""A checksum of what code does, not of how it is written.

Artifacts record the checksum of the code they depend on, so that the service
refuses an artifact built from other code. Hashing the raw bytes makes a
docstring edit, a comment, a reformat or a file move look like a change of
physics; hashing the normalised syntax tree does not: the tree drops comments
and layout, and docstrings (the first string of a module, class or function)
are removed before it is dumped. A change of any statement, name or number
changes the checksum.
"""

from __future__ import annotations

import ast
import hashlib
from collections.abc import Sequence
from pathlib import Path

__all__ = ["normalised_source", "source_tree_sha256"]


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


def source_tree_sha256(paths: Sequence[Path]) -> str:
    """SHA-256 over the normalised syntax trees of `paths`, in the given order.

    The file names are not hashed, so a module moved elsewhere keeps its checksum.

    Parameters
    ----------
    paths : sequence of Path
        Python source files.

    Returns
    -------
    str
        Hex digest.
    """
    digest = hashlib.sha256()
    for path in paths:
        digest.update(normalised_source(path.read_text(encoding="utf-8")).encode())
        digest.update(b"\0")
    return digest.hexdigest()
