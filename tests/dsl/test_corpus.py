"""The document corpus: every invalid document fails exactly as annotated.

Each file in ``data/invalid`` ends with ``<!-- expect: LINE:COL: fragment -->``
comments, one per error it must produce; ``data/warnings`` files carry
``expect-warning`` comments; ``data/valid`` files must produce no problem at all.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
from lxml import etree

from prima.dsl import check_file, load_profile
from prima.errors import DocumentError, Problem, Severity
from prima.xmlio import MAX_BYTES, _parser, parse_xml, schema, verdict_schema

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).parents[2]
INVALID = sorted((DATA / "invalid").glob("*.pxml"))
VALID = sorted((DATA / "valid").glob("*.pxml")) + sorted((ROOT / "apps").rglob("*.pxml"))
WARNINGS = sorted((DATA / "warnings").glob("*.pxml"))
_EXPECT = re.compile(r"<!-- (expect|expect-warning): (\d+):(\d+): (.*?) -->")


def _expected(path: Path, kind: str) -> list[tuple[int, int, str]]:
    return [(int(line), int(col), frag) for k, line, col, frag
            in _EXPECT.findall(path.read_text(encoding="utf-8")) if k == kind]


def _found(problems: list[Problem], severity: Severity) -> list[Problem]:
    return [p for p in problems if p.severity is severity]


def _assert_matches(problems: list[Problem], expected: list[tuple[int, int, str]]) -> None:
    assert expected, "the test file has no expectation comments"
    assert len(problems) == len(expected), "\n".join(str(p) for p in problems)
    found = sorted(problems, key=lambda p: (p.line, p.col))
    for (line, col, fragment), problem in zip(sorted(expected), found, strict=True):
        assert (problem.line, problem.col) == (line, col), str(problem)
        assert fragment in problem.message, str(problem)


def test_corpus_is_large_enough() -> None:
    assert len(INVALID) >= 30


@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.stem)
def test_invalid_document_reports_exact_errors(path: Path) -> None:
    problems = check_file(path)
    _assert_matches(_found(problems, Severity.ERROR), _expected(path, "expect"))
    assert all(p.file == str(path) for p in problems)


@pytest.mark.parametrize("path", WARNINGS, ids=lambda p: p.stem)
def test_warnings_are_reported_without_errors(path: Path) -> None:
    problems = check_file(path)
    assert not _found(problems, Severity.ERROR)
    _assert_matches(_found(problems, Severity.WARNING), _expected(path, "expect-warning"))


ROBOT_OF = {"fa7-spotlight": ROOT / "robots" / "guide-robot.xml"}
"""Shipped applications written for a robot other than the default home robot."""


@pytest.mark.parametrize("path", VALID, ids=lambda p: p.stem)
def test_valid_document_has_no_problem(path: Path) -> None:
    robot = ROBOT_OF.get(path.stem)
    assert check_file(path, load_profile(robot) if robot else None) == []


def _schema_elements(xsd: Path) -> set[str]:
    tree = etree.parse(str(xsd))
    ns = {"xs": "http://www.w3.org/2001/XMLSchema"}
    return {e.get("name") for e in tree.iterfind(".//xs:element[@name]", ns)}


def test_valid_corpus_uses_every_element() -> None:
    used: set[str] = set()
    for path in VALID:
        used |= {etree.QName(e).localname for e in etree.parse(str(path)).iter(etree.Element)}
    assert _schema_elements(ROOT / "schemas" / "pxml.xsd") - used == set()


@pytest.mark.skipif(shutil.which("xmllint") is None, reason="xmllint is not installed")
@pytest.mark.parametrize("path", VALID, ids=lambda p: p.stem)
def test_libxml2_accepts_valid_documents(path: Path) -> None:
    result = subprocess.run(
        ["xmllint", "--noout", "--schema", str(ROOT / "schemas" / "pxml.xsd"), str(path)],
        capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr


@pytest.mark.skipif(shutil.which("xmllint") is None, reason="xmllint is not installed")
@pytest.mark.parametrize("name", ["schema-bad-kind", "schema-missing-attribute",
                                  "schema-unknown-element", "schema-number-argument"])
def test_libxml2_rejects_schema_errors_too(name: str) -> None:
    path = DATA / "invalid" / f"{name}.pxml"
    result = subprocess.run(
        ["xmllint", "--noout", "--schema", str(ROOT / "schemas" / "pxml.xsd"), str(path)],
        capture_output=True, text=True, check=False)
    assert result.returncode != 0


SCHEMA_LEVEL = [p for p in INVALID if p.stem.startswith("schema-")]


@pytest.mark.parametrize("path", VALID + SCHEMA_LEVEL, ids=lambda p: p.stem)
def test_both_validators_agree(path: Path) -> None:
    # libxml2 gives the verdict and xmlschema the diagnostics; they must agree.
    doc = parse_xml(path.read_bytes(), str(path), DocumentError)
    libxml2_says_valid = verdict_schema("pxml.xsd").validate(doc.root.getroottree())
    xmlschema_errors = list(schema("pxml.xsd").iter_errors(doc.root))
    assert libxml2_says_valid == (not xmlschema_errors)
    assert libxml2_says_valid == (path in VALID)


def test_oversized_document_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "big.pxml"
    path.write_text("<pxml>" + " " * MAX_BYTES + "</pxml>")
    [problem] = check_file(path)
    assert (problem.line, problem.col) == (1, 1)
    assert "the limit is" in problem.message


def test_parser_never_expands_entities_even_without_the_doctype_check(tmp_path: Path) -> None:
    # Defence in depth: even if the DOCTYPE pre-check were bypassed, the
    # parser itself neither reads files nor expands internal entities.
    secret = tmp_path / "secret.txt"
    secret.write_text("SECRET-MARKER")
    xxe = (f'<!DOCTYPE r [<!ENTITY s SYSTEM "{secret.as_uri()}">'
           '<!ENTITY l "lol"><!ENTITY l2 "&l;&l;&l;&l;">]><r>&s;&l2;</r>').encode()
    root = etree.fromstring(xxe, _parser())
    serialized = etree.tostring(root)
    assert b"SECRET-MARKER" not in serialized
    assert b"lol" not in serialized
    assert all(isinstance(child, etree._Entity) for child in root)  # left as references


def test_parse_error_carries_location() -> None:
    with pytest.raises(DocumentError) as info:
        parse_xml(b"<a>\n  <b></c>\n</a>", "x.pxml", DocumentError)
    [problem] = info.value.problems
    assert (problem.file, problem.line) == ("x.pxml", 2)
    assert "mismatch" in problem.message


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le", "utf-32"])
def test_non_utf8_documents_cannot_smuggle_a_doctype(tmp_path: Path, codec: str) -> None:
    # In UTF-16 the bytes of "<!DOCTYPE" differ, and an attribute's entity
    # reference would be expanded by the parser: such files are refused outright.
    doc = ('<?xml version="1.0" encoding="UTF-16"?>\n'
           '<!DOCTYPE pxml [<!ENTITY hi "Hello from an entity">]>\n'
           '<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">'
           '<var name="x" expr="\'&hi;\'"/><state id="s" initial="true"/></pxml>')
    path = tmp_path / "smuggled.pxml"
    path.write_bytes(doc.encode(codec))
    [problem] = check_file(path)
    assert (problem.line, problem.col) == (1, 1) and "must be UTF-8" in problem.message
