"""Shared by the benchmark scripts: rewrite one marked section of RESULTS.md."""

from __future__ import annotations

from pathlib import Path

__all__ = ["RESULTS", "write_section"]

RESULTS = Path(__file__).resolve().parent / "RESULTS.md"


def write_section(name: str, text: str, path: Path = RESULTS) -> None:
    """Replace the block between ``<!-- BEGIN name -->`` and ``<!-- END name -->``.

    The block is appended when the file has no such markers yet; every other
    section is left byte for byte as it was.
    """
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    body = path.read_text() if path.exists() else "# Benchmark results\n"
    block = f"{begin}\n{text.strip(chr(10))}\n{end}"
    if begin in body and end in body:
        head, rest = body.split(begin, 1)
        _, tail = rest.split(end, 1)
        body = head + block + tail
    else:
        body = body.rstrip("\n") + "\n\n" + block + "\n"
    path.write_text(body.rstrip("\n") + "\n")
