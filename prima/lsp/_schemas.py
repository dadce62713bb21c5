"""What the schemas say of an element or an attribute: its documentation, its
attributes and the children it may have, and the values an attribute takes.

The schemas are the one source of these texts (the common Commands' part of
``pxml.xsd`` is generated from the Command catalog); this module only reads
them, through xmlschema (``prima.xmlio.schema``, built once per process).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from prima.xmlio import schema

__all__ = ["SCHEMAS", "AttributeInfo", "ElementInfo", "element_info"]

SCHEMAS = {
    "urn:prima:pxml:1": "pxml.xsd",
    "urn:prima:robot:1": "robot.xsd",
    "urn:prima:scenario:1": "scenario.xsd",
    "urn:prima:map:1": "map.xsd",
}
"""The schema of each of PRIMA's namespaces."""


@dataclass(frozen=True)
class AttributeInfo:
    name: str
    doc: str
    required: bool
    default: str | None
    values: tuple[str, ...]
    """The values it may take, when the schema lists them (an enumeration, a boolean)."""
    type_name: str


@dataclass(frozen=True)
class ElementInfo:
    name: str
    doc: str
    attributes: dict[str, AttributeInfo]
    children: tuple[str, ...]
    """The elements it may hold, in the schema's order."""
    text: bool
    """It holds text (a chain, a description, a choice)."""
    decl: Any
    """xmlschema's declaration."""


def _doc(component: Any) -> str:
    for holder in (component, getattr(component, "ref", None), getattr(component, "type", None)):
        annotation = getattr(holder, "annotation", None)
        if annotation is not None and str(annotation).strip():
            return " ".join(str(annotation).split())
    return ""


def _values(attribute: Any) -> tuple[str, ...]:
    kind = attribute.type
    enumeration = getattr(kind, "enumeration", None)
    if enumeration:
        return tuple(str(v) for v in enumeration)
    if getattr(kind, "name", None) == "{http://www.w3.org/2001/XMLSchema}boolean":
        return ("true", "false")
    return ()


def _info(decl: Any) -> ElementInfo:
    kind = decl.type
    attributes: dict[str, AttributeInfo] = {}
    children: list[str] = []
    text = False
    if kind.is_complex():
        for name, attribute in kind.attributes.items():
            if not isinstance(name, str):
                continue
            type_name = str(getattr(attribute.type, "local_name", None) or "")
            attributes[name] = AttributeInfo(
                name, _doc(attribute), attribute.use == "required", attribute.default,
                _values(attribute), type_name)
        if kind.has_simple_content():
            text = True
        elif kind.content is not None and hasattr(kind.content, "iter_elements"):
            seen: dict[str, None] = {}
            for child in kind.content.iter_elements():
                seen.setdefault(child.local_name, None)
            children = list(seen)
            text = bool(kind.mixed)
    else:
        text = True
    return ElementInfo(decl.local_name, _doc(decl), attributes, tuple(children), text, decl)


def element_info(namespace: str | None, path: Sequence[str]) -> ElementInfo | None:
    """What the schema of ``namespace`` says of the element at ``path`` (its name and its
    ancestors' from the root down), or None when the path leaves the schema."""
    name = SCHEMAS.get(namespace or "")
    if name is None or not path:
        return None
    xsd = schema(name)
    decl = xsd.elements.get(path[0])
    if decl is None:
        return None
    for step in path[1:]:
        content = getattr(decl.type, "content", None)
        if content is None or not hasattr(content, "iter_elements"):
            return None
        found: Any = next((c for c in content.iter_elements() if c.local_name == step), None)
        if found is None:
            return None
        decl = found
    return _info(decl)
