"""Did you mean ...? for misspelt state names, element names and command-line options,
as misspelt Commands already had."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from prima.cli import main
from prima.suggest import similar

PXML = ('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t">{}</pxml>\n')


def _validate(tmp_path: Path, body: str) -> str:
    path = tmp_path / "t.pxml"
    path.write_text(PXML.format(body))
    out = io.StringIO()
    main(["validate", str(path)], out=out, err=io.StringIO())
    return out.getvalue()


@pytest.mark.parametrize("name, names, meant", [
    ("guid", ["asking", "guide"], "guide"), ("b", ["a", "bb"], None), ("GUIDE", ["guide"], "guide"),
    ("gudie", ["guide"], "guide"), ("far", ["guide"], None),
])
def test_similar(name: str, names: list[str], meant: str | None) -> None:
    assert similar(name, names) == meant


def test_a_misspelt_state_name(tmp_path: Path) -> None:
    said = _validate(tmp_path, '<state id="guide" initial="true"><entry><goto state="gide"/>'
                               "</entry></state>")
    assert "no state has the id 'gide'; did you mean 'guide'?" in said, said


def test_a_misspelt_element_name(tmp_path: Path) -> None:
    said = _validate(tmp_path, '<stat id="s" initial="true"/><state id="t" initial="true"/>')
    assert "<stat> is not allowed at the top of the document; did you mean <state>?" in said


@pytest.mark.parametrize("argv, hint", [
    (["run", "x.xml", "--fomat", "jsonl"], "(--fomat: did you mean --format?)"),
    (["validate", "apps", "-robot", "r.xml"], "(-robot: did you mean --robot?)"),
    (["judge", "x.jsonl", "--max-lates=2"], "(--max-lates: did you mean --max-late?)"),
])
def test_a_misspelt_option(argv: list[str], hint: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"prima {argv[0]}: error: unrecognized arguments: " in err and hint in err, err
