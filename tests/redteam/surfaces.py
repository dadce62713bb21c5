"""The red-team corpus, second part: what a run leaves behind (traces, pages, pictures,
sweeps, the debugger's prompt, the command line), attacked by a hostile EA author,
a forger of traces and a careless new user. Each row runs the command a user would
and says how it must end (:class:`~tests.redteam.runner.Exits`); none may end in a
traceback.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from tests.redteam.cases import MAP, ROOT, Make, made, write
from tests.redteam.runner import Accepted, Case, Exits

C1_OR_C0 = "[\x00-\x09\x0b-\x1f\x7f-\x9f]"
"""A raw control character in what a command prints (a newline aside)."""


def _speaker(words: str, name: str = "s.xml") -> Make:
    """A scenario whose EA says ``words`` (characters outside letters and digits written as
    character references), on a one-place map."""
    said = "".join(c if c.isalnum() or c == " " else f"&#x{ord(c):x};" for c in words)
    said = said.replace("&#x7b;", "{{").replace("&#x7d;", "}}").replace("&#x22;", '\\"') \
        .replace("&#x5c;", "\\\\")

    def make(folder: Path) -> Path:
        (folder / "map.xml").write_text(MAP)
        (folder / "ea.pxml").write_text(
            '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"><state id="s" initial="true">'
            f'<entry><chain>Speak("{said}")</chain></entry></state></pxml>\n')
        path = folder / name
        path.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="6">'
                        '<map href="map.xml"/><apps ea="ea.pxml"/><robot place="a"/>'
                        "</scenario>\n")
        return path
    return make


def _trace(*rows: dict[str, object] | str) -> Make:
    """A jsonl trace of these rows (a text row is written as it is)."""
    return write("run.jsonl", "".join((r if isinstance(r, str) else json.dumps(r)) + "\n"
                                      for r in rows))


START = {"t": 0, "seq": 0, "kind": "start", "app": "a", "ab": 1, "command": "Speak",
         "devices": ["speaker"], "text": "hi"}
END = {"t": 1, "seq": 1, "kind": "end", "app": "a", "ab": 1, "command": "Speak",
       "devices": ["speaker"]}


def _forged(**changes: object) -> Make:
    return _trace(START | changes, END)


def _trace_reads_back(path: Path) -> None:
    from prima.cli import main
    from prima.tracefile import load_trace

    trace = path.parent / "r.jsonl"
    rows = load_trace(trace)
    assert any("\u2028" in str(r.get("text")) for r in rows)
    assert main(["judge", str(trace)], out=open(os.devnull, "w"),  # noqa: SIM115
                err=open(os.devnull, "w")) == 0  # noqa: SIM115


def _page_keeps_its_player(path: Path) -> None:
    page = (path.parent / "p.html").read_text(encoding="utf-8")
    data = page[page.index("const PRIMA_SHOW = "):]
    assert "<" not in data[: data.index("</script>")]


def _not_utf8(folder: Path) -> Path:
    made_path = _speaker("hello")(folder)
    return made_path.rename(folder / os.fsdecode(b"run-\xff.xml"))


def _shipped_apps(_folder: Path) -> Path:
    return ROOT / "apps"


def _shipped_scenarios(_folder: Path) -> Path:
    return ROOT / "scenarios"


SURFACES = [
    # 1: the review page
    Case("show-comment-script", "an utterance '<!--<script>' that blanked prima show's page",
         _speaker("<!--<script> and </script>"), Exits(0, "prima show: wrote"),
         command=("show", "{path}", "-o", "{dir}/p.html"), then=_page_keeps_its_player,
         seconds=8),
    Case("show-forged-device", "markup in a forged trace's device name",
         _forged(devices=["<img src=x onerror=alert(1)>"]), Exits(0, "prima show: wrote"),
         command=("show", "{path}", "-o", "{dir}/p.html"), seconds=8),
    # 2: pictures
    Case("plot-mathtext-words", "an utterance '$x^$' that matplotlib's mathtext cannot parse",
         _speaker("costs $x^$ each"), Exits(0, "bars on"),
         command=("plot", "{path}", "-o", "{dir}/p.svg"), seconds=8),
    Case("plot-mathtext-name", "a scenario file named '$x^$' (the picture's title)",
         _speaker("hello", name="$x^$.xml"), Exits(0, "frames"),
         command=("plot", "{path}", "-o", "{dir}/p.gif"), seconds=15),
    # 3: line separators in the jsonl trace
    Case("jsonl-line-separator", "an utterance with U+2028, U+2029 and U+0085",
         _speaker("one\u2028two\u2029three\x85four"), Exits(0),
         command=("run", "{path}", "--format", "jsonl", "--out", "{dir}/r.jsonl"),
         then=_trace_reads_back, seconds=6),
    Case("text-trace-c1", "C1 control characters in an utterance (CSI clears a terminal)",
         _speaker("a\x9b2Jb\x7f"), Exits(0, "a\\x9b2Jb\\x7f", absent=C1_OR_C0),
         command=("run", "{path}")),
    # 4: forged and damaged traces
    Case("trace-detail-type", "a detail of the wrong type (a command id that is text)",
         _forged(detail={"command_id": "x"}),
         Exits(1, "run.jsonl:1:1: error: detail 'command_id' has the wrong type"),
         command=("judge", "{path}")),
    Case("trace-detail-show", "the same forged trace, shown",
         _forged(detail={"over": 5}), Exits(1, "detail 'over' has the wrong type"),
         command=("show", "{path}", "-o", "{dir}/p.html")),
    Case("trace-detail-plot", "a nested value where a detail is a text, drawn",
         _forged(detail={"args": {"a": [1]}}), Exits(1, "detail 'args' has the wrong type"),
         command=("plot", "{path}", "-o", "{dir}/p.svg")),
    Case("trace-nan-pose", "a pose of NaN (JSON that Python reads)",
         _forged(robot={"x": float("nan"), "y": 0, "heading": 0}),
         Exits(1, "field 'robot' needs numbers x, y and heading"), command=("judge", "{path}")),
    Case("trace-deep-json", "a trace line of 100,000 nested arrays",
         _trace("[" * 100_000 + "]" * 100_000), Exits(1, "run.jsonl:1:1: error: not a JSON"),
         command=("judge", "{path}")),
    Case("trace-long-line", "a trace line over 1 MiB",
         _trace(START | {"text": "a" * (1 << 20)}), Exits(1, "longer than 1,048,576"),
         command=("show", "{path}", "-o", "{dir}/p.html")),
    Case("trace-not-utf8", "a trace that is not UTF-8",
         write("run.jsonl", b'{"t": 0, "seq": 0, "kind": "log", "text": "\xff"}\n'),
         Exits(1, "cannot read the trace"), command=("plot", "{path}", "-o", "{dir}/p.png")),
    # 5: files and the debugger's prompt
    Case("out-not-utf8-name", "a scenario and an output file whose names are not UTF-8",
         made(_not_utf8), Exits(0, "page-\\xff.html"),
         command=("show", "{path}", "-o", "{dir}/" + os.fsdecode(b"page-\xff.html")),
         seconds=8),
    Case("out-full-disk", "an output on a full disk",
         _speaker("hello"), Exits(1, "prima run: error: cannot write /dev/full"),
         command=("run", "{path}", "--out", "/dev/full")),
    Case("out-not-writable", "an output where nothing can be written",
         _speaker("hello"), Exits(1, "prima run: error: cannot write /proc/version"),
         command=("run", "{path}", "--out", "/proc/version")),
    Case("debug-apostrophe", "an apostrophe at prima debug's prompt",
         _speaker("hello"), Exits(0, "cannot read that line: no closing quotation"),
         command=("debug", "{path}"), stdin="break app don't\nquit\n"),
    Case("debug-c1", "C1 control characters shown at prima debug's prompt",
         _speaker("a\x9b2Jb"), Exits(0, "a\\x9b2Jb", absent=C1_OR_C0),
         command=("debug", "{path}"), stdin="break command Speak\ncontinue\nwhere\nquit\n"),
    # 6: sweeps
    Case("sweep-many-jobs", "--jobs 1024 for 2 runs (one worker a run, no more)",
         _speaker("hello"), Exits(0, "2 of 2 runs"),
         command=("sweep", "{path}", "--runs", "2", "--jitter", "1", "--jobs", "1024",
                  "--worst", "0"), seconds=10),
    # 8: mistakes that passed in silence
    Case("debug-unknown-state", "a breakpoint on a state no application has",
         _speaker("hello"), Exits(0, "no state 'nope' in this run, no breakpoint set"),
         command=("debug", "{path}"), stdin="break state nope\nquit\n"),
    Case("cli-misspelt-option", "a misspelt option",
         _speaker("hello"), Exits(2),  # (argparse's message: tests/test_suggest.py)
         command=("run", "{path}", "--fomat", "jsonl")),
    Case("event-field-misspelt", "event.eror == null: a misspelt field, always true",
         write("t.pxml", '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"><state id="s" '
                         'initial="true"><entry><chain>hi: Speak("hi")</chain></entry>'
                         '<on-end of="hi" cond="event.eror == null"><log text="x"/></on-end>'
                         "</state></pxml>\n"),
         Exits(0, "warning: event field 'eror' is not one PRIMA's events carry"),
         command=("validate", "{path}")),
    Case("scenario-message-late", "a message timed after the run's end",
         write("s.xml", '<scenario xmlns="urn:prima:scenario:1" name="s" until="10">'
                        '<map href="map.xml"/><robot place="a"/>'
                        '<message at="30" sender="h" text="late"/></scenario>\n',
               lambda folder: (folder / "map.xml").write_text(MAP)),
         Exits(0, "warning: this <message> at 30 s is timed at or after the run ends"),
         command=("validate", "{path}")),
    # 10: prima live (its page's inputs: tests/test_live.py)
    Case("live-save-over-scenario", "prima live told to save its session over its scenario",
         _speaker("hello"), Exits(2, "is one of the session's inputs"),
         command=("live", "{path}", "--save", "{path}", "--port", "0"), seconds=6),
    Case("live-save-over-map", "prima live told to save its session over its map",
         _speaker("hello"), Exits(2, "is one of the session's inputs"),
         command=("live", "{path}", "--save", "{dir}/map.xml", "--port", "0"), seconds=6),
    # 9: the shipped files
    Case("validate-apps", "prima validate apps/ (FA7 is the guide robot's)",
         made(_shipped_apps), Accepted(), seconds=10),
    Case("validate-scenarios", "prima validate scenarios/",
         made(_shipped_scenarios), Accepted(), seconds=20),
]
