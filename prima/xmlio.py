"""Secure XML loading with exact source positions, and schema validation.

Shared by every loader (documents, robot profiles, scenarios, maps).

Documents come from strangers (an EA is loaded from the building the robot
visits), so parsing is locked down: no DOCTYPE at all (hence no DTD, no
external or internal entities, no entity-expansion bombs), no network, a size
limit and a depth limit. After a successful parse, :class:`SourceMap` scans the
raw text once to learn where every start tag, attribute value and text content
begins; lxml itself only knows the line on which a start tag *ends*.

Schema validation (:func:`validate`): libxml2 (through lxml) decides in
microseconds whether a document is valid; xmlschema, pure Python and about a
hundred times slower, runs only on the documents libxml2 rejects, to produce
its thorough diagnostics. Each of its errors becomes one line located at the
element, attribute or unexpected child it is about. Both validators read the
same shipped schemas, and the test suite checks that they agree on every
document of the corpus; should they ever disagree, libxml2's own located
errors are reported, so nothing invalid passes. Each schema is built once per
process.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from prima.errors import LocatedError, Problem, Severity

if TYPE_CHECKING:
    import xmlschema

__all__ = [
    "MAX_BYTES",
    "MAX_DEPTH",
    "Hint",
    "SourceMap",
    "XmlDocument",
    "local_name",
    "parse_xml",
    "read_source",
    "schema",
    "validate",
    "verdict_schema",
]

MAX_BYTES = 1 << 20
"""Largest document accepted (1 MiB); a dialogue document is far smaller."""

MAX_DEPTH = 64
"""Deepest element nesting accepted."""

_DOCTYPE = re.compile(rb"<!DOCTYPE", re.IGNORECASE)


def _parser() -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        load_dtd=False,
        dtd_validation=False,
        no_network=True,
        huge_tree=False,
        remove_blank_text=False,
    )


@dataclass
class _Place:
    start: int
    attrs: dict[str, tuple[int, str]] = field(default_factory=dict)
    content: int = -1


class SourceMap:
    """Maps elements, attribute values and text content to 1-based line:col."""

    def __init__(self, text: str, root: etree._Element) -> None:
        self._text = text
        self._line_starts = [0] + [m.end() for m in re.finditer("\n", text)]
        self._elements = list(root.iter(tag=etree.Element))  # keeps proxies alive
        places = _scan_start_tags(text)
        self._places: dict[etree._Element, _Place] = dict(zip(self._elements, places, strict=False))

    def position(self, offset: int) -> tuple[int, int]:
        """Line and column (both 1-based) of a character offset."""
        lo, hi = 0, len(self._line_starts) - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if self._line_starts[mid] <= offset:
                lo = mid
            else:
                hi = mid - 1
        return lo + 1, offset - self._line_starts[lo] + 1

    def line_text(self, line: int) -> str:
        """The text of a 1-based source line (without its line break)."""
        if not 1 <= line <= len(self._line_starts):
            return ""
        start = self._line_starts[line - 1]
        end = self._line_starts[line] - 1 if line < len(self._line_starts) else len(self._text)
        return self._text[start:end].rstrip("\r")

    def element(self, el: etree._Element) -> tuple[int, int]:
        """Where the element's start tag begins (its ``<``)."""
        place = self._places.get(el)
        if place is None:
            # lxml-stubs 0.5 leave sourceline (an int or None) untyped
            return (el.sourceline or 1, 1)  # type: ignore[return-value]
        return self.position(place.start)

    def attribute(self, el: etree._Element, name: str, index: int = 0) -> tuple[int, int]:
        """Where character ``index`` of attribute ``name``'s (decoded) value is."""
        place = self._places.get(el)
        if place is None or name not in place.attrs:
            return self.element(el)
        start, raw = place.attrs[name]
        return self.position(start + _raw_index(raw, index))

    def text(self, el: etree._Element, index: int = 0) -> tuple[int, int]:
        """Where character ``index`` of the element's text content is."""
        place = self._places.get(el)
        if place is None or place.content < 0:
            return self.element(el)
        end = self._text.find("<", place.content)
        raw = self._text[place.content : end if end >= 0 else len(self._text)]
        return self.position(place.content + _raw_index(raw, index))


def _raw_index(raw: str, index: int) -> int:
    """Offset in ``raw`` of decoded character ``index`` (entity refs count as one)."""
    decoded = 0
    i = 0
    while i < len(raw) and decoded < index:
        if raw[i] == "&":
            end = raw.find(";", i)
            i = end + 1 if end >= 0 else i + 1
        else:
            i += 1
        decoded += 1
    return i


_MARKUP = re.compile(
    r"""<(?:!--.*?-->|!\[CDATA\[.*?\]\]>|\?.*?\?>|![^>]*>|/[^>]*>"""
    r"""|(?P<name>[^\s/>!?][^\s/>]*)(?P<attrs>(?:\s+[^\s=/>]+\s*=\s*(?:"[^"]*"|'[^']*'))*)\s*(?P<empty>/?)>)""",
    re.S,
)
_ATTRIBUTE = re.compile(r"""([^\s=/>]+)\s*=\s*(?:"([^"]*)"|'([^']*)')""")


