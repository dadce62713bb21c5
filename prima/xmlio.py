"""Secure XML loading with exact source positions, and schema validation.

Shared by every loader (documents, robot profiles, scenarios, maps).

Documents come from strangers (an EA is loaded from the building the robot
visits), so parsing is locked down: UTF-8 only, no DOCTYPE at all (hence no
DTD, no external or internal entities, no entity-expansion bombs), no network,
only regular files, a size limit and a depth limit. After a successful parse,
:class:`SourceMap` scans the raw text once to learn where every start tag,
attribute value and text content begins (lxml itself only knows the line on
which a start tag *ends*); a lookup costs a binary search, so locating every
problem of a large file stays linear.

Schema validation (:func:`validate`): libxml2 (through lxml) decides in
microseconds whether a document is valid; xmlschema, pure Python and about a
hundred times slower, runs only on the documents libxml2 rejects, to produce
its thorough diagnostics. Each of its errors becomes one line located at the
element, attribute or unexpected child it is about. Both validators read the
same shipped schemas, and the test suite checks that they agree on every
document of the corpus; should they ever disagree, libxml2's own located
errors are reported, so nothing invalid passes. xmlschema builds every error
of a document before it yields the first, at about a tenth of a millisecond
each, so it only diagnoses documents of at most :data:`XMLSCHEMA_NODES`
elements and attributes; larger ones get libxml2's errors, reworded the same
way. Each schema is built once per process.

A file reports at most :data:`MAX_PROBLEMS` problems, then one line counting
the rest (:func:`limit`).
"""

from __future__ import annotations

import os
import re
import stat
from bisect import bisect_right
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from functools import cache, cached_property
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from prima.record import Record
from prima.suggest import similar
from prima.errors import LocatedError, Problem, Severity
from prima.shipped import packaged

if TYPE_CHECKING:
    import xmlschema

__all__ = [
    "MAX_ATTRIBUTES",
    "MAX_DIGITS",
    "MAX_BYTES",
    "MAX_DEPTH",
    "MAX_PROBLEMS",
    "XMLSCHEMA_NODES",
    "Bound",
    "Hint",
    "SourceMap",
    "XmlDocument",
    "integer",
    "is_element",
    "limit",
    "local_name",
    "number",
    "parse_xml",
    "read_source",
    "schema",
    "unsaved",
    "validate",
    "verdict_schema",
]

MAX_BYTES = 1 << 20
"""Largest document accepted (1 MiB); a dialogue document is far smaller."""

MAX_DEPTH = 64
"""Deepest element nesting accepted."""

MAX_PROBLEMS = 50
"""Most problems reported for one file; one more line counts the rest."""

MAX_ATTRIBUTES = 64
"""Most attributes xmlschema is shown on one element (a document with more goes to libxml2)."""

XMLSCHEMA_NODES = 2_000
"""Largest document (elements plus attributes) xmlschema diagnoses; the largest
shipped application has about 300."""

_DOCTYPE = re.compile(rb"<!DOCTYPE", re.IGNORECASE)
_DECLARED = re.compile(rb"""\A(?:\xef\xbb\xbf)?<\?xml[^>]*?\sencoding\s*=\s*["']([^"']*)["']""")
_UTF8 = frozenset({"utf-8", "utf8"})


def _parser() -> etree.XMLParser:
    return etree.XMLParser(
        encoding="utf-8",
        resolve_entities=False,
        load_dtd=False,
        dtd_validation=False,
        no_network=True,
        huge_tree=False,
        remove_blank_text=False,
    )


# ---------------------------------------------------------------- source positions

class _Offsets:
    """Where each decoded character of an attribute value or a text is written.

    A value reads the same as it is written except at an entity or character
    reference (``&amp;``: one character, several written), a CR LF line end
    (one character, two written) and a CDATA section's markup (none written
    as characters). Only those breaks are kept, so a lookup is a binary search.
    """

    __slots__ = ("decoded", "raw")

    def __init__(self, text: str, start: int, end: int) -> None:
        self.decoded = [0]
        self.raw = [start]
        done = 0  # decoded characters before ``at``
        at = start
        for m in _BREAKS.finditer(text, start, end):
            done += m.start() - at
            token = m.group()
            if token == "<":  # the first child element or comment: the text ends
                break
            if token.startswith("<![CDATA["):
                self._add(done, m.start() + 9)
                done += len(token) - 12
            else:
                done += 1
            at = m.end()
            self._add(done, at)

    def _add(self, decoded: int, raw: int) -> None:
        self.decoded.append(decoded)
        self.raw.append(raw)

    def offset(self, index: int) -> int:
        """The offset in the file of decoded character ``index``."""
        i = bisect_right(self.decoded, index) - 1
        return self.raw[i] + index - self.decoded[i]


_BREAKS = re.compile(r"&[^;<]*;|\r\n|<!\[CDATA\[.*?\]\]>|<", re.S)


