"""What a run's words become on every surface it leaves behind (:mod:`prima.escape`): an
utterance cannot split a jsonl line, drive a terminal, end the page's script or be
typeset as mathematics."""

from __future__ import annotations

import io
import json
import re
from pathlib import Path

import pytest

from prima import escape
from prima.cli import main
from prima.escape import json_line, markup, script_json, terminal
from prima.judge import load_trace

MAP = '<map xmlns="urn:prima:map:1" name="m"><place name="a" x="0" y="0"/></map>\n'


def speaking(folder: Path, words: str, until: int = 6) -> Path:
    """A scenario whose EA says ``words`` (written as XML character references)."""
    said = "".join(f"&#x{ord(c):x};" if not c.isalnum() else c for c in words)
    said = (said.replace("&#x7b;", "{{").replace("&#x7d;", "}}").replace("&#x22;", '\\"')
            .replace("&#x5c;", "\\\\"))
    (folder / "map.xml").write_text(MAP)
    (folder / "ea.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"><state id="s" initial="true">'
        f'<entry><chain>Speak("{said}")</chain></entry></state></pxml>\n')
    scenario = folder / "s.xml"
    scenario.write_text(f'<scenario xmlns="urn:prima:scenario:1" name="s" until="{until}">'
                        '<map href="map.xml"/><apps ea="ea.pxml"/><robot place="a"/>'
                        "</scenario>\n")
    return scenario


def _cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    return main(list(argv), out=out, err=err), out.getvalue(), err.getvalue()


# the escaping itself: one function per medium

@pytest.mark.parametrize("text, shown", [
    ("a\nb", "a\\nb"), ("\x1b[31m", "\\x1b[31m"), ("\x9b31m", "\\x9b31m"), ("\x85", "\\x85"),
    ("\u2028\u2029", "\\u2028\\u2029"), ("\x7f", "\\x7f"), ("caf\u00e9 \u3042", "caf\u00e9 \u3042"),
    (b"n\xffe".decode("utf-8", "surrogateescape"), "n\\xffe"),
])
def test_terminal(text: str, shown: str) -> None:
    assert terminal(text) == shown


def test_terminal_escapes_no_character_python_calls_printable() -> None:
    """:func:`terminal` and :func:`~prima.escape.unshowable` return a printable text as it
    is, without the pattern's search: sound only while the pattern takes no printable
    character. Each of the 1,114,112 code points, alone and amid words, is shown as the
    pattern alone would show it."""
    pattern = re.compile(escape._TERMINAL)
    for code in range(0x110000):
        c = chr(code)
        if pattern.fullmatch(c):
            assert not c.isprintable(), f"U+{code:04X}"
    for c in "\n\x1b\x9b\u061c\u200f\u2028\u202e\u2069\udcff\x00":
        text = f"say {c} now"
        assert terminal(text) == pattern.sub(escape._escape_one, text) != text
        assert escape.unshowable(text) == c
    for text in ("caf\u00e9 \u3042", "a\u00a0b", "zero\u200bwidth", ""):
        assert terminal(text) == text and escape.unshowable(text) is None


@pytest.mark.parametrize("value", ["a\u2028b\u2029c\x85d", "<!--<script>", "</script>", "\u3042"])
def test_json_line_and_script_json_read_back_as_written(value: str) -> None:
    for dumped in (json_line([value]), script_json([value])):
        assert json.loads(dumped) == [value]
        assert len(dumped.splitlines()) == 1 and "\u2028" not in dumped and "\x85" not in dumped
    assert not set("<>&") & set(script_json([value]))


def test_markup() -> None:
    assert markup('<b>x</b> & "q"') == "&lt;b&gt;x&lt;/b&gt; &amp; &quot;q&quot;"


# each surface

@pytest.mark.parametrize("separator", ["\u2028", "\u2029", "\x85"])
def test_a_line_separator_in_an_utterance_keeps_the_trace_readable(
        tmp_path: Path, separator: str) -> None:
    scenario = speaking(tmp_path, f"one{separator}two")
    trace = tmp_path / "run.jsonl"
    assert main(["run", str(scenario), "--format", "jsonl", "--out", str(trace)]) == 0
    rows = load_trace(trace)
    assert any(r.get("text") == f"one{separator}two" for r in rows)
    assert separator not in trace.read_text(encoding="utf-8")
    assert _cli("judge", str(trace))[0] == 0


def test_a_forged_trace_drives_no_terminal_through_the_judges_findings(
        tmp_path: Path) -> None:
    forged = "\x1b]0;owned\x07\x1b[2J\u202e\x9b"
    rows = [{"t": 0, "seq": 0, "kind": "event", "text": "touched" + forged},
            {"t": 0, "seq": 1, "kind": "request", "app": "a" + forged, "ab": 1, "tree": 1,
             "command": "Speak", "text": "hi" + forged, "reactive": True,
             "reason": "new-tree", "devices": ["speaker"],
             "detail": {"command_id": 1, "at": forged + ".pxml:1:1"}},
            {"t": 100, "seq": 2, "kind": "start", "app": "a" + forged, "ab": 1, "tree": 1,
             "command": "Speak", "text": "hi" + forged, "devices": ["speaker"],
             "detail": {"command_id": 1}}]
    trace = tmp_path / f"{forged}.jsonl"
    trace.write_text("".join(json_line(r) + "\n" for r in rows), encoding="utf-8")
    status, out, _ = _cli("judge", str(trace))
    assert status == 1 and re.search(r"\n  late reactions +1  > max 0\n", out), out
    assert "seq 0 t=0 a\\x1b]0;owned\\x07\\x1b[2J\\u202e\\x9b touched" in out, out
    assert not re.search("[\x00-\x09\x0b-\x1f\x7f-\x9f\u202e]", out), out


