"""Validation of NEMSIS documents against the shipped v3.5.1 XSDs (``xsd/``).

The validator is libxml2's XML Schema 1.0 implementation through ``lxml``: compiled
once per process (about 60 ms), then a few milliseconds per record. Nothing is
fetched: the schemas include each other by relative path, and the parsers here
refuse network access, DTDs and entity expansion.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from lxml import etree

__all__ = ["SCHEMA_PATH", "XSD_DIR", "SchemaError", "schema", "validate"]

#: The shipped schemas (with their provenance, ``xsd/PROVENANCE.md``).
XSD_DIR: Final = Path(__file__).parent / "xsd"
#: The root schema of an EMS data set (``EMSDataSet``).
SCHEMA_PATH: Final = XSD_DIR / "EMSDataSet_v3.xsd"
#: Errors reported at most per document. [R] A record that fails fails on few elements;
#: the bound keeps a problem document small if a defect breaks many.
MAX_ERRORS: Final = 20


@dataclass(frozen=True)
class SchemaError:
    """One violation of the schema.

    Attributes
    ----------
    line : int
        Line of the document (1-based).
    element : str
        The element's path in the document (``/EMSDataSet/Header/...``), without the
        namespace.
    message : str
        libxml2's message.
    """

    line: int
    element: str
    message: str


def _parser() -> etree.XMLParser:
    return etree.XMLParser(no_network=True, resolve_entities=False, load_dtd=False, huge_tree=False)


@functools.cache
def schema() -> etree.XMLSchema:
    """The compiled EMSDataSet schema (once per process)."""
    return etree.XMLSchema(etree.parse(str(SCHEMA_PATH), parser=_parser()))


def _element_path(tree: etree._Element, xpath: str | None) -> str:
    """``EMSDataSet/Header/PatientCareReport[1]/eInjury/...`` of an error's element."""
    if not xpath:
        return ""
    try:
        found = tree.getroottree().xpath(xpath)
    except etree.XPathError:
        return xpath
    if not isinstance(found, list) or not found or not isinstance(found[0], etree._Element):
        return xpath
    names = []
    node: etree._Element | None = found[0]
    while node is not None:
        name = etree.QName(node).localname
        parent = node.getparent()
        if parent is not None and len(parent.findall(node.tag)) > 1:
            name += f"[{parent.findall(node.tag).index(node) + 1}]"
        names.append(name)
        node = parent
    return "/".join(reversed(names))


def validate(document: bytes) -> list[SchemaError]:
    """The schema violations of an XML document (empty: valid).

    A document that is not well-formed XML is one error on its line.
    """
    try:
        tree = etree.fromstring(document, parser=_parser())
    except etree.XMLSyntaxError as exc:
        return [SchemaError(line=exc.lineno or 0, element="", message=str(exc))]
    checker = schema()
    if checker.validate(tree):
        return []
    log: Any = checker.error_log  # lxml-stubs type the log without its entries
    return [
        SchemaError(line=e.line, element=_element_path(tree, e.path), message=e.message.strip())
        for e in list(log)[:MAX_ERRORS]
    ]
