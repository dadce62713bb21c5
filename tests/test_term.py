"""Colour on a terminal only, plain text to pipes and files; tables as wide as their
content, and as wide as the terminal where that helps (:mod:`prima.term`)."""

from __future__ import annotations

import io
import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import pytest

from prima.cli import main
from prima.judge import Report, Silence, Thresholds, format_table
from prima.term import BOLD, PLAIN, RED, Cell, Paint, columns, layout, wants_colour
from tests.test_escape import speaking

ROOT = Path(__file__).parents[1]
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"
BROKEN = ROOT / "tests" / "dsl" / "data" / "invalid" / "chain-unknown-argument.pxml"
SGR = re.compile(r"\x1b\[[0-9;]*m")
CONTROL = re.compile("[\x00-\x09\x0b-\x1f\x7f-\x9f]")
COLOUR_VARIABLES = ("NO_COLOR", "FORCE_COLOR", "CLICOLOR_FORCE", "TERM", "COLUMNS")


class _Stream(io.StringIO):
    def __init__(self, tty: bool) -> None:
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.mark.parametrize("when, env, tty, colour", [
    ("auto", {}, True, True),
    ("auto", {}, False, False),
    ("auto", {"NO_COLOR": "1"}, True, False),
    ("auto", {"NO_COLOR": ""}, True, True),  # (empty: as if not set)
    ("auto", {"FORCE_COLOR": "1"}, False, True),
    ("auto", {"CLICOLOR_FORCE": "1"}, False, True),
    ("auto", {"CLICOLOR_FORCE": "0"}, False, False),
    ("auto", {"NO_COLOR": "1", "FORCE_COLOR": "1"}, True, False),
    ("auto", {"TERM": "dumb"}, True, False),
    ("auto", {"TERM": "dumb", "FORCE_COLOR": "1"}, False, True),
    ("always", {"NO_COLOR": "1"}, False, True),
    ("never", {"FORCE_COLOR": "1"}, True, False),
])
def test_the_colour_rule(when: str, env: dict[str, str], tty: bool, colour: bool) -> None:
    assert wants_colour(_Stream(tty), when, env) is colour


def test_paint_escapes_words_before_it_colours_them() -> None:
    painted = Paint(True)("a\x1b]0;title\x07b", RED, BOLD)
    assert painted == "\x1b[31;1ma\\x1b]0;title\\x07b\x1b[0m"
    assert PLAIN("a\x1bb", RED) == "a\x1bb"  # no colour: the text as it is


def test_layout_sizes_columns_from_their_content_and_colour_moves_none() -> None:
    rows: list[list[str | Cell]] = [[Cell("name", (BOLD,)), Cell("n", (BOLD,))],
                                    ["a-very-long-application-name", "1"], ["b", "100"]]
    plain = layout(rows, right=(1,), indent="  ")
    assert plain == ["  name                           n",
                     "  a-very-long-application-name   1",
                     "  b                            100"]
    assert [SGR.sub("", row) for row in layout(rows, right=(1,), indent="  ",
                                               paint=Paint(True))] == plain
    assert layout([["a\nb", "c"]]) == ["a\\nb c"]  # a name cannot break a row


def test_columns_is_the_terminals_width_and_none_for_a_pipe(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "123")
    assert columns(_Stream(tty=False)) is None
    assert columns(_Stream(tty=True)) == 123


# ------------------------------------------------------------ a terminal and a pipe

def _environment(**more: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in COLOUR_VARIABLES}
    return {**env, "PYTHONPATH": str(ROOT), "COLUMNS": "60", **more}


def on_a_terminal(*argv: str, **env: str) -> str:
    """What ``prima ARGV`` shows on a terminal (a pseudo-terminal: standard output and
    standard error both)."""
    main_end, child_end = pty.openpty()
    child = subprocess.Popen([sys.executable, "-m", "prima", *argv], stdin=subprocess.DEVNULL,
                             stdout=child_end, stderr=child_end, cwd=ROOT,
                             env=_environment(**env))
    os.close(child_end)
    chunks = []
    while True:
        try:
            chunk = os.read(main_end, 65536)
        except OSError:  # (the child has gone: EIO)
            break
        if not chunk:
            break
        chunks.append(chunk)
    child.wait(timeout=120)
    os.close(main_end)
    return b"".join(chunks).decode().replace("\r\n", "\n")


def piped(*argv: str, **env: str) -> str:
    """What ``prima ARGV`` writes to pipes (standard output, then standard error)."""
    done = subprocess.run([sys.executable, "-m", "prima", *argv], capture_output=True,
                          text=True, cwd=ROOT, env=_environment(**env), check=False)
    return done.stdout + done.stderr


PROGRESS = re.compile(r"\[[#.]+\] \d+/\d+ runs")
"""prima sweep's progress bar (redrawn in place on a terminal, a line a tenth else)."""


def _text(said: str) -> list[str]:
    """The lines of what a command said, in order (standard output and standard error
    mixed on a terminal: sorted), without the progress bar."""
    return sorted(line for line in said.splitlines() if line and not PROGRESS.fullmatch(line))


