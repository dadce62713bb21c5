"""A forgiving reading of XML text as it is being typed: tags, attributes, where the
cursor is.

The language server answers about a buffer that is often not well formed (a tag
half written, a quote not yet closed), so it never parses it with an XML parser
for completion, hover or go-to-definition: one pass of regular expressions finds
every start tag with its attributes and every end tag, an element stack pairs
them as well as it can, and :func:`locate` says what an offset is in. Offsets
are Python string indices (code points) into the text.
"""

from __future__ import annotations

import enum
import html
import re
from dataclasses import dataclass

__all__ = ["Attr", "Spot", "Tag", "Where", "XmlText", "first_tag", "locate", "rescan", "scan"]

_MARKUP = re.compile(r"<!--.*?(?:-->|\Z)|<\?.*?(?:\?>|\Z)|<!\[CDATA\[.*?(?:\]\]>|\Z)"
                     r"|<!.*?(?:>|\Z)|</(?P<end>[^\s<>]*)[^<>]*>?|<(?P<start>[^\s<>/!?]*)", re.S)
_ATTR = re.compile(r"""\s*(?P<name>[^\s=<>/"']+)"""
                   r"""(?:\s*=\s*(?:"(?P<dq>[^"<]*)"?|'(?P<sq>[^'<]*)'?))?""")
_TAG_END = re.compile(r"\s*(/?>)?")
_WHOLE_TAG = re.compile(r"""<[^\s<>/!?]*(?P<attrs>(?:\s+[^\s=<>/"']+\s*=\s*"""
                        r"""(?:"[^"<]*"|'[^'<]*'))*)\s*(?P<close>/?>)""")
"""A start tag written whole: every attribute with a quoted value, then ``>`` or ``/>``."""


@dataclass
class Attr:
    """An attribute as written (its value undecoded; ``value_end`` is where the value
    stops, before its closing quote or where the text stops)."""

    name: str
    name_start: int
    value_start: int
    """-1: no value written yet."""
    value_end: int
    raw: str

    @property
    def value(self) -> str:
        """The value as XML reads it (entities decoded)."""
        return html.unescape(self.raw)

    @property
    def name_end(self) -> int:
        return self.name_start + len(self.name)


class Tag:
    """A start tag (and the element it opens). Its attributes are read from the text on
    first need (a document's tags are many; most requests look at a few)."""

    __slots__ = ("_attrs", "_span", "children", "closed", "content_end", "empty", "end", "name",
                 "parent", "raw_name", "start")

    def __init__(self, name: str, start: int, end: int, closed: bool, empty: bool,
                 attrs: list[Attr] | tuple[str, int, int], raw_name: str = "") -> None:
        self.name = name
        """Its local name (a prefix dropped)."""
        self.start = start
        """Offset of its ``<``."""
        self.end = end
        """Offset just after its ``>`` (or where it stops, when not closed)."""
        self.closed = closed
        self.empty = empty
        self._attrs: list[Attr] | None = attrs if isinstance(attrs, list) else None
        self._span = attrs if isinstance(attrs, tuple) else None
        """(source, start, end) of attributes not read yet."""
        self.parent: Tag | None = None
        self.content_end = -1
        """Where its content ends (its end tag's ``<``; the text's end if never closed)."""
        self.children: list[Tag] = []
        self.raw_name = raw_name

    @property
    def attrs(self) -> list[Attr]:
        if self._attrs is None:
            source, start, end = self._span or ("", 0, 0)
            self._attrs = _attributes(source, start, end)[0]
            self._span = None
        return self._attrs

    @property
    def name_start(self) -> int:
        return self.start + 1

    @property
    def name_end(self) -> int:
        return self.start + 1 + len(self.raw_name)

    def attr(self, name: str) -> Attr | None:
        return next((a for a in self.attrs if a.name == name), None)

    def get(self, name: str, default: str = "") -> str:
        found = self.attr(name)
        return default if found is None else found.value

    def path(self) -> list[str]:
        """The names of the elements from the root down to this one."""
        out: list[str] = []
        tag: Tag | None = self
        while tag is not None:
            out.append(tag.name)
            tag = tag.parent
        return out[::-1]

    def text(self, source: str) -> tuple[int, str]:
        """Its text content before its first child tag or comment: where it starts,
        and the text as written (undecoded)."""
        if self.empty or not self.closed:
            return self.end, ""
        stop = source.find("<", self.end)
        stop = len(source) if stop < 0 or stop > self.content_end >= 0 else stop
        return self.end, source[self.end:stop]


class Where(enum.Enum):
    """What an offset is in."""

    TAG_NAME = "tag-name"
    END_TAG_NAME = "end-tag-name"
    ATTR_NAME = "attr-name"
    ATTR_VALUE = "attr-value"
    TEXT = "text"
    OTHER = "other"
    """A comment, a processing instruction, a declaration."""


