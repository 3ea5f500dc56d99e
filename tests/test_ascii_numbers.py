"""Numbers are read in ASCII digits only, everywhere.

``\\d`` in a regular expression (without ``re.ASCII``), ``int()``, ``Decimal()`` and
``str.isdigit`` / ``isdecimal`` / ``isnumeric`` take any script's digits (``٢٠١٠``,
``２０１０``; ``isdigit`` even ``²``, which ``int()`` then refuses). A VEDS model year in
Arabic-Indic digits was once accepted, stored, and then failed its NEMSIS record. No
module of the service or the engine may use them: digits are ``[0-9]``.
"""

from __future__ import annotations

import ast
from pathlib import Path

from tests.paths import ROOT

#: The functions of the ``re`` module that take a pattern first.
RE_CALLS = frozenset(
    {"compile", "match", "fullmatch", "search", "sub", "subn", "split", "findall", "finditer"}
)
#: The str methods that take any script's digits.
UNICODE_DIGIT_TESTS = frozenset({"isdigit", "isdecimal", "isnumeric"})


def _ascii_flag(call: ast.Call) -> bool:
    flags = [ast.unparse(a) for a in [*call.args[1:], *(k.value for k in call.keywords)]]
    return any("re.ASCII" in f or f == "re.A" or "re.A |" in f or "| re.A" in f for f in flags)


def _findings(path: Path) -> list[tuple[int, str]]:
    """(line, what) of every way `path` reads digits of any script."""
    out: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Attribute):
            continue
        if node.func.attr in UNICODE_DIGIT_TESTS:
            out.append((node.lineno, f".{node.func.attr}() takes any script's digits"))
        on_re = isinstance(node.func.value, ast.Name) and node.func.value.id == "re"
        if on_re and node.func.attr in RE_CALLS and node.args:
            pattern = node.args[0]
            if isinstance(pattern, ast.Constant) and isinstance(pattern.value, str | bytes):
                text = pattern.value if isinstance(pattern.value, str) else pattern.value.decode()
                if "\\d" in text and not _ascii_flag(node):
                    out.append((node.lineno, f"\\d without re.ASCII in {text!r}"))
    return sorted(out)


def test_no_module_reads_digits_of_other_scripts() -> None:
    sources = sorted(p for pkg in ("service", "models") for p in (ROOT / pkg).rglob("*.py"))
    assert len(sources) > 100, "the scan sees the packages"
    findings = [
        f"{p.relative_to(ROOT)}:{line}: {what}" for p in sources for line, what in _findings(p)
    ]
    assert findings == []


def test_the_scan_finds_what_it_looks_for(tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text(
        "import re\n"
        "A = re.compile(r'^\\d{4}$')\n"
        "B = re.compile(r'\\d+', re.ASCII)\n"
        "C = '12'.isdigit()\n"
        "D = re.fullmatch(r'[0-9]{4}', '2010')\n"
        "E = re.match(rb'\\d', b'1', flags=re.I)\n",
        encoding="utf-8",
    )
    assert _findings(probe) == [
        (2, "\\d without re.ASCII in '^\\\\d{4}$'"),
        (4, ".isdigit() takes any script's digits"),
        (6, "\\d without re.ASCII in '\\\\d'"),
    ]