class _Place:
    """Where one start tag is written: its ``<``, the span of its attributes (read on
    first need: a valid document rarely needs an attribute's position) and where
    its content begins (-1 for an empty element)."""

    __slots__ = ("start", "attrs_start", "attrs_end", "content", "_attrs", "offsets")

    def __init__(self, start: int, attrs_start: int, attrs_end: int, content: int) -> None:
        self.start = start
        self.attrs_start = attrs_start
        self.attrs_end = attrs_end
        self.content = content
        self._attrs: dict[str, tuple[int, int]] | None = None
        self.offsets: dict[str, _Offsets] = {}
        """Decoded-offset maps, built on first use (attribute name, or "" for the text)."""

    def attrs(self, text: str) -> dict[str, tuple[int, int]]:
        """Attribute (local) name -> where its raw value starts and ends."""
        if self._attrs is None:
            self._attrs = {}
            for a in _ATTRIBUTE.finditer(text, self.attrs_start, self.attrs_end):
                raw_name = a.group(1)
                if raw_name.startswith("xmlns"):  # a namespace declaration, not an attribute
                    continue
                group = 2 if a.group(2) is not None else 3
                self._attrs[raw_name.rpartition(":")[2]] = (a.start(group), a.end(group))
        return self._attrs


class SourceMap:
    """Maps elements, attribute values and text content to 1-based line:col.

    Built in one pass over the text; every lookup is a dictionary access and a
    binary search, so a file with many problems is located in linear time.
    """

    def __init__(self, text: str, root: etree._Element) -> None:
        self._text = text
        self._line_starts = [0] + [m.end() for m in re.finditer("\n", text)]
        self._elements = list(root.iter(tag=etree.Element))  # keeps proxies alive
        places, self.depth = _scan_start_tags(text)
        """How deep the elements nest (the root alone: 1)."""
        self._places: dict[etree._Element, _Place] = dict(zip(self._elements, places, strict=False))

    @cached_property
    def _attribute_counts(self) -> list[int]:
        return [len(el.attrib) for el in self._elements]

    @property
    def nodes(self) -> int:
        """Elements plus attributes: what schema diagnostics cost (counted when asked:
        only a document the schema refuses is asked)."""
        return len(self._places) + sum(self._attribute_counts)

    @property
    def most_attributes(self) -> int:
        """The most attributes one element carries."""
        return max(self._attribute_counts, default=0)

    @property
    def source(self) -> str:
        """The text the map was built from (a byte-order mark left out)."""
        return self._text

    def offset(self, el: etree._Element) -> int | None:
        """Where the element's start tag begins (its ``<``), if it is known."""
        place = self._places.get(el)
        return None if place is None else place.start

    def position(self, offset: int) -> tuple[int, int]:
        """Line and column (both 1-based) of a character offset."""
        line = bisect_right(self._line_starts, offset) - 1
        return line + 1, offset - self._line_starts[line] + 1

    def line_text(self, line: int) -> str:
        """The text of a 1-based source line (without its line break)."""
        if not 1 <= line <= len(self._line_starts):
            return ""
        start = self._line_starts[line - 1]
        end = self._line_starts[line] - 1 if line < len(self._line_starts) else len(self._text)
        return self._text[start:end].rstrip("\r")

    def line_length(self, line: int) -> int:
        """How many characters a 1-based source line has (without its line break)."""
        if not 1 <= line <= len(self._line_starts):
            return 0
        end = self._line_starts[line] - 1 if line < len(self._line_starts) else len(self._text)
        return end - self._line_starts[line - 1]

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
        span = None if place is None else place.attrs(self._text).get(name)
        if place is None or span is None:
            return self.element(el)
        offsets = place.offsets.get(name)
        if offsets is None:
            offsets = place.offsets[name] = _Offsets(self._text, *span)
        return self.position(offsets.offset(index))

    def text(self, el: etree._Element, index: int = 0) -> tuple[int, int]:
        """Where character ``index`` of the element's text content is."""
        place = self._places.get(el)
        if place is None or place.content < 0:
            return self.element(el)
        offsets = place.offsets.get("")
        if offsets is None:
            offsets = place.offsets[""] = _Offsets(self._text, place.content, len(self._text))
        return self.position(offsets.offset(index))


_MARKUP = re.compile(
    r"""<(?:!--.*?-->|!\[CDATA\[.*?\]\]>|\?.*?\?>|![^>]*>|(?P<end>/)[^>]*>"""
    r"""|(?P<name>[^\s/>!?][^\s/>]*)(?P<attrs>(?:\s+[^\s=/>]+\s*=\s*(?:"[^"]*"|'[^']*'))*)\s*(?P<empty>/?)>)""",
    re.S,
)
_ATTRIBUTE = re.compile(r"""([^\s=/>]+)\s*=\s*(?:"([^"]*)"|'([^']*)')""")


