"""XSD validation of scenario and map files, with exact line:col problems.

Each schema is built once per process (building an ``xmlschema.XMLSchema``
costs far more than validating a small file) and looked up as package data
``prima.schemas``, falling back to the source tree's ``schemas/`` folder when
PRIMA runs from a checkout without being installed.
"""

from __future__ import annotations

import functools
import re
from importlib import resources
from pathlib import Path

import xmlschema
from lxml import etree

from prima._xml import XmlDocument, local_name
from prima.errors import Problem

__all__ = ["schema_path", "validate"]

_NS_TAG = re.compile(r"\{[^}]*\}")
_BAD_VALUE = re.compile(r"^attribute (\S+?)=")
_NOT_ALLOWED = re.compile(r"^'([^']+)' attribute not allowed")
_UNEXPECTED = re.compile(r"^Unexpected child with tag '[^']*' at position (\d+)")


def schema_path(name: str) -> Path:
    """Where the XSD file ``name`` is."""
    try:
        found = resources.files("prima.schemas") / name
        if found.is_file():
            return Path(str(found))
    except ModuleNotFoundError:
        pass
    return Path(__file__).resolve().parents[2] / "schemas" / name


@functools.lru_cache(maxsize=None)
def _schema(name: str) -> xmlschema.XMLSchema:
    return xmlschema.XMLSchema(str(schema_path(name)))


def validate(doc: XmlDocument, schema: str) -> list[Problem]:
    """Problems the XSD ``schema`` finds in ``doc`` (empty if valid)."""
    problems: list[Problem] = []
    for err in _schema(schema).iter_errors(doc.root):
        elem = err.elem if isinstance(getattr(err, "elem", None), etree._Element) else doc.root
        reason = _NS_TAG.sub("", err.reason or str(err)).rstrip(".")
        where = f"<{local_name(elem)}>"
        m = _UNEXPECTED.match(reason)
        if m:
            children = [c for c in elem if isinstance(c.tag, str)]
            index = int(m.group(1)) - 1
            if 0 <= index < len(children):
                child = children[index]
                expected = reason.split(". ", 1)[1] if ". " in reason else ""
                message = f"<{local_name(child)}> is not allowed here in {where}"
                if expected:
                    message += f" ({expected[0].lower()}{expected[1:]})"
                problems.append(doc.problem(child, message))
                continue
        m = _BAD_VALUE.match(reason) or _NOT_ALLOWED.match(reason)
        if m and m.group(1) in elem.attrib:
            problems.append(doc.problem(elem, f"{where}: {reason}", attribute=m.group(1)))
        else:
            problems.append(doc.problem(elem, f"{where}: {reason}"))
    return problems
