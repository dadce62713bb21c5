"""Secure loading: exact positions in linear time, bounded reports, regular files only."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from prima import xmlio
from prima.dsl import check_document, check_file
from prima.errors import DocumentError, Problem, Severity
from prima.xmlio import (
    MAX_BYTES,
    MAX_PROBLEMS,
    XMLSCHEMA_NODES,
    limit,
    parse_xml,
    read_source,
    unsaved,
)
from tests.work import bytecodes, growth

HEAD = '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t">\n'


def _doc(text: str) -> tuple[object, list[Problem]]:
    return check_document(text.encode(), "t.pxml")


# ---------------------------------------------------------------- positions

@pytest.mark.parametrize("raw, index, col", [
    ("abc", 2, 9),
    ("&amp;&lt;x", 2, 16),          # an entity reference is one character
    ("&#x41;&#66;x", 2, 18),        # so is a character reference
    ("&quot;", 1, 13),              # just past the end
])
def test_attribute_positions_count_references_as_one_character(raw: str, index: int,
                                                               col: int) -> None:
    doc = parse_xml(f'<a v="{raw}"/>'.encode(), "x", DocumentError)
    assert doc.where.attribute(doc.root, "v", index) == (1, col)


def test_text_positions_skip_cdata_markup_and_crlf() -> None:
    data = b"<a>x&amp;<![CDATA[<&>]]>\r\nyz<b/></a>"
    doc = parse_xml(data, "x", DocumentError)
    assert doc.root.text == "x&<&>\nyz"
    assert doc.where.text(doc.root, 0) == (1, 4)   # x
    assert doc.where.text(doc.root, 2) == (1, 19)  # < inside the CDATA section
    assert doc.where.text(doc.root, 6) == (2, 1)   # y, after the CR LF
    assert doc.where.text(doc.root, 7) == (2, 2)   # z


@pytest.mark.pure  # (it counts xmlio's bytecodes: compiled, it runs none)
def test_locating_many_faults_in_one_long_text_is_linear() -> None:
    # 20,000 faults, 100 to a line: finding a fault's line is a binary search, not a
    # walk from the start of the text.
    def faults(chains: int) -> list[Problem]:
        steps = ", ".join("Speak(x)" for _ in range(100))
        body = "\n".join(f"<chain>{steps}</chain>" for _ in range(chains))
        return _doc(f'{HEAD}<state id="s" initial="true"><entry>{body}</entry></state>'
                    "</pxml>")[1]
    problems = faults(200)
    assert len(problems) == MAX_PROBLEMS + 1
    assert problems[-1].message == "... and 19,950 more problems (a file reports at most 50)"
    assert growth(faults, 10, 200, only=xmlio.__file__) < 1.2


def test_a_problem_on_a_very_long_line_has_no_caret_line() -> None:
    filler = "x" * 2_000
    _d, [problem] = _doc(f'{HEAD}<state id="s" initial="true"><entry>'
                         f'<log text="{filler}{{1 +}}"/></entry></state></pxml>')
    assert "ends too early" in problem.message and problem.source == ""
    _d, [problem] = _doc(f'{HEAD}<state id="s" initial="true"><entry>\n'
                         '<log text="{1 +}"/></entry></state></pxml>')
    assert problem.source == '<log text="{1 +}"/></entry></state></pxml>'


# ---------------------------------------------------------------- bounded reports

def test_limit_keeps_the_first_problems_and_counts_the_rest() -> None:
    found = [Problem("f", i, 1, Severity.WARNING, "w") for i in range(1, 61)]
    kept = limit(found, "f")
    assert kept[:MAX_PROBLEMS] == found[:MAX_PROBLEMS]
    assert str(kept[-1]) == "f:1:1: warning: ... and 10 more problems (a file reports at most 50)"
    assert limit(found[:MAX_PROBLEMS], "f") == found[:MAX_PROBLEMS]
    assert limit(found[:51], "f", total=12_345)[-1].message.startswith("... and 12,295 more")
    assert limit(found[:51], "f", total=12_345)[-1].severity is Severity.ERROR


def test_schema_faults_of_a_large_document_are_reported_by_libxml2_quickly() -> None:
    attrs = " ".join(f'a{i}="x"' for i in range(40_000))
    text = f'{HEAD}<state id="s" initial="true" {attrs}/></pxml>'
    problems: list[Problem] = []
    # about 60 bytecodes an attribute (the scan for positions); xmlschema runs thousands
    assert bytecodes(lambda: problems.extend(_doc(text)[1])) < 200 * 40_000
    assert len(problems) == MAX_PROBLEMS + 1
    assert problems[0].message == "<state>: attribute 'a0' is not allowed here"
    assert (problems[0].line, problems[0].col) == (2, 34)
    assert problems[-1].message.startswith("... and 39,950 more problems")


def test_large_documents_get_the_same_wording_as_small_ones() -> None:
    # Above XMLSCHEMA_NODES, libxml2's errors are reworded like xmlschema's.
    filler = '<var name="v"/>\n' * XMLSCHEMA_NODES
    faults = ('<var name="1x"/>\n<state id="s" initial="maybe" bogus="1"/>\n'
              '<state id="t"><entry><zz/></entry></state>\n<state/>\n'
              '<state id="u"><entry><chain order="soon">Speak(text="x")</chain></entry></state>\n')
    small = _doc(f"{HEAD}{faults}</pxml>")[1]
    large = _doc(f"{HEAD}{filler}{faults}</pxml>")[1]
    shift = XMLSCHEMA_NODES
    assert [(p.line, p.col, p.message) for p in small] == [
        (2, 12, "<var>: attribute name='1x': must be a name: a letter or _, then letters, "
                "digits or _"),
        (3, 24, "<state>: attribute initial='maybe': must be true or false"),
        (3, 38, "<state>: attribute 'bogus' is not allowed here"),
        (4, 22, "<zz> is not allowed inside <entry>"),
        (5, 1, "<state>: missing required attribute 'id'"),
        (6, 36, "<chain>: attribute order='soon': must be 'after-latest' or 'asap'"),
    ]
    assert [(p.line - shift, p.col, p.message) for p in large] == [
        (p.line, p.col, p.message) for p in small]


def test_fifty_thousand_unknown_elements_are_quick() -> None:
    body = "<unknown/>\n" * 50_000
    text = f'{HEAD}<state id="s" initial="true"/>\n{body}</pxml>'
    problems: list[Problem] = []
    # about 80 bytecodes an element; xmlschema runs thousands
    assert bytecodes(lambda: problems.extend(_doc(text)[1])) < 200 * 50_000
    assert [p.message for p in problems] == ["<unknown> is not allowed at the top of the document"]


# ---------------------------------------------------------------- reading

def test_a_named_pipe_is_refused_without_blocking(tmp_path: Path) -> None:
    fifo = tmp_path / "app.pxml"
    os.mkfifo(fifo)
    [problem] = check_file(fifo)
    assert (problem.line, problem.col) == (1, 1)
    assert problem.message == "a named pipe: PRIMA reads only regular files"


def test_a_directory_or_device_is_refused(tmp_path: Path) -> None:
    with pytest.raises(DocumentError, match="a directory: PRIMA reads only regular files"):
        read_source(tmp_path, DocumentError)
    with pytest.raises(DocumentError, match="a device: PRIMA reads only regular files"):
        read_source(Path(os.devnull), DocumentError)


def test_reading_stops_after_the_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A file that grows after its size was checked is still cut at the limit.
    path = tmp_path / "big.pxml"
    path.write_bytes(b" " * (MAX_BYTES + 100))
    real_stat = os.stat

    def small_stat(p: object, *args: object, **kwargs: object) -> os.stat_result:
        info = real_stat(p)  # type: ignore[arg-type]
        return os.stat_result((info.st_mode, *info[1:6], 10, *info[7:]))

    monkeypatch.setattr(os, "stat", small_stat)
    with pytest.raises(DocumentError, match="file is more than 1048576 bytes"):
        read_source(path, DocumentError)


@pytest.mark.parametrize("declared", ["ISO-8859-1", "UTF-16", "cp500"])
def test_only_utf8_is_read(declared: str) -> None:
    data = f'<?xml version="1.0" encoding="{declared}"?>\n<pxml/>'.encode()
    with pytest.raises(DocumentError) as info:
        parse_xml(data, "x", DocumentError)
    [problem] = info.value.problems
    assert (problem.line, problem.col) == (1, 31)
    assert problem.message == f"PRIMA documents must be UTF-8, not {declared!r}"


def test_a_utf8_byte_order_mark_does_not_shift_columns() -> None:
    doc = parse_xml(b'\xef\xbb\xbf<a v="x"/>', "x", DocumentError)
    assert doc.where.attribute(doc.root, "v") == (1, 7)


def test_prima_schemas_have_no_identity_constraints() -> None:
    # the ASCII selector check used while xmlschema builds them relies on it
    schemas = Path(__file__).resolve().parents[2] / "schemas"
    for xsd in schemas.glob("*.xsd"):
        text = xsd.read_text(encoding="utf-8")
        assert not any(f"<xs:{c}" in text for c in ("unique", "key", "keyref", "selector")), xsd


def test_the_ascii_selector_check_is_put_back(monkeypatch: pytest.MonkeyPatch) -> None:
    from xmlschema.validators.identities import XsdFieldSelector, XsdSelector

    from prima.xmlio import _ascii_selector_checks

    for cls in (XsdSelector, XsdFieldSelector):  # as before xmlschema's first need
        monkeypatch.setattr(cls, "pattern", None)
    with _ascii_selector_checks():
        for cls, good in ((XsdSelector, ".//xs:element|xs:attribute"), (XsdFieldSelector, "@name")):
            assert cls.pattern is not None and cls.pattern.fullmatch(good), cls
        assert not XsdSelector.pattern.match("@name")  # the same language, over ASCII names
    assert XsdSelector.pattern is None and XsdFieldSelector.pattern is None


# ---------------------------------------------------------------- plain words

_BAD_VALUES = [
    ("scenario.xsd",
     '<scenario xmlns="urn:prima:scenario:1" name="bad name!" until="-5" seed="x" rate="0">'
     '<map href=""/><robot x="1" y="1" heading="abc"/>'
     '<user x="1" y="1" speed="0"><touch at="-1"/></user></scenario>',
     ["<scenario>: attribute name='bad name!': must be a name: a letter or _, then letters, "
      "digits, _, . or -",
      "<scenario>: attribute until='-5': must be more than 0",
      "<scenario>: attribute seed='x': must be a whole number, 0 or more",
      "<scenario>: attribute rate='0': must be a whole number, 1 or more",
      "<map>: attribute href='': must not be empty",
      "<robot>: attribute heading='abc': must be a number written like 12 or -0.5 (no "
      "exponent: not 1e3)",
      "<user>: attribute speed='0': must be more than 0",
      "<touch>: attribute at='-1': must be 0 or more"]),
    ("map.xsd",
     '<map xmlns="urn:prima:map:1" name="m m"><place name="a" x="0" y="0" kind="castle"/>'
     '<wall x1="0" y1="0" x2="1" y2="1" thickness="-1"/></map>',
     ["<map>: attribute name='m m': must be a name: a letter or _, then letters, digits, _, . "
      "or -",
      "<place>: attribute kind='castle': must be one of 'entrance', 'hall', 'corridor', "
      "'corner', 'door', 'room', 'poster', 'panel', 'shelf', 'counter' or 'point'",
      "<wall>: attribute thickness='-1': must be more than 0"]),
    ("pxml.xsd",
     '<pxml xmlns="urn:prima:pxml:1" kind="xa" name="9bad"><var name="a-b"/>'
     '<stream hold="-1"><state id="s" initial="maybe"/></stream></pxml>',
     ["<pxml>: attribute kind='xa': must be 'fa' or 'ea'",
      "<pxml>: attribute name='9bad': must be a name: a letter or _, then letters, digits, _ "
      "or -",
      "<var>: attribute name='a-b': must be a name: a letter or _, then letters, digits or _",
      "<stream>: attribute hold='-1': must be more than 0",
      "<state>: attribute initial='maybe': must be true or false"]),
]


@pytest.mark.parametrize("xsd, text, expected", _BAD_VALUES, ids=[c[0] for c in _BAD_VALUES])
@pytest.mark.parametrize("by", ["xmlschema", "libxml2"])
def test_a_bad_value_says_in_plain_words_what_it_must_be(
        xsd: str, text: str, expected: list[str], by: str,
        monkeypatch: pytest.MonkeyPatch) -> None:
    # by the validator that refused it (a facet, a built-in type), with either validator
    # (libxml2 words large files' faults): no Decimal('0'), no pattern lists, no int()
    from prima import xmlio

    if by == "libxml2":
        monkeypatch.setattr(xmlio, "XMLSCHEMA_NODES", -1)
    doc = xmlio.parse_xml(text.encode(), "f.xml", DocumentError)
    assert [p.message for p in xmlio.validate(doc, xsd)] == expected


def test_a_pattern_of_other_shapes_is_quoted_as_written() -> None:
    from prima.xmlio import _pattern_words

    assert _pattern_words("[A-Z][A-Za-z0-9]*") == (
        "must be a name: an upper-case letter, then letters or digits")
    assert _pattern_words(r"\{.+\}") == r"must match the pattern \{.+\}"


def test_libxml2_bounds_read_as_xmlschema_holds_them() -> None:
    from prima.xmlio import _libxml2_value

    assert _libxml2_value("[facet 'minInclusive'] The value '-1' is less than the minimum "
                          "value allowed ('0.50')") == "must be 0.5 or more"
    assert _libxml2_value("[facet 'maxExclusive'] The value '9' must be less than '5'") == (
        "must be less than 5")


# ---------------------------------------------------------------- unsaved buffers

def test_unsaved_text_is_read_in_place_of_the_file_and_only_meanwhile(tmp_path: Path) -> None:
    """What ``prima lsp`` checks: an editor's buffer, by the file's path however it is
    written; the file itself is untouched, and read again once the context ends."""
    path = tmp_path / "a.pxml"
    path.write_bytes(b"on disk")
    with unsaved({path: b"in the editor"}):
        assert read_source(tmp_path / "." / "a.pxml", DocumentError) == b"in the editor"
        assert read_source(path, DocumentError) == b"in the editor"
        with pytest.raises(DocumentError):  # another file: the disk, as ever
            read_source(tmp_path / "b.pxml", DocumentError)
        with unsaved({path: b"x" * (MAX_BYTES + 1)}), pytest.raises(DocumentError) as info:
            read_source(path, DocumentError)
        assert "the limit is" in str(info.value)
    assert read_source(path, DocumentError) == b"on disk"