@dataclass
class Spot:
    """What an offset is in: a tag's name, an attribute's name or value, or the text
    content of ``tag`` (None: outside the root)."""

    where: Where
    tag: Tag | None
    attr: Attr | None = None
    index: int = 0
    """Within an attribute value or a text: the offset from its first character."""


@dataclass
class XmlText:
    """A buffer read: its tags in document order."""

    source: str
    tags: list[Tag]
    ends: list[tuple[int, int, str]]
    """End tags: (start, end, name)."""
    others: list[tuple[int, int]]
    """Comments, processing instructions, CDATA sections, declarations."""

    @property
    def root(self) -> Tag | None:
        return next((t for t in self.tags if t.parent is None), None)

    def named(self, name: str) -> list[Tag]:
        return [t for t in self.tags if t.name == name]


def _local(name: str) -> str:
    return name.rpartition(":")[2]


def _attributes(source: str, pos: int, stop: int | None = None) -> tuple[list[Attr], int]:
    """The attributes written from ``pos`` (up to ``stop``), and where they end."""
    attrs: list[Attr] = []
    while True:
        m = _ATTR.match(source, pos) if stop is None else _ATTR.match(source, pos, stop)
        if not m or m.end() == pos:
            break
        if m.group("dq") is not None or m.group("sq") is not None:
            group = "dq" if m.group("dq") is not None else "sq"
            attrs.append(Attr(m.group("name"), m.start("name"), m.start(group), m.end(group),
                              m.group(group)))
        else:
            attrs.append(Attr(m.group("name"), m.start("name"), -1, -1, ""))
        pos = m.end()
    return attrs, pos


def _start_tag(source: str, at: int, raw_name: str) -> Tag:
    whole = _WHOLE_TAG.match(source, at)
    if whole is not None:  # well formed: its attributes are read when asked for
        return Tag(_local(raw_name), at, whole.end(), True, whole.group("close") == "/>",
                   (source, whole.start("attrs"), whole.end("attrs")), raw_name)
    attrs, pos = _attributes(source, at + 1 + len(raw_name))
    end = _TAG_END.match(source, pos)
    closer = end.group(1) if end else None
    stop = end.end() if end else pos
    if closer is None:  # not closed: the tag stops where the next markup begins
        nxt = source.find("<", pos)
        stop = len(source) if nxt < 0 else nxt
        stop = max(stop, pos)
    return Tag(_local(raw_name), at, stop, closer is not None, closer == "/>", attrs, raw_name)


def scan(source: str) -> XmlText:
    """Every tag of ``source``, paired as well as the text allows."""
    tags: list[Tag] = []
    ends: list[tuple[int, int, str]] = []
    others: list[tuple[int, int]] = []
    stack: list[Tag] = []
    pos = 0
    while True:
        m = _MARKUP.search(source, pos)
        if m is None:
            break
        if m.group("start") is not None:
            tag = _start_tag(source, m.start(), m.group("start"))
            tag.parent = stack[-1] if stack else None
            if tag.parent is not None:
                tag.parent.children.append(tag)
            tags.append(tag)
            if tag.closed and not tag.empty:
                stack.append(tag)
            pos = max(tag.end, m.end())
        elif m.group("end") is not None:
            name = _local(m.group("end"))
            ends.append((m.start(), m.end(), name))
            for i in range(len(stack) - 1, -1, -1):
                if stack[i].name == name:
                    for open_tag in stack[i:]:
                        open_tag.content_end = m.start()
                    del stack[i:]
                    break
            pos = m.end()
        else:
            others.append((m.start(), m.end()))
            pos = m.end()
    for tag in stack:
        tag.content_end = len(source)
    return XmlText(source, tags, ends, others)


def rescan(old: XmlText, source: str) -> XmlText:
    """:func:`scan` of ``source``, a later version of ``old.source``; ``old`` is taken
    over (its tags move to the new text) when what changed is one run of text or one
    attribute's value that no markup character enters or leaves, which is what a
    keystroke mostly is: then only offsets move, and no tag is read again. Otherwise
    the text is scanned whole. Either way ``old`` must not be used again."""
    before = old.source
    start = _common_prefix(before, source)
    tail = _common_suffix(before, source, start)
    old_end, new_end = len(before) - tail, len(source) - tail
    removed, typed = before[start:old_end], source[start:new_end]
    if "<" in removed or "<" in typed:
        return scan(source)
    holder = _holder(old, start, old_end)
    if holder is None:
        return scan(source)
    tag, attr = holder
    if attr is not None:
        quote = before[attr.value_start - 1]
        if quote in removed or quote in typed or before[attr.value_end:attr.value_end + 1] != quote:
            return scan(source)
    _shift(old, source, old_end, len(source) - len(before), tag)
    return old


def _common_prefix(a: str, b: str) -> int:
    """How many first characters ``a`` and ``b`` share (compared in halves, in C)."""
    low, high = 0, min(len(a), len(b))
    while low < high:
        mid = (low + high + 1) // 2
        if a[low:mid] == b[low:mid]:
            low = mid
        else:
            high = mid - 1
    return low


