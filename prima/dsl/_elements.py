"""Reading schema-valid elements: the helpers the document and profile loaders share."""

from __future__ import annotations

from lxml import etree

from prima.xmlio import is_element, local_name


def elements(parent: etree._Element) -> list[etree._Element]:
    """The child elements, without comments and processing instructions."""
    return [c for c in parent if is_element(c)]


def children(parent: etree._Element, tag: str) -> list[etree._Element]:
    """The child elements named ``tag``."""
    return [c for c in elements(parent) if local_name(c) == tag]


def flag(el: etree._Element, name: str, default: bool = False) -> bool:
    """An ``xs:boolean`` attribute (``true`` or ``1``), or ``default`` when it is absent."""
    value = el.get(name)
    return default if value is None else value in ("true", "1")