def _scan_start_tags(text: str) -> tuple[list[_Place], int]:
    """Start tags of a well-formed document, in document order, and how deep its
    elements nest."""
    places: list[_Place] = []
    depth = deepest = 0
    for m in _MARKUP.finditer(text):
        kind = m.lastgroup  # "empty" (a start tag's last group), "end", or None (the rest)
        if kind == "end":
            depth -= 1
        elif kind is not None:
            depth += 1
            if depth > deepest:
                deepest = depth
            if m.group("empty"):
                depth -= 1
                places.append(_Place(m.start(), m.start("attrs"), m.end("attrs"), -1))
            else:
                places.append(_Place(m.start(), m.start("attrs"), m.end("attrs"), m.end()))
    return places, deepest


@dataclass(repr=False)
class XmlDocument(Record):
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


@dataclass(frozen=True, repr=False, eq=False)
class Bound(Record):
    """The range a number written in an attribute must lie in, and its unit."""

    high: float
    unit: str = ""
    low: float = 0.0
    """The lowest value; with ``positive``, values must be greater than it."""
    positive: bool = True


MAX_DIGITS = 18
"""Most digits of an integer attribute (a seed, a rate, a count) that is read."""


def _shown(raw: str) -> str:
    return repr(raw if len(raw) <= 20 else raw[:17] + "...")


def number(doc: XmlDocument, el: etree._Element, name: str, bound: Bound,
           default: float) -> float | Problem:
    """Attribute ``name`` (a decimal the schema accepted) as a float within ``bound``,
    or the problem at the attribute; ``default`` when it is absent.

    A decimal can still be infinite or zero as a float (``1`` and 400 zeros,
    ``0.`` and 400 zeros), and would crash a run that validated.
    """
    raw = el.get(name)
    if raw is None:
        return default
    try:
        value = float(raw)
    except ValueError:
        return doc.problem(el, f"{name}={_shown(raw)} is not a number", attribute=name)
    unit = f" {bound.unit}" if bound.unit else ""
    if not value <= bound.high:  # also NaN
        return doc.problem(el, f"{name}={_shown(raw)} is too large: at most {bound.high:,g}{unit}",
                           attribute=name)
    if bound.positive and value <= bound.low:
        return doc.problem(el, f"{name}={_shown(raw)} must be greater than {bound.low:g}"
                               + (" (a value this small counts as 0)" if value == bound.low
                                  and raw.strip("+-0.") else ""), attribute=name)
    if value < bound.low:
        return doc.problem(el, f"{name}={_shown(raw)} is too small: at least {bound.low:,g}{unit}",
                           attribute=name)
    return value


def integer(doc: XmlDocument, el: etree._Element, name: str, high: int,
            default: int) -> int | Problem:
    """Attribute ``name`` (a non-negative integer the schema accepted) at most ``high``,
    or the problem at the attribute; ``default`` when it is absent. Its digits are
    counted before it is converted (Python refuses more than 4,300 of them)."""
    raw = el.get(name)
    if raw is None:
        return default
    digits = raw.strip().lstrip("+").lstrip("0") or "0"
    if not digits.isdigit() or len(digits) > MAX_DIGITS or int(digits) > high:
        return doc.problem(el, f"{name}={_shown(raw)} is too large: at most {high:,}",
                           attribute=name)
    return int(digits)


def limit(problems: Iterable[Problem], name: str, total: int | None = None) -> list[Problem]:
    """At most :data:`MAX_PROBLEMS` of ``problems``, then one line counting the rest.

    ``total`` is how many there are when ``problems`` holds only the first ones
    (at least ``MAX_PROBLEMS + 1`` of them); the counting line is at ``name:1:1``.
    """
    found = list(problems)
    total = len(found) if total is None else max(total, len(found))
    if total <= MAX_PROBLEMS:
        return found
    rest = found[MAX_PROBLEMS:]
    errors = any(p.severity is Severity.ERROR for p in rest) or len(found) < total
    more = total - MAX_PROBLEMS
    return [*found[:MAX_PROBLEMS], Problem(
        name, 1, 1, Severity.ERROR if errors else Severity.WARNING,
        f"... and {more:,} more problem{'s' if more != 1 else ''} "
        f"(a file reports at most {MAX_PROBLEMS})")]


# ---------------------------------------------------------------- reading and parsing

def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


_UNSAVED: ContextVar[Mapping[Path, bytes] | None] = ContextVar("prima_unsaved", default=None)
"""What :func:`unsaved` put in place of files, by resolved path."""


@contextmanager
def unsaved(sources: Mapping[Path, bytes]) -> Iterator[None]:
    """While inside, :func:`read_source` reads these bytes for these files instead of
    what is on disk: what an editor holds and has not saved, which ``prima lsp``
    checks exactly as the saved files would be checked (the files a scenario
    names included). Within this context only (and this thread or task)."""
    token = _UNSAVED.set({_resolved(Path(p)): data for p, data in sources.items()})
    try:
        yield
    finally:
        _UNSAVED.reset(token)