def _common_suffix(a: str, b: str, prefix: int) -> int:
    """How many last characters ``a`` and ``b`` share, not counting into ``prefix``."""
    low, high = 0, min(len(a), len(b)) - prefix
    while low < high:
        mid = (low + high + 1) // 2
        if a[len(a) - mid:len(a) - low] == b[len(b) - mid:len(b) - low]:
            low = mid
        else:
            high = mid - 1
    return low


def _holder(old: XmlText, start: int, end: int) -> tuple[Tag | None, Attr | None] | None:
    """What the changed characters ``[start, end)`` of ``old.source`` lie in: a run of
    text between two pieces of markup (None, None), one attribute's value (its tag and
    it), or (None) anything else."""
    text = old.source
    for begin, stop in old.others:
        if begin < end and start < stop or (stop == start and not text.endswith(">", 0, stop)):
            return None
    for begin, stop, _name in old.ends:
        if begin < end and start < stop or (stop == start and not text.endswith(">", 0, stop)):
            return None
    at = _last_starting_before(old.tags, start)
    if at is None or at.end < start or (at.end == start and text.endswith(">", 0, at.end)):
        return None, None  # between markup (a tag ending in '>' examined nothing after it)
    if not at.closed or at.end <= end:
        return None
    for attr in at.attrs:
        if attr.value_start >= 0 and attr.value_start <= start and end <= attr.value_end:
            return at, attr
    return None


def _last_starting_before(tags: list[Tag], offset: int) -> Tag | None:
    """The last tag whose ``<`` is before ``offset``."""
    low, high = 0, len(tags)
    while low < high:
        mid = (low + high) // 2
        if tags[mid].start < offset:
            low = mid + 1
        else:
            high = mid
    return tags[low - 1] if low else None


def _shift(old: XmlText, source: str, at: int, by: int, holder: Tag | None) -> None:
    """Move everything from offset ``at`` of ``old`` on by ``by`` characters, into the
    new ``source`` (``holder``: the tag whose attribute value changed)."""
    for tag in old.tags:
        if tag is holder:
            tag.end += by
            if tag.content_end >= at:
                tag.content_end += by
            tag._attrs, tag._span = None, (source, tag.name_end, tag.end)
            continue
        moved = tag.start >= at
        if moved:
            tag.start += by
            tag.end += by
        if tag.content_end >= at:
            tag.content_end += by
        if tag._span is not None:
            _text, begin, stop = tag._span
            tag._span = (source, begin + by, stop + by) if moved else (source, begin, stop)
        elif tag._attrs is not None and moved:
            for attr in tag._attrs:
                attr.name_start += by
                if attr.value_start >= 0:
                    attr.value_start += by
                    attr.value_end += by
    old.ends = [(b + by, e + by, n) if b >= at else (b, e, n) for b, e, n in old.ends]
    old.others = [(b + by, e + by) if b >= at else (b, e) for b, e in old.others]
    old.source = source


def first_tag(source: str) -> Tag | None:
    """The first start tag of ``source`` (the root :func:`scan` finds), read alone."""
    pos = 0
    while True:
        m = _MARKUP.search(source, pos)
        if m is None:
            return None
        if m.group("start") is not None:
            return _start_tag(source, m.start(), m.group("start"))
        pos = m.end()


def _innermost(text: XmlText, offset: int) -> Tag | None:
    """The innermost element whose content holds ``offset``."""
    found: Tag | None = None
    for tag in text.tags:
        if tag.start > offset:
            break
        if tag.closed and not tag.empty and tag.end <= offset <= tag.content_end:
            found = tag
    return found


def locate(text: XmlText, offset: int) -> Spot:
    """What ``offset`` (a cursor: between two characters) is in."""
    for start, end in text.others:
        if start < offset < end:
            return Spot(Where.OTHER, None)
    for tag in text.tags:
        if tag.start > offset:
            break
        if not tag.start < offset <= tag.end or (tag.closed and offset == tag.end):
            continue
        if offset <= tag.name_end:
            return Spot(Where.TAG_NAME, tag, index=offset - tag.name_start)
        for attr in tag.attrs:
            if attr.value_start >= 0 and attr.value_start <= offset <= attr.value_end:
                return Spot(Where.ATTR_VALUE, tag, attr, offset - attr.value_start)
            if attr.name_start <= offset <= attr.name_end:
                return Spot(Where.ATTR_NAME, tag, attr, offset - attr.name_start)
        return Spot(Where.ATTR_NAME, tag, None)
    for start, end, _name in text.ends:
        if start < offset <= end:
            inner = _innermost(text, start)
            return Spot(Where.END_TAG_NAME, inner, index=offset - start - 2)
    inner = _innermost(text, offset)
    if inner is None:
        return Spot(Where.TEXT, None)
    return Spot(Where.TEXT, inner, index=offset - inner.end)