def _scan_start_tags(text: str) -> list[_Place]:
    """Start tags of a well-formed document, in document order."""
    places: list[_Place] = []
    for m in _MARKUP.finditer(text):
        if m.group("name") is None:
            continue
        place = _Place(start=m.start(), content=-1 if m.group("empty") else m.end())
        base = m.start("attrs")
        for a in _ATTRIBUTE.finditer(m.group("attrs")):
            raw_name = a.group(1)
            name = raw_name.rpartition(":")[2] if not raw_name.startswith("xmlns") else raw_name
            group = 2 if a.group(2) is not None else 3
            place.attrs[name] = (base + a.start(group), a.group(group))
        places.append(place)
    return places


@dataclass
class XmlDocument:
    """A parsed document with its source map."""

    name: str
    root: etree._Element
    where: SourceMap

    def problem(
        self,
        el: etree._Element,
        message: str,
        *,
        attribute: str | None = None,
        index: int = 0,
        severity: Severity = Severity.ERROR,
    ) -> Problem:
        """A problem located at an element, or inside one of its attributes."""
        if attribute is None:
            line, col = self.where.element(el)
        else:
            line, col = self.where.attribute(el, attribute, index)
        return Problem(self.name, line, col, severity, message)


def read_source(path: Path, error: type[LocatedError]) -> bytes:
    """Read a file's bytes, turning OS errors and oversize files into problems."""
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise error([Problem(str(path), 1, 1, Severity.ERROR,
                                 f"file is {size} bytes; the limit is {MAX_BYTES}")])
        return path.read_bytes()
    except OSError as exc:
        raise error([Problem(str(path), 1, 1, Severity.ERROR,
                             f"cannot read file: {exc.strerror or exc}")]) from exc


def parse_xml(data: bytes, name: str, error: type[LocatedError]) -> XmlDocument:
    """Parse untrusted bytes securely; raise ``error`` with located problems."""

    def fail(line: int, col: int, message: str) -> LocatedError:
        return error([Problem(name, line, col, Severity.ERROR, message)])

    if len(data) > MAX_BYTES:
        raise fail(1, 1, f"document is {len(data)} bytes; the limit is {MAX_BYTES}")
    if data.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" in data[:4]:
        raise fail(1, 1, "PRIMA documents must be UTF-8 (this one looks like UTF-16 or UTF-32)")
    doctype = _DOCTYPE.search(data)
    if doctype:
        before = data[: doctype.start()]
        line = before.count(b"\n") + 1
        col = doctype.start() - (before.rfind(b"\n") + 1) + 1
        raise fail(line, col, "DOCTYPE declarations are not allowed "
                              "(no DTDs or entities in PRIMA documents)")
    try:
        root = etree.fromstring(data, _parser())
    except etree.XMLSyntaxError as exc:
        line, col = exc.position if exc.position else (1, 1)
        message = _syntax_message(exc)
        raise fail(max(line, 1), max(col, 1), f"malformed XML: {message}") from exc
    info = root.getroottree().docinfo
    # defence in depth: never expected here (lxml-stubs 0.5 lack DocInfo.doctype)
    if info.doctype or info.internalDTD is not None:  # type: ignore[union-attr]
        raise fail(1, 1, "DOCTYPE declarations are not allowed "
                         "(no DTDs or entities in PRIMA documents)")
    encoding = info.encoding or "utf-8"
    try:
        text = data.decode(encoding)
    except (LookupError, UnicodeDecodeError) as exc:
        raise fail(1, 1, f"cannot decode document as {encoding}") from exc
    doc = XmlDocument(name=name, root=root, where=SourceMap(text, root))
    _check_depth(doc, lambda el, msg: error([doc.problem(el, msg)]))
    return doc


def _syntax_message(exc: etree.XMLSyntaxError) -> str:
    message = exc.msg or str(exc)
    return re.sub(r", line \d+, column \d+$", "", message)


def _check_depth(doc: XmlDocument, fail: Callable[[etree._Element, str], LocatedError]) -> None:
    stack = [(doc.root, 1)]
    while stack:
        el, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise fail(el, f"elements nest deeper than {MAX_DEPTH} levels")
        stack.extend((child, depth + 1) for child in el if isinstance(child.tag, str))


def local_name(el: etree._Element) -> str:
    """The element's tag without its namespace."""
    return etree.QName(el).localname


# ---------------------------------------------------------------- schemas

Hint = Callable[[etree._Element, str, str], "str | None"]
"""Better wording for a failed attribute value: (element, attribute, value) -> message."""


def _read(name: str) -> bytes:
    return resources.files("prima.schemas").joinpath(name).read_bytes()


@cache
def verdict_schema(name: str) -> etree.XMLSchema:
    """libxml2's compiled form of ``schemas/<name>``, built once per process."""
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    return etree.XMLSchema(etree.fromstring(_read(name), parser))


@cache
def schema(name: str) -> xmlschema.XMLSchema:
    """xmlschema's form of ``schemas/<name>``, built once per process, on first need."""
    import xmlschema  # imported lazily: only documents with errors need it

    ref = resources.files("prima.schemas").joinpath(name)
    with resources.as_file(ref) as path:
        return xmlschema.XMLSchema(str(path))


_NS = re.compile(r"\{[^}]*\}")
_ATTR_VALUE = re.compile(
    r"^attribute (?P<name>[\w:\-]+)=(?P<value>'.*?'|\".*?\")?:? ?(?P<rest>.*)$", re.S)
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
    # lxml-stubs 0.5 declare _ErrorLog without __iter__; it yields _LogEntry objects
    return [Problem(doc.name, e.line, max(e.column, 1), Severity.ERROR,
                    f"schema: {_clean(e.message)}")
            for e in checker.error_log]  # type: ignore[attr-defined]


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