def _resolved(path: Path) -> Path:
    try:
        return path.resolve()
    except (OSError, RuntimeError):  # a symlink loop
        return path.absolute()


def read_source(path: Path, error: type[LocatedError]) -> bytes:
    """Read a regular file's bytes, at most :data:`MAX_BYTES` of them.

    A named pipe, a device or a directory is refused before it is opened (and
    it is opened without blocking, should it change in between), and no more
    than the limit plus one byte is read, so a file that grows cannot get past
    the limit. Every failure is a problem at ``path:1:1``. Inside :func:`unsaved`,
    a file it names is read from there (under the same size limit).
    """
    def fail(message: str) -> LocatedError:
        return error([Problem(str(path), 1, 1, Severity.ERROR, message)])

    overlay = _UNSAVED.get()
    if overlay:
        held = overlay.get(_resolved(Path(path)))
        if held is not None:
            if len(held) > MAX_BYTES:
                raise fail(f"file is {len(held)} bytes; the limit is {MAX_BYTES}")
            return held
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            raise fail(f"{_kind(info.st_mode)}: PRIMA reads only regular files")
        if info.st_size > MAX_BYTES:
            raise fail(f"file is {info.st_size} bytes; the limit is {MAX_BYTES}")
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
        with os.fdopen(fd, "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                raise fail("not a regular file: PRIMA reads only regular files")
            data = f.read(MAX_BYTES + 1)
    except OSError as exc:
        raise fail(f"cannot read file: {exc.strerror or exc}") from exc
    if len(data) > MAX_BYTES:
        raise fail(f"file is more than {MAX_BYTES} bytes; the limit is {MAX_BYTES}")
    return data


def parse_xml(data: bytes, name: str, error: type[LocatedError]) -> XmlDocument:
    """Parse untrusted bytes securely; raise ``error`` with located problems."""

    def fail(line: int, col: int, message: str) -> LocatedError:
        return error([Problem(name, line, col, Severity.ERROR, message)])

    if len(data) > MAX_BYTES:
        raise fail(1, 1, f"document is {len(data)} bytes; the limit is {MAX_BYTES}")
    if data.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" in data[:4]:
        raise fail(1, 1, "PRIMA documents must be UTF-8 (this one looks like UTF-16 or UTF-32)")
    declared = _DECLARED.match(data)
    if declared and declared.group(1).decode("ascii", "replace").lower() not in _UTF8:
        col = declared.start(1) + 1 - (3 if data.startswith(b"\xef\xbb\xbf") else 0)
        raise fail(1, col, "PRIMA documents must be UTF-8, not "
                           f"{declared.group(1).decode('ascii', 'replace')!r}")
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
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:  # lxml accepted it, so never expected
        raise fail(1, 1, "cannot decode document as UTF-8") from exc
    doc = XmlDocument(name=name, root=root, where=SourceMap(text, root))
    _check_depth(doc, lambda el, msg: error([doc.problem(el, msg)]))
    return doc


def _syntax_message(exc: etree.XMLSyntaxError) -> str:
    message = exc.msg or str(exc)
    return re.sub(r", line \d+, column \d+$", "", message)


def _check_depth(doc: XmlDocument, fail: Callable[[etree._Element, str], LocatedError]) -> None:
    if doc.where.depth <= MAX_DEPTH:  # (counted as the text was read: no walk)
        return
    stack = [(doc.root, 1)]
    while stack:
        el, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise fail(el, f"elements nest deeper than {MAX_DEPTH} levels")
        stack.extend((child, depth + 1) for child in el if is_element(child))


def is_element(node: etree._Element) -> bool:
    """Whether ``node``, a child as lxml gives it, is an element: not a comment or a
    processing instruction, whose ``tag`` is a function. (lxml's stubs say a ``str``:
    read as one, the compiled build checks it is one and fails. Every compiled module
    asks this, or reads ``tag`` of elements only.)"""
    return isinstance(getattr(node, "tag"), str)  # noqa: B009 (Any: not checked as a str)


def local_name(el: etree._Element) -> str:
    """The element's tag without its namespace."""
    tag: object = getattr(el, "tag")  # noqa: B009 (see is_element)
    if isinstance(tag, str):  # "{namespace}name" or "name": what QName reads, without it
        return tag.rpartition("}")[2]
    return etree.QName(el).localname


# ---------------------------------------------------------------- schemas

Hint = Callable[[etree._Element, str, str], "str | None"]
"""Better wording for a failed attribute value: (element, attribute, value) -> message."""


def _read(name: str) -> bytes:
    return packaged("prima.schemas", name).read_bytes()


@cache
def verdict_schema(name: str) -> etree.XMLSchema:
    """libxml2's compiled form of ``schemas/<name>``, built once per process."""
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
    return etree.XMLSchema(etree.fromstring(_read(name), parser))


@cache
def schema(name: str) -> xmlschema.XMLSchema:
    """xmlschema's form of ``schemas/<name>``, built once per process, on first need."""
    import xmlschema  # imported lazily: only documents with errors need it

    with _ascii_selector_checks():
        return xmlschema.XMLSchema(str(packaged("prima.schemas", name)))


_ASCII_NAME_START = "[A-Za-z_:]"
_ASCII_NAME_CHAR = "[-.0-9A-Za-z_:]"


@contextmanager
def _ascii_selector_checks() -> Iterator[None]:
    """While PRIMA builds a schema with xmlschema, its check of identity-constraint
    XPaths matches ASCII names only.

    xmlschema checks the XPath of every ``xs:selector`` and ``xs:field`` against
    a pattern it compiles on first need from XML's name classes (``\\i``, ``\\c``:
    most of Unicode), about 0.1 s of CPU, a third of what the first document with
    a schema fault costs. The only identity constraints are the XSD meta-schema's
    (PRIMA's schemas have none: ``tests/dsl/test_xmlio.py`` checks), whose
    XPaths are ASCII, so the same pattern over ASCII names checks them alike.
    Each class's own pattern (none yet) is put back afterwards, so anyone else's
    schema built in the process is checked as xmlschema checks it. With another
    version of xmlschema that has no such class attribute this does nothing.
    """
    from xmlschema.validators import identities

    patched = []
    for cls in (identities.XsdSelector, identities.XsdFieldSelector):
        regexp = getattr(cls, "_REGEXP", None)
        if getattr(cls, "pattern", 0) is None and isinstance(regexp, str):
            cls.pattern = re.compile(regexp.replace("\\i", _ASCII_NAME_START)
                                     .replace("\\c", _ASCII_NAME_CHAR))
            patched.append(cls)
    try:
        yield
    finally:
        for cls in patched:
            cls.pattern = None


# The patterns that read the validators' messages are compiled on their first use (through
# re's own cache, ``re.compile(_NS)``): only a file with a fault needs them, and compiling
# them all would cost every command that reads a file about a millisecond of its start.
_NS = r"\{[^}'\s]*\}"
"""A namespace in Clark notation (``{urn:prima:pxml:1}state``); not libxml2's sets of
values (``{'asap', 'after-latest'}``)."""
_ATTR_VALUE = r"(?s)^attribute (?P<name>[\w:\-]+)=(?P<value>'.*?'|\".*?\")?:? ?(?P<rest>.*)$"
_NOT_ALLOWED = r"^'(?P<name>[\w:\-]+)' attribute not allowed"
_UNEXPECTED = r"Unexpected child with tag '(?P<tag>[^']+)' at position (?P<pos>\d+)"
_MISSING = r"missing required attribute '(?P<name>[\w:\-]+)'"


def _clean(text: str) -> str:
    text = re.compile(_NS).sub("", text)
    return " ".join(text.split())


def validate(doc: XmlDocument, schema_name: str, hint: Hint | None = None) -> list[Problem]:
    """Every schema violation of ``doc`` as a located problem (at most :data:`MAX_PROBLEMS`,
    then one line counting the rest)."""
    checker = verdict_schema(schema_name)
    if checker.validate(doc.root.getroottree()):
        return []
    # lxml-stubs 0.5 declare _ErrorLog without __iter__ or __len__; it holds _LogEntry objects
    log: Sequence[etree._LogEntry] = checker.error_log  # type: ignore[assignment]
    small = doc.where.nodes <= XMLSCHEMA_NODES and doc.where.most_attributes <= MAX_ATTRIBUTES
    if small:
        problems = list(_problems(doc, schema(schema_name), hint))
        if problems:
            return limit(problems, doc.name)
    return _libxml2_problems(doc, log, hint)


def _problems(doc: XmlDocument, xsd: xmlschema.XMLSchema, hint: Hint | None) -> Iterator[Problem]:
    children: dict[etree._Element, list[etree._Element]] = {}
    for err in xsd.iter_errors(doc.root):
        el = err.elem if isinstance(err.elem, etree._Element) else doc.root
        reason = _clean(err.reason or str(err))
        m = re.compile(_UNEXPECTED).search(reason)
        if m:
            if el not in children:
                children[el] = [c for c in el if is_element(c)]
            yield _unexpected(doc, el, children[el], int(m.group("pos")) - 1,
                              _clean(m.group("tag")), _element_names(xsd))
            continue
        yield _reworded(doc, el, reason, hint, _wanted(err.validator))


def _element_names(xsd: xmlschema.XMLSchema) -> tuple[str, ...]:
    """Every element name a schema declares (to say which one a misspelt one may be)."""
    import xmlschema  # (loaded already: it made ``xsd``)

    names = _ELEMENT_NAMES.get(id(xsd))
    if names is None:
        names = _ELEMENT_NAMES[id(xsd)] = tuple(sorted({
            c.local_name for c in xsd.iter_components()
            if isinstance(c, xmlschema.XsdElement) and c.local_name}))
    return names


_ELEMENT_NAMES: dict[int, tuple[str, ...]] = {}


def _unexpected(doc: XmlDocument, parent: etree._Element, children: list[etree._Element],
                pos: int, tag: str, known: Iterable[str] = ()) -> Problem:
    """A child element the parent's content does not allow (and the element its name may
    be a misspelling of)."""
    child = children[pos] if 0 <= pos < len(children) else parent
    child_tag = local_name(child) if child is not parent else tag
    where = "at the top of the document" if parent is doc.root else \
        f"inside <{local_name(parent)}>"
    meant = similar(child_tag, known)
    return doc.problem(child, f"<{child_tag}> is not allowed {where}"
                              + (f"; did you mean <{meant}>?" if meant else ""))


def _reworded(doc: XmlDocument, el: etree._Element, reason: str, hint: Hint | None,
              wanted: str | None = None) -> Problem:
    """One of xmlschema's reasons about ``el`` (its attributes or its content), reworded;
    ``wanted`` says in plain words what the value must be, when the validator is known."""
    tag = f"<{local_name(el)}>"
    m = re.compile(_ATTR_VALUE).match(reason)
    if m:
        return _bad_value(doc, el, m.group("name"), wanted or _clean(m.group("rest")), hint)
    m = re.compile(_NOT_ALLOWED).match(reason)
    if m:
        return doc.problem(el, f"{tag}: attribute '{m.group('name')}' is not allowed here",
                           attribute=m.group("name"))
    m = re.compile(_MISSING).search(reason)
    if m:
        return doc.problem(el, f"{tag}: missing required attribute '{m.group('name')}'")
    if "is not complete" in reason:
        expected = re.search(r"Tag (.*) expected", reason)
        wanted = f": expected {expected.group(1)}" if expected else ""
        return doc.problem(el, f"{tag} is incomplete{wanted}")
    return doc.problem(el, f"{tag}: {wanted or reason}")


def _bad_value(doc: XmlDocument, el: etree._Element, name: str, reason: str,
               hint: Hint | None) -> Problem:
    value = el.get(name, "")
    better = hint(el, name, value) if hint else None
    shown = value if len(value) <= 60 else value[:57] + "..."
    return doc.problem(el, f"<{local_name(el)}>: attribute {name}={shown!r}: "
                           f"{better or reason or 'invalid value'}", attribute=name)


# libxml2's wording, e.g. "Element '{urn:prima:pxml:1}state', attribute 'x': The
# attribute 'x' is not allowed." (the element is found from the entry's path)
_LIBXML2 = r"(?s)^Element '(?P<tag>[^']*)'(?:, attribute '(?P<attr>[^']*)')?: (?P<rest>.*)$"
_LIBXML2_MISSING = r"The attribute '(?P<name>[^']+)' is required but missing"
_LIBXML2_EXPECTED = r"Expected is (?:one of )?\( (?P<tags>.*?) \)"
_STEP = r"(?P<name>[^/\[]+)(?:\[(?P<pos>\d+)\])?"


def _libxml2_problems(doc: XmlDocument, log: Sequence[etree._LogEntry],
                      hint: Hint | None) -> list[Problem]:
    """libxml2's own errors, located and worded like xmlschema's (large documents)."""
    found = [_from_libxml2(doc, entry, hint) for entry in log[: MAX_PROBLEMS + 1]]
    return limit(found, doc.name, len(log))


def _from_libxml2(doc: XmlDocument, entry: etree._LogEntry, hint: Hint | None) -> Problem:
    el = _at_path(doc.root, entry.path or "")
    m = re.compile(_LIBXML2).match(_clean(entry.message or ""))
    if el is None or m is None:
        return Problem(doc.name, max(entry.line, 1), max(entry.column, 1), Severity.ERROR,
                       f"schema: {_clean(entry.message or '')}")
    attr, rest = m.group("attr"), m.group("rest")
    if attr is not None and "is not allowed" in rest:
        return doc.problem(el, f"<{local_name(el)}>: attribute '{attr}' is not allowed here",
                           attribute=attr)
    if attr is not None:
        return _bad_value(doc, el, attr, _libxml2_value(rest.rstrip(".")), hint)
    missing = re.compile(_LIBXML2_MISSING).search(rest)
    if missing:
        return doc.problem(el, f"<{local_name(el)}>: missing required attribute "
                               f"'{missing.group('name')}'")
    expected = re.compile(_LIBXML2_EXPECTED).search(rest)
    if "This element is not expected" in rest:
        parent = el.getparent()
        if parent is not None:
            return _unexpected(doc, parent, [el], 0, local_name(el))
    if "Missing child element" in rest and expected:
        return doc.problem(el, f"<{local_name(el)}> is incomplete: expected "
                               f"{expected.group('tags')}")
    return doc.problem(el, f"<{local_name(el)}>: {rest}")


# libxml2's reason a value is bad: the facet or the built-in type that refused it
_LIBXML2_FACET = r"(?s)^\[facet '(?P<facet>\w+)'\] (?P<rest>.*)$"
_LIBXML2_FACET_VALUE = {
    "enumeration": r"(?s)the set \{(?P<v>.*)\}$",
    "pattern": r"(?s)by the pattern '(?P<v>.*)'$",
    "minInclusive": r"allowed \('(?P<v>[^']*)'\)$",
    "maxInclusive": r"allowed \('(?P<v>[^']*)'\)$",
    "minExclusive": r"greater than '(?P<v>[^']*)'$",
    "maxExclusive": r"less than '(?P<v>[^']*)'$",
    "minLength": r"length of '(?P<v>\d+)'$",
    "maxLength": r"length of '(?P<v>\d+)'$",
    "length": r"length of '(?P<v>\d+)'$",
}
_LIBXML2_TYPE = r"(?s)^'.*' is not a valid value of the atomic type 'xs:(?P<type>\w+)'$"


def _libxml2_value(reason: str) -> str:
    """libxml2's reason a value is bad, in the plain words xmlschema's are put in (by the
    facet or built-in type named in it); as libxml2 says it for any other."""
    m = re.compile(_LIBXML2_FACET).match(reason)
    if m and m.group("facet") in _LIBXML2_FACET_VALUE:
        facet = m.group("facet")
        found = re.compile(_LIBXML2_FACET_VALUE[facet]).search(m.group("rest"))
        if found:
            value = found.group("v")
            if facet == "enumeration":
                return _one_of(re.findall(r"'([^']*)'", value))
            if facet == "pattern":
                return _pattern_words(value)
            if facet.startswith(("min", "max")) and "Length" not in facet:
                value = _number_text(_decimal(value))
            return _facet_words(facet, value)
    m = re.compile(_LIBXML2_TYPE).match(reason)
    if m and m.group("type") in _TYPE_WORDS:
        return _TYPE_WORDS[m.group("type")]
    return reason


# ---------------------------------------------------------------- what a value must be

_FACET_WORDS = {
    "minInclusive": "must be {} or more",
    "maxInclusive": "must be {} or less",
    "minExclusive": "must be more than {}",
    "maxExclusive": "must be less than {}",
    "minLength": "must be at least {} character(s) long",
    "maxLength": "must be at most {} character(s) long",
    "length": "must be exactly {} character(s) long",
}
"""What a value must be, by the XSD facet that refused it, given the facet's value."""

_TYPE_WORDS = {
    "decimal": "must be a number written like 12 or -0.5 (no exponent: not 1e3)",
    **dict.fromkeys(("double", "float"), "must be a number"),
    **dict.fromkeys(("integer", "long", "int", "short", "byte"), "must be a whole number"),
    **dict.fromkeys(("nonNegativeInteger", "unsignedLong", "unsignedInt", "unsignedShort",
                     "unsignedByte"), "must be a whole number, 0 or more"),
    "positiveInteger": "must be a whole number, 1 or more",
    "nonPositiveInteger": "must be a whole number, 0 or less",
    "negativeInteger": "must be a whole number, -1 or less",
    "boolean": "must be true or false",
}
"""What a value must be, by the XSD built-in type that refused it."""

_BUILTIN_CHECKS = {
    "positive_int_validator": "positiveInteger",
    "non_negative_int_validator": "nonNegativeInteger",
    "non_positive_int_validator": "nonPositiveInteger",
    "negative_int_validator": "negativeInteger",
    "int_validator": "int", "long_validator": "long", "short_validator": "short",
    "byte_validator": "byte", "unsigned_int_validator": "unsignedInt",
    "unsigned_long_validator": "unsignedLong", "unsigned_short_validator": "unsignedShort",
    "unsigned_byte_validator": "unsignedByte", "decimal_validator": "decimal",
}
"""xmlschema's range checks of built-in types (plain functions), by the type they check."""


def _wanted(validator: object) -> str | None:
    """What the value refused by xmlschema's ``validator`` must be, in plain words (None for
    a validator of another kind: an element's content, a union, ...)."""
    from xmlschema.validators import (
        XsdAtomicBuiltin,
        XsdEnumerationFacets,
        XsdFacet,
        XsdPatternFacets,
    )

    if isinstance(validator, XsdPatternFacets):
        return " or ".join(dict.fromkeys(_pattern_words(r) for r in validator.regexps))
    if isinstance(validator, XsdEnumerationFacets):
        return _one_of([str(v) for v in validator.enumeration])
    if isinstance(validator, XsdFacet):
        facet = str(validator.elem.tag).rpartition("}")[2]
        return _facet_words(facet, _number_text(validator.value)) \
            if facet in _FACET_WORDS else None
    if isinstance(validator, XsdAtomicBuiltin):
        return _TYPE_WORDS.get(str(validator.name).rpartition("}")[2])
    name = getattr(validator, "__name__", "")
    return _TYPE_WORDS.get(_BUILTIN_CHECKS.get(name, ""))


def _facet_words(facet: str, value: str) -> str:
    """What a value must be for ``facet`` (one of :data:`_FACET_WORDS`) of ``value``."""
    if facet == "minLength" and value == "1":
        return "must not be empty"
    return _FACET_WORDS[facet].format(value)


def _decimal(text: str) -> object:
    """``text`` as a Decimal, as xmlschema holds a bound (the text itself if it is none)."""
    from decimal import Decimal, InvalidOperation

    try:
        return Decimal(text)
    except InvalidOperation:
        return text


def _number_text(value: object) -> str:
    """A facet's value as written in a message: ``0``, ``0.5`` (not ``Decimal('0')``)."""
    from decimal import Decimal

    if isinstance(value, Decimal):
        text = format(value.normalize(), "f")
        return text if text != "-0" else "0"
    return str(value)


def _one_of(values: Sequence[str]) -> str:
    """``must be 'fa' or 'ea'``; ``must be one of 'a', 'b' or 'c'``."""
    quoted = [f"'{v}'" for v in values]
    if len(quoted) <= 2:
        return f"must be {' or '.join(quoted)}"
    return f"must be one of {', '.join(quoted[:-1])} or {quoted[-1]}"


_ATOM = (r"(\[(?P<cls>(?:\\.|[^\]\\])+)\]|\\(?P<esc>.)|(?P<lit>[^\\\[\](){}|.*+?^$]))"
         r"(?P<q>[*+?]?)")
_RANGES = (("A-Za-z", "a letter", "letters"), ("A-Z", "an upper-case letter", "upper-case letters"),
           ("a-z", "a lower-case letter", "lower-case letters"), ("0-9", "a digit", "digits"))


def _pattern_words(regex: str) -> str:
    """What a value matching an XSD pattern looks like, in plain words, for a pattern made of
    character classes and characters (``[A-Za-z_][A-Za-z0-9_\\-]*``: ``must be a name: a
    letter or _, then letters, digits, _ or -``); other patterns are quoted as they are."""
    parts: list[str] = []
    at = 0
    while at < len(regex):
        m = re.compile(_ATOM).match(regex, at)
        if m is None:
            return f"must match the pattern {regex}"
        at = m.end()
        one, many = _choices(m.group("cls")) if m.group("cls") else \
            ([m.group("esc") or m.group("lit")],) * 2
        quantity = m.group("q")
        words = _or(many) if quantity in ("*", "+") else _or(one)
        if quantity == "?":
            words = f"optionally {words}"
        elif quantity == "*" and parts:
            words = f"then any number of {words}" if len(many) == 1 else f"then {words}"
        elif quantity == "+":
            words = f"then one or more {words}" if parts else f"one or more {words}"
        elif parts:
            words = f"then {words}"
        parts.append(words)
    return f"must be a name: {', '.join(parts)}"


def _choices(cls: str) -> tuple[list[str], list[str]]:
    """The characters a class admits, in words: (singular, plural) (``a letter``, ``letters``)."""
    one: list[str] = []
    many: list[str] = []
    for chars, singular, plural in _RANGES:
        if chars in cls:
            cls = cls.replace(chars, "", 1)
            one.append(singular)
            many.append(plural)
    rest = re.sub(r"\\(.)", r"\1", cls)
    one.extend(rest)
    many.extend(rest)
    return one, many


def _or(words: Sequence[str]) -> str:
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} or {words[-1]}"


def _at_path(root: etree._Element, path: str) -> etree._Element | None:
    """The element libxml2 names by ``path`` (``/*/*[3]``, ``/p:pxml/p:state[2]``), or None.

    libxml2 writes ``*`` for an element in a default namespace, counting every
    element sibling; a name (``p:state``) counts the siblings of that name.
    """
    steps = path.split("/")[1:]
    if not steps:
        return None
    el: etree._Element | None = root
    for depth, step in enumerate(steps):
        m = re.compile(_STEP).fullmatch(step)
        if m is None or el is None:
            return None
        pos = int(m.group("pos") or 1) - 1
        if depth == 0:
            if pos:
                return None
            continue
        name = m.group("name").rpartition(":")[2]
        same = (c for c in el if is_element(c) and (name == "*" or local_name(c) == name))
        el = next((c for i, c in enumerate(same) if i == pos), None)
    return el