def test_control_characters_reach_no_terminal(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "a\x7fb\x9b2Jc")  # (XML has no C0 control characters)
    status, out, _ = _cli("run", str(scenario))
    assert status == 0
    assert "a\\x7fb\\x9b2Jc" in out and not re.search("[\x00-\x09\x0b-\x1f\x7f-\x9f]", out)


def test_control_characters_reach_no_terminal_through_debug(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    scenario = speaking(tmp_path, "a\x9b2Jb")
    monkeypatch.setattr("prima.cli._debug._stdin", lambda: io.StringIO("break command Speak\n"
                                                                "continue\nwhere\napps\n"))
    status, out, _ = _cli("debug", str(scenario))
    assert status == 0 and "a\\x9b2Jb" in out
    assert not re.search("[\x00-\x09\x0b-\x1f\x7f-\x9f]", out)


def test_a_file_name_or_an_option_in_a_usage_error_reaches_no_terminal(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    forged = str(tmp_path / "\x1b]0;owned\x07\x1b[2J.xml")
    shown = forged.replace("\x1b", "\\x1b").replace("\x07", "\\x07")
    batch = ["--runs", "1", "--jitter", "0"]
    for argv in (["run", forged], ["validate", forged], ["judge", forged], ["test", forged],
                 ["debug", forged], ["sweep", forged, *batch],
                 ["check", "cafe", "--scenario", forged], ["run", forged, "--\x1b[2J"],
                 ["sweep", forged, *batch, "--executor", "\x9b2J"]):
        status, out, err = _cli(*argv)
        err += capsys.readouterr().err  # (argparse's own errors: to sys.stderr)
        assert status == 2 and out == "", (argv, err)
        assert not re.search("[\x00-\x09\x0b-\x1f\x7f-\x9f]", err), (argv, err)
        assert shown in err or "\\x1b[2J" in err or "\\x9b2J" in err, (argv, err)


def test_words_cannot_blank_the_review_page(tmp_path: Path) -> None:
    pytest.importorskip("plotly")
    scenario = speaking(tmp_path, "<!--<script> </script> and on")
    page = tmp_path / "s.html"
    assert _cli("show", str(scenario), "-o", str(page))[0] == 0
    text = page.read_text(encoding="utf-8")
    data = text[text.index("const PRIMA_SHOW = "):]
    data = data[: data.index("</script>")]
    assert "<" not in data and ">" not in data
    rows = json.loads(data.removeprefix("const PRIMA_SHOW = ").rstrip().removesuffix(";"))["rows"]
    assert any("<!--<script> </script>" in (row.get("text") or "") for row in rows)


def test_markup_in_a_forged_device_name_is_shown_as_itself(tmp_path: Path) -> None:
    pytest.importorskip("plotly")
    trace = tmp_path / "run.jsonl"
    trace.write_text(json.dumps({"t": 0, "seq": 0, "kind": "start", "app": "a", "ab": 1,
                                 "command": "Speak", "devices": ["<b>x</b>"]}) + "\n"
                     + json.dumps({"t": 1, "seq": 1, "kind": "end", "app": "a", "ab": 1,
                                   "command": "Speak", "devices": ["<b>x</b>"]}) + "\n")
    page = tmp_path / "run.html"
    assert _cli("show", str(trace), "-o", str(page))[0] == 0
    text = page.read_text(encoding="utf-8")
    # the label is the markup escaped ('&lt;b&gt;...'), its '&' written \u0026 in the JSON
    assert '"y":["\\u0026lt;b\\u0026gt;x\\u0026lt;/b\\u0026gt;"' in text
    assert '"y":["\\u003cb' not in text


@pytest.mark.parametrize("suffix", [".svg", ".png", ".pdf", ".gif"])
@pytest.mark.parametrize("words", ["$x^$", "$x^2$"])
def test_dollars_are_not_mathematics_in_pictures(tmp_path: Path, suffix: str,
                                                 words: str) -> None:
    pytest.importorskip("matplotlib")
    scenario = speaking(tmp_path, words).rename(tmp_path / f"a {words} b.xml")  # the title
    picture = tmp_path / f"${{y}}${suffix}"
    status, _, err = _cli("plot", str(scenario), "-o", str(picture))
    assert status == 0 and "Traceback" not in err, err
    if suffix == ".svg":
        assert f"a {words} b" in picture.read_text(encoding="utf-8")  # the title, as written
