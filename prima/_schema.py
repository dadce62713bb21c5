"""XSD validation: libxml2 gives the verdict, xmlschema explains failures.

libxml2 (through lxml) decides in microseconds whether a document is valid;
xmlschema, pure Python and about a hundred times slower, runs only on the
documents libxml2 rejects, to produce its thorough diagnostics. Each of its
errors becomes one line located at the element, attribute or unexpected
child it is about. Both validators read the same shipped schemas, and the
test suite checks that they agree on every document of the corpus; should
they ever disagree, libxml2's own located errors are reported, so nothing
invalid passes. Each schema is built once per process.
"""

from __future__ import annotations

import re
from functools import lru_cache
from importlib import resources
from typing import TYPE_CHECKING, Callable, Iterator

from lxml import etree

from prima._xml import XmlDocument, local_name
from prima.errors import Problem, Severity

if TYPE_CHECKING:
    import xmlschema

Hint = Callable[[etree._Element, str, str], "str | None"]
"""Better wording for a failed attribute value: (element, attribute, value) -> message."""


def _read(name: str) -> bytes:
    return resources.files("prima.schemas").joinpath(name).read_bytes()


@lru_cache(maxsize=None)
def verdict_schema(name: str) -> etree.XMLSchema:
    """libxml2's compiled form of ``schemas/<name>``, built once per process."""
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    return etree.XMLSchema(etree.fromstring(_read(name), parser))


@lru_cache(maxsize=None)
def schema(name: str) -> xmlschema.XMLSchema:
    """xmlschema's form of ``schemas/<name>``, built once per process, on first need."""
    import xmlschema  # imported lazily: only documents with errors need it

    ref = resources.files("prima.schemas").joinpath(name)
    with resources.as_file(ref) as path:
        return xmlschema.XMLSchema(str(path))


_NS = re.compile(r"\{[^}]*\}")
_ATTR_VALUE = re.compile(r"^attribute (?P<name>[\w:\-]+)=(?P<value>'.*?'|\".*?\")?:? ?(?P<rest>.*)$", re.S)
_NOT_ALLOWED = re.compile(r"^'(?P<name>[\w:\-]+)' attribute not allowed")
_UNEXPECTED = re.compile(r"Unexpected child with tag '(?P<tag>[^']+)' at position (?P<pos>\d+)")
_MISSING = re.compile(r"missing required attribute '(?P<name>[\w:\-]+)'")


def _clean(text: str) -> str:
    text = _NS.sub("", text)
    return " ".join(text.split())


def validate(doc: XmlDocument, schema_name: str, hint: Hint | None = None) -> list[Problem]:
    """Every schema violation of ``doc`` as a located problem."""
    checker = verdict_schema(schema_name)
    if checker.validate(doc.root.getroottree()):
        return []
    problems = list(_problems(doc, schema(schema_name), hint))
    if problems:
        return problems
    return [Problem(doc.name, e.line, max(e.column, 1), Severity.ERROR, f"schema: {_clean(e.message)}")
            for e in checker.error_log]


def _problems(doc: XmlDocument, xsd: xmlschema.XMLSchema, hint: Hint | None) -> Iterator[Problem]:
    for err in xsd.iter_errors(doc.root):
        el = err.elem if isinstance(err.elem, etree._Element) else doc.root
        tag = f"<{local_name(el)}>"
        reason = _clean(err.reason or str(err))
        m = _ATTR_VALUE.match(reason)
        if m:
            name = m.group("name")
            value = el.get(name, "")
            better = hint(el, name, value) if hint else None
            message = better or _clean(m.group("rest")) or "invalid value"
            yield doc.problem(el, f"{tag}: attribute {name}={value!r}: {message}", attribute=name)
            continue
        m = _NOT_ALLOWED.match(reason)
        if m:
            yield doc.problem(el, f"{tag}: attribute '{m.group('name')}' is not allowed here",
                              attribute=m.group("name"))
            continue
        m = _MISSING.search(reason)
        if m:
            yield doc.problem(el, f"{tag}: missing required attribute '{m.group('name')}'")
            continue
        m = _UNEXPECTED.search(reason)
        if m:
            children = [c for c in el if isinstance(c.tag, str)]
            pos = int(m.group("pos")) - 1
            child = children[pos] if 0 <= pos < len(children) else el
            child_tag = local_name(child) if child is not el else _clean(m.group("tag"))
            where = "at the top of the document" if el is doc.root else f"inside {tag}"
            yield doc.problem(child, f"<{child_tag}> is not allowed {where}")
            continue
        if "is not complete" in reason:
            expected = re.search(r"Tag (.*) expected", reason)
            wanted = f": expected {expected.group(1)}" if expected else ""
            yield doc.problem(el, f"{tag} is incomplete{wanted}")
            continue
        yield doc.problem(el, f"{tag}: {reason}")