@pytest.mark.parametrize("argv", [
    ["validate", str(BROKEN)],
    ["judge", str(SAMPLE_03), "--max-late", "0"],
    ["run", str(SAMPLE_03), "--until", "30"],
    ["sweep", str(SAMPLE_03), "--runs", "2", "--jitter", "1", "--jobs", "1", "--worst", "0"],
    ["run", "no-such.xml"],
    ["run", "no-such.xml", "--format", "jsnol"],
], ids=["validate", "judge", "run", "sweep", "usage", "argparse"])
def test_colour_on_a_terminal_only(argv: list[str]) -> None:
    """The acceptance: the same command on a terminal and through a pipe: colour only on
    the terminal, and else the same text."""
    shown, plain = on_a_terminal(*argv), piped(*argv)
    assert SGR.search(shown) and "\x1b" not in plain
    assert _text(SGR.sub("", shown)) == _text(plain)
    assert "\x1b" not in on_a_terminal(*argv, NO_COLOR="1")
    assert "\x1b" not in on_a_terminal(*argv, TERM="dumb")
    assert "\x1b" not in on_a_terminal("--color", "never", *argv)
    assert SGR.search(piped(*argv, FORCE_COLOR="1"))
    assert SGR.search(piped(*argv[:1], "--color=always", *argv[1:]))


def test_what_is_coloured() -> None:
    said = on_a_terminal("validate", str(BROKEN))
    assert f"\x1b[1m{BROKEN}:5:14:\x1b[0m \x1b[31;1merror\x1b[0m: Turn needs the argument " \
           "'angle'" in said
    assert "\x1b[31;1m2 error(s)\x1b[0m" in said
    said = on_a_terminal("run", "no-such.xml")
    assert said == "prima run: \x1b[31;1merror\x1b[0m: no such file: no-such.xml\n"
    said = on_a_terminal("valdiate")
    assert "prima: \x1b[31;1merror\x1b[0m: argument COMMAND: invalid choice: " in said


def test_a_changed_golden_trace_is_coloured_as_git_colours_a_diff(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello there")
    (tmp_path / "s.golden.txt").write_text("  No.     time  R/U  app          behavior\n"
                                           "    0     0.00   R   t            waves\n")
    out = io.StringIO()
    assert main(["test", str(scenario), "--color", "always"], out=out, err=io.StringIO()) == 1
    shown = out.getvalue()
    assert shown.startswith(f"\x1b[31;1mdifferent\x1b[0m {scenario}\n")
    assert "\x1b[31m-    0     0.00   R   t            waves\x1b[0m\n" in shown
    assert "\x1b[32m+    0     0.00   R   t            loads ea.pxml (ea)\x1b[0m\n" in shown
    plain = io.StringIO()
    assert main(["test", str(scenario)], out=plain, err=io.StringIO()) == 1
    assert SGR.sub("", shown) == plain.getvalue()


def test_a_wide_terminal_shows_more_of_what_was_said() -> None:
    argv = ["judge", str(SAMPLE_03)]
    assert 'speech "Prof. Kido..."' in piped(*argv)
    assert 'speech "Prof. Kido..."' in SGR.sub("", on_a_terminal(*argv, COLUMNS="60"))
    wide = SGR.sub("", on_a_terminal(*argv, COLUMNS="200"))
    assert '''speech "Prof. Kidode's room."''' in wide
    assert max(len(line) for line in wide.splitlines() if line.startswith("  ")) <= 200


def test_colour_never_lets_words_drive_the_terminal(tmp_path: Path) -> None:
    # (XML has no C0 control characters: C1's CSI and OSC, as a terminal also reads them)
    scenario = speaking(tmp_path, "hi \x9d0;owned\x9c \x9b2J there")
    shown = {}
    for command in ("run", "judge"):
        out, err = io.StringIO(), io.StringIO()
        assert main([command, str(scenario), "--color", "always"], out=out, err=err) == 0
        shown[command] = out.getvalue() + err.getvalue()
        assert SGR.search(shown[command]), command
        assert not CONTROL.search(SGR.sub("", shown[command])), command
    assert 'Speak "hi \\x9d0;owned\\x9c \\x9b2J there"' in shown["run"]


# ------------------------------------------------------------ widths from content

def test_a_long_app_name_keeps_the_trace_in_line(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello there")
    document = tmp_path / "ea.pxml"
    document.write_text(document.read_text().replace('name="t"', 'name="a-very-long-app-name"'))
    out = io.StringIO()
    assert main(["run", str(scenario)], out=out, err=io.StringIO()) == 0
    rows = out.getvalue().splitlines()
    column = rows[0].index("behavior")
    assert rows[0].startswith("  No.     time  R/U  app")
    for row in rows[1:]:
        assert row[column - 1] == " " and row[column] != " ", row
    assert any("a-very-long-app-name loads ea.pxml" in row for row in rows)


def test_three_figure_counts_keep_the_summary_in_line() -> None:
    many = tuple(Silence(i, float(i), "a", 1.0) for i in range(120))
    reports = [Report("busy", 200.0, 500, Thresholds(), findings={"silences": many}),
               Report("calm-and-long-named", 200.0, 500, Thresholds())]
    table = format_table(reports)
    busy, calm = table.splitlines()[-2:]
    assert busy.index("stuck") == calm.index("stuck") and busy.index("silences 120") > 0
    assert calm.startswith("calm-and-long-named  reactions 0")
    coloured = format_table(reports, Paint(True))
    assert SGR.sub("", coloured) == table
    assert "\x1b[31;1m120\x1b[0m" in coloured and "\x1b[32mok\x1b[0m" in coloured
    assert "\x1b[31;1mFAIL: silences 120 > 0\x1b[0m" in coloured
