"""The red-team corpus, second part: what a run leaves behind (traces, pages, pictures,
sweeps, the debugger's prompt, the command line), attacked by a hostile EA author,
a forger of traces and a careless new user. Each row runs the command a user would
and says how it must end (:class:`~tests.redteam.runner.Exits`); none may end in a
traceback.
"""

from __future__ import annotations

import json
import os
import socket
from collections.abc import Callable
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


def _placed_on_the_robot(folder: Path) -> Path:
    """The robot tracks a user who stands exactly on it and follows it."""
    (folder / "map.xml").write_text(MAP)
    (folder / "ea.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"><state id="s" initial="true">'
        "<entry><chain>TrackingHuman(1.0)</chain></entry></state></pxml>\n")
    path = folder / "s.xml"
    path.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="8">'
                    '<map href="map.xml"/><apps ea="ea.pxml"/><robot place="a"/>'
                    '<user x="0" y="0"><follow at="0" distance="1"/></user></scenario>\n')
    return path


def _forged_results(old: str, new: str) -> Make:
    """A sweep's results file (``r.jsonl``, of two runs of a scenario) whose first record
    has ``old`` replaced by ``new``."""
    def make(folder: Path) -> Path:
        from prima.cli import main

        path = _speaker("hello")(folder)
        results = folder / "r.jsonl"
        assert main(["sweep", str(path), "--runs", "2", "--jitter", "1", "--jobs", "1",
                     "--worst", "0", "--results", str(results)],
                    out=open(os.devnull, "w"), err=open(os.devnull, "w")) == 0  # noqa: SIM115
        head, first, *_ = results.read_text().splitlines()
        assert old in first, first
        results.write_text(f"{head}\n{first.replace(old, new, 1)}\n")
        return path
    return make


RESUME = ("sweep", "{path}", "--runs", "2", "--jitter", "1", "--jobs", "1", "--worst", "0",
          "--resume", "{dir}/r.jsonl")
"""Resume the sweep whose results ``_forged_results`` forged."""


_LISTENING: list[socket.socket] = []
"""Ports the cases listen on, kept open while the tests run (the children inherit them)."""


def _silent_port(folder: Path) -> Path:
    """A scenario, and a port (written in ``port``) that accepts connections and never
    answers: what a sweep takes for a Dask scheduler."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)
    _LISTENING.append(listener)
    (folder / "port").write_text(str(listener.getsockname()[1]))
    return _speaker("hello")(folder)


def _shipped_apps(_folder: Path) -> Path:
    return ROOT / "apps"


def _shipped_scenarios(_folder: Path) -> Path:
    return ROOT / "scenarios"


def _lsp_frame(message: dict[str, object]) -> bytes:
    body = json.dumps(message).encode()
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


_LSP_INIT = _lsp_frame({"jsonrpc": "2.0", "id": 1, "method": "initialize",
                        "params": {"processId": None, "rootUri": None, "capabilities": {}}})


# ------------------------------------------------------------ outputs: what they must not do

EARLIER = b"an earlier file the user made\n"
"""What is at an output's place before the command writes it."""

LONG = "x" * 300
"""A file name longer than any file system takes (255 bytes)."""


def _earlier(name: str, make: Make | None = None) -> Make:
    """``make``'s input (a scenario that speaks, by default) and ``EARLIER`` at ``name``."""
    def made_too(folder: Path) -> Path:
        path = (make or _speaker("hello"))(folder)
        (folder / name).write_bytes(EARLIER)
        return path
    return made_too


def _kept(name: str) -> Callable[[Path], None]:
    """The earlier file at ``name`` is byte for byte as it was, no part of the new one
    left beside it."""
    def check(path: Path) -> None:
        assert (path.parent / name).read_bytes() == EARLIER
        assert not list(path.parent.glob(".prima-*")), list(path.parent.iterdir())
    return check


def _inputs_intact(path: Path) -> None:
    """The scenario and the EA it runs are still themselves."""
    assert (path.parent / "s.xml").read_text().startswith("<scenario")
    assert (path.parent / "ea.pxml").read_text().startswith("<pxml")


def _mapped(name: str) -> Make:
    """A speaking scenario whose map file is named ``name``."""
    def make(folder: Path) -> Path:
        path = _speaker("hello")(folder)
        (folder / "map.xml").rename(folder / name)
        path.write_text(path.read_text().replace('href="map.xml"', f'href="{name}"'))
        return path
    return make


def _linked(kind: str) -> Make:
    """A speaking scenario and another name for it (a hard or a symbolic link)."""
    def make(folder: Path) -> Path:
        path = _speaker("hello")(folder)
        (os.link if kind == "hard" else os.symlink)(path, folder / "other.txt")
        return path
    return make


def _results_resumable(path: Path) -> None:
    """A results file a full disk stopped: its header and whole records, and no more than
    a last line cut short; with room again, ``--resume`` goes on from them."""
    import resource

    from prima.cli import main

    results = path.parent / "r.jsonl"
    lines = results.read_bytes().split(b"\n")
    assert json.loads(lines[0])["prima"] == "sweep results"
    kept = [json.loads(x)["run"] for x in lines[1:-1]]
    assert kept and kept == list(range(len(kept)))
    hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]
    resource.setrlimit(resource.RLIMIT_FSIZE, (hard, hard))  # room again
    quiet = open(os.devnull, "w")  # noqa: SIM115
    assert main(["sweep", str(path), "--runs", "6", "--jitter", "1", "--jobs", "1",
                 "--worst", "0", "--resume", str(results)], out=quiet, err=quiet) == 0
    again = results.read_text().splitlines()
    assert [json.loads(x)["run"] for x in again[1:]] == list(range(6))


def _said_and_cut(folder: Path) -> Path:
    """A forged trace: one utterance of 99,999 s (its ``duration`` result)."""
    start = START | {"command": "FaceHumanAndSpeak", "text": "hi there"}
    end = END | {"command": "FaceHumanAndSpeak", "t": 99_999,
                 "detail": {"result": "duration=99999"}}
    return _trace(start, end)(folder)


def _user_says(words: str) -> Make:
    """A scenario whose user says ``words`` at 1 s."""
    def make(folder: Path) -> Path:
        path = _speaker("hello")(folder)
        said = "".join(c if c.isalnum() or c == " " else f"&#x{ord(c):x};" for c in words)
        path.write_text(path.read_text().replace(
            '<robot place="a"/>', '<robot place="a"/><user place="a">'
            f'<say at="1" text="{said}"/></user>'))
        return path
    return make


def _failing(folder: Path) -> Path:
    """A scenario whose EA divides by zero once it has spoken."""
    path = _speaker("hello")(folder)
    (folder / "ea.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"><var name="x" expr="0"/>'
        '<state id="s" initial="true"><entry><request><speak text="hi"/></request>'
        '<assign name="x" expr="1 / 0"/></entry></state></pxml>\n')
    return path


def _controlled(folder: Path) -> Path:
    """A document with an error, its file's name holding an escape sequence."""
    path = folder / "bad\x1b[2J.pxml"
    path.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"/>\n')
    return path


def _worst_named_as_ea(folder: Path) -> Path:
    """A speaking scenario, and its EA also as s-run0-seed0.xml (a worst run's name)."""
    path = _speaker("hello")(folder)
    (folder / "s-run0-seed0.xml").write_bytes((folder / "ea.pxml").read_bytes())
    return path


def _golden_differs(folder: Path) -> Path:
    """A scenario named with an escape sequence, its golden trace out of date."""
    path = _speaker("hello")(folder).rename(folder / "s\x1b[2J.xml")
    (folder / "s\x1b[2J.golden.txt").write_text("an old trace\n")
    return path


_TAKES = {"run": ("{path}",), "show": ("{path}",), "plot": ("{path}",),
          "sweep": ("{path}", "--runs", "1", "--jitter", "0"),
          "check": ("{dir}/ea.pxml", "--scenario", "{path}", "--runs", "1")}
"""What each command is given besides an output (a command a user would type)."""


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
    Case("user-on-the-robot", "a user placed on the robot who follows it (distance 0)",
         _placed_on_the_robot, Exits(0, "follows the robot", absent="Error"),
         command=("run", "{path}"), seconds=6),
    Case("resume-count-huge", "--resume with a count of 10^400",
         _forged_results('"late": 0', '"late": 1' + "0" * 400),
         Exits(1, "r.jsonl:2:"), command=RESUME, seconds=6),
    Case("resume-counts-array", "--resume with counts that are not an object",
         _forged_results('"counts": {', '"counts": [], "x": {'),
         Exits(1, "field 'counts' must be an object"), command=RESUME, seconds=6),
    Case("resume-deep", "--resume with a record of 100,000 nested arrays",
         _forged_results('{"job": 0', "[" * 100_000 + "]" * 100_000 + '{"job": 0'),
         Exits(1, "nested more than 16 levels deep"), command=RESUME, seconds=6),
    Case("resume-lateness-soon", "--resume with a lateness of \"soon\"",
         _forged_results('"worst_lateness": 0.0', '"worst_lateness": "soon"'),
         Exits(1, "field 'worst_lateness' must be a number"), command=RESUME, seconds=6),
    Case("resume-lateness-missing", "--resume with a record without its worst_lateness",
         _forged_results('"worst_lateness": 0.0, ', ""),
         Exits(1, "field 'worst_lateness' is missing"), command=RESUME, seconds=6),
    Case("dask-silent-port", "--executor dask:// to a port that accepts and never answers",
         _silent_port, Exits(1, "did not answer within 0.5 s (PRIMA_DASK_CONNECT_TIMEOUT)"),
         command=("sweep", "{path}", "--runs", "2", "--jitter", "1", "--worst", "0",
                  "--executor", "dask://127.0.0.1:{port}"),
         env=(("PRIMA_DASK_CONNECT_TIMEOUT", "0.5"),), seconds=8),
    Case("dask-long-host", "--executor dask:// to a host name of 300 characters",
         _speaker("hello"), Exits(2, "the host name is 300 characters long"),
         command=("sweep", "{path}", "--runs", "2", "--jitter", "1", "--worst", "0",
                  "--executor", "dask://" + "a" * 300 + ":8786")),
    Case("check-place-unknown", "prima check of an EA that goes where a message says",
         write("ea.pxml", '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t">\n'
                          '<var name="goal" expr="\'\'"/>\n<on event="message">\n'
                          '<assign name="goal" expr="event.text"/>\n'
                          "<chain>TopologicalMove({goal})</chain></on>\n"
                          '<state id="s" initial="true"/></pxml>\n'),
         Exits(2, "ea.pxml:5:8: TopologicalMove goes to a place nobody can know"),
         command=("check", "{path}", "--fa", str(ROOT / "apps" / "fa" / "fa6-scheduler.pxml"),
                  "--robot", str(ROOT / "robots" / "home-robot.xml"), "--runs", "1"),
         seconds=6),
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
    # 10: an output that names an input is refused before anything runs
    Case("out-is-scenario", "prima run s.xml --out s.xml", _speaker("hello"),
         Exits(2, "s.xml is the scenario (", absent="Traceback"),
         command=("run", "{path}", "--out", "{path}"), then=_inputs_intact),
    Case("out-is-ea", "--out naming the EA the scenario runs", _speaker("hello"),
         Exits(2, "ea.pxml is an EA of s.xml ("),
         command=("run", "{path}", "--format", "jsonl", "--out", "{dir}/ea.pxml"),
         then=_inputs_intact),
    Case("out-is-map-another-way", "--out naming the map by another path", _speaker("hello"),
         Exits(2, "is the map of s.xml"),
         command=("run", "{path}", "--out", "{dir}/./sub/../map.xml")),
    Case("out-is-hard-link", "--out a hard link to the scenario", _linked("hard"),
         Exits(2, "other.txt is the scenario ("),
         command=("run", "{path}", "--out", "{dir}/other.txt"), then=_inputs_intact),
    Case("out-is-symlink", "--out a symbolic link to the scenario", _linked("symbolic"),
         Exits(2, "other.txt is the scenario ("),
         command=("run", "{path}", "--out", "{dir}/other.txt"), then=_inputs_intact),
    Case("show-out-is-scenario", "prima show s.xml -o s.xml", _speaker("hello"),
         Exits(2, "s.xml is the scenario ("), command=("show", "{path}", "-o", "{path}"),
         then=_inputs_intact),
    Case("show-out-is-trace", "prima show run.jsonl -o run.jsonl", _forged(),
         Exits(2, "run.jsonl is the trace shown ("), command=("show", "{path}", "-o", "{path}")),
    Case("plot-out-is-map", "a picture over the scenario's map (a map named m.svg)",
         _mapped("m.svg"), Exits(2, "m.svg is the map of s.xml ("),
         command=("plot", "{path}", "-o", "{dir}/m.svg")),
    Case("sweep-out-is-scenario", "prima sweep s.xml --out s.xml", _speaker("hello"),
         Exits(2, "s.xml is a file: the scenario ("),
         command=("sweep", "{path}", "--runs", "1", "--jitter", "0", "--out", "{path}"),
         then=_inputs_intact),
    Case("sweep-results-is-ea", "prima sweep --results over the EA", _speaker("hello"),
         Exits(2, "ea.pxml is an EA of s.xml ("),
         command=("sweep", "{path}", "--runs", "1", "--jitter", "0", "--results",
                  "{dir}/ea.pxml"), then=_inputs_intact),
    Case("sweep-worst-run-is-ea", "an EA named as a worst run would be, in --out",
         made(_worst_named_as_ea),
         Exits(2, "a worst run written there may be named s-run0-seed0.xml"),
         command=("sweep", "{path}", "--runs", "1", "--jitter", "0", "--ea",
                  "{dir}/s-run0-seed0.xml", "--out", "{dir}")),
    Case("check-junit-is-ea", "prima check ea.pxml --junit ea.pxml", _speaker("hello"),
         Exits(2, "ea.pxml is an EA checked ("),
         command=("check", "{dir}/ea.pxml", "--scenario", "{path}", "--junit",
                  "{dir}/ea.pxml"), then=_inputs_intact),
    Case("check-summary-is-scenario", "prima check --summary over its scenario",
         _speaker("hello"), Exits(2, "s.xml is a scenario checked ("),
         command=("check", "{dir}/ea.pxml", "--scenario", "{path}", "--summary", "{path}"),
         then=_inputs_intact),
    Case("check-results-is-ea", "prima check --results over the EA", _speaker("hello"),
         Exits(2, "ea.pxml is an EA checked ("),
         command=("check", "{dir}/ea.pxml", "--scenario", "{path}", "--results",
                  "{dir}/ea.pxml"), then=_inputs_intact),
    Case("check-two-outputs-one-file", "--junit and --summary naming one file",
         _speaker("hello"), Exits(2, "is also the --junit file"),
         command=("check", "{dir}/ea.pxml", "--scenario", "{path}", "--junit", "{dir}/o",
                  "--summary", "{dir}/o")),
    Case("test-update-golden-is-map", "prima test --update over the scenario's map",
         _mapped("s.golden.txt"), Exits(2, "s.golden.txt is the map of s.xml ("),
         command=("test", "{path}", "--update")),
    # 11: a write that fails half-way leaves the earlier file whole (a file size limit)
    Case("mcap-fails-midway", "an MCAP recording that cannot be written whole",
         _earlier("r.mcap"), Exits(1, "cannot write"), file_limit=4096,
         command=("run", "{path}", "--format", "mcap", "--out", "{dir}/r.mcap"),
         then=_kept("r.mcap"), seconds=6),
    Case("jsonl-fails-midway", "a jsonl trace that cannot be written whole",
         _earlier("r.jsonl"), Exits(1, "cannot write"), file_limit=512,
         command=("run", "{path}", "--format", "jsonl", "--out", "{dir}/r.jsonl"),
         then=_kept("r.jsonl")),
    Case("page-fails-midway", "a page that cannot be written whole", _earlier("p.html"),
         Exits(1, "cannot write"), file_limit=65536,
         command=("show", "{path}", "-o", "{dir}/p.html"), then=_kept("p.html"), seconds=8),
    Case("picture-fails-midway", "a picture that cannot be written whole", _earlier("p.png"),
         Exits(1, "cannot write"), file_limit=4096,
         command=("plot", "{path}", "-o", "{dir}/p.png"), then=_kept("p.png"), seconds=8),
    Case("golden-fails-midway", "a golden trace that cannot be written whole",
         _earlier("s.golden.txt"), Exits(1, "cannot write"), file_limit=64,
         command=("test", "{path}", "--update"), then=_kept("s.golden.txt")),
    Case("results-fails-midway", "a results file the disk fills under (the runs done kept)",
         _speaker("hello"), Exits(1, "; the batch stopped, the records of its first"),
         file_limit=1500,
         command=("sweep", "{path}", "--runs", "6", "--jitter", "1", "--jobs", "1",
                  "--worst", "0", "--results", "{dir}/r.jsonl"),
         then=_results_resumable, seconds=8),
    # 12: file-system errors on outputs are one line
    *(Case(f"name-too-long-{command}-{option.strip('-')}",
           f"a 300-character file name for prima {command} {option}", _speaker("hello"),
           Exits(1, f"prima {command}: error: cannot write "),
           command=(command, *_TAKES[command], option, "{dir}/" + LONG + suffix))
      for command, option, suffix in (
          ("run", "--out", ""), ("show", "-o", ".html"), ("plot", "-o", ".svg"),
          ("sweep", "--out", ""), ("sweep", "--results", ""), ("check", "--junit", ""),
          ("check", "--summary", ""), ("check", "--results", ""))),
    Case("mcap-full-disk", "prima run --format mcap --out /dev/full", _speaker("hello"),
         Exits(1, "prima run: error: cannot write /dev/full: no space left on device"),
         command=("run", "{path}", "--format", "mcap", "--out", "/dev/full"), seconds=4),
    Case("results-full-disk", "prima sweep --results /dev/full", _speaker("hello"),
         Exits(1, "prima sweep: error: cannot write /dev/full: no space left on device"),
         command=("sweep", "{path}", "--runs", "2", "--jitter", "1", "--jobs", "1",
                  "--worst", "0", "--results", "/dev/full")),
    # 13: numbers in traces are bounded where they are read
    *(Case(f"trace-huge-{field}-{command}", f"a {field} of 5,000 digits, {command}",
           _trace(json.dumps(START | {field: 0}).replace(f'"{field}": 0', f'"{field}": 1'
                                                          + "0" * 5000), END),
           Exits(1, "run.jsonl:1:"),
           command=(command, "{path}", *(("-o", "{dir}/p.svg") if command == "plot" else
                                         ("-o", "{dir}/p.html") if command == "show" else ())))
      for field in ("seq", "t") for command in ("show", "plot", "judge")),
    # 14: what --audio synthesises is bounded, in time and words
    Case("audio-long-utterance", "an utterance of 99,999 s (was a MemoryError)",
         made(_said_and_cut), Exits(0, "its sound is its beginning, 120.0 s"),
         command=("show", "{path}", "--audio", "-o", "{dir}/p.html"), seconds=10),
    Case("audio-many-words", "an utterance of 100,000 words (was 2.7 GB and 80 s)",
         _trace(START | {"text": " ".join(["word"] * 100_000)}, END | {"t": 40_000}),
         Exits(0, "says 100,000 word(s)"),
         command=("show", "{path}", "--audio", "-o", "{dir}/p.html"), seconds=10),
    # 15: escaping, in every row and every message
    Case("text-trace-bidi-user", "U+202E and U+200F in what the user says",
         _user_says("abc\u202edef\u200fghi"), Exits(0, "abc\\u202edef\\u200fghi",
                                                      absent="[\u202e\u200f]"),
         command=("run", "{path}")),
    Case("validate-control-name", "an escape sequence in a file's name, plain validate",
         made(_controlled), Exits(1, "bad\\x1b[2J.pxml:1:", absent=C1_OR_C0),
         command=("validate", "{path}")),
    Case("validate-caret-c1", "a C1 control character in the line under validate's caret",
         write("t.pxml", '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t">\n'
                         '<var name="x" expr="1 + \x9b2J @"/>\n'
                         '<state id="s" initial="true"/>\n</pxml>\n'),
         Exits(1, "expr=\"1 + \\x9b2J @\"", absent=C1_OR_C0), command=("validate", "{path}")),
    Case("test-control-name", "an escape sequence in a scenario's name, prima test's diff",
         made(_golden_differs), Exits(1, "s\\x1b[2J.golden.txt", absent=C1_OR_C0),
         command=("test", "{path}")),
    Case("test-missing-golden", "prima test of a scenario without its golden trace",
         _speaker("hello"), Exits(1, "no golden trace s.golden.txt: create it with prima "
                                     "test --update "),
         command=("test", "{path}")),
    # 16: traces are portable: no absolute path in any line
    Case("trace-error-relative", "a runtime error's line in the text trace",
         made(_failing), Exits(0, "ERROR: ea.pxml:1:", absent="ERROR: /"),
         command=("run", "{path}")),
    Case("jsonl-error-relative", "a runtime error's line in the jsonl trace",
         made(_failing), Exits(0, '"text": "ea.pxml:1:', absent='"text": "/'),
         command=("run", "{path}", "--format", "jsonl")),
    # 17: names no file can have, and names of shipped files that are not shipped
    Case("cli-name-too-long", "a scenario named with 300 letters (a traceback from os.stat)",
         _speaker("hello"), Exits(2, "...: file name too long"),
         command=("run", "{dir}/" + "a" * 300 + ".xml")),
    Case("check-fa-name-too-long", "prima check --fa with a path 5,000 letters long",
         _speaker("hello"), Exits(2, "...: file name too long"),
         command=("check", "{dir}/ea.pxml", "--fa", "apps/fa/" + "a" * 5000)),
    Case("run-fa-not-shipped", "--fa with a name no shipped FA has",
         _speaker("hello"), Exits(2, "no such file: fa9-nope"),
         command=("run", "{path}", "--fa", "fa9-nope")),
    # 18: the language server's client
    Case("lsp-huge-length", "a Content-Length of 10^17 and a body cut short (the server ended "
         "with a traceback)", made(_shipped_apps),
         Exits(1, "the client's stream ended inside a refused message: stopping",
               absent="Traceback"),
         command=("lsp",), stdin=_LSP_INIT + b"Content-Length: 99999999999999999\r\n\r\n{",
         seconds=8),
    Case("lsp-garbage-headers", "headers that are no headers, then a clean shutdown",
         made(_shipped_apps),
         Exits(0, "skipped up to the next Content-Length header", absent="Traceback"),
         command=("lsp",), stdin=_LSP_INIT + b"Content-Type: x\r\n\r\n{}\r\nnoise\r\n"
         + _lsp_frame({"jsonrpc": "2.0", "id": 2, "method": "shutdown"})
         + _lsp_frame({"jsonrpc": "2.0", "method": "exit"}), seconds=8),
    # 19: prima live (its page's inputs: tests/live/test_live.py)
    Case("live-save-over-scenario", "prima live told to save its session over its scenario",
         _speaker("hello"), Exits(2, "s.xml is the scenario ("),
         command=("live", "{path}", "--save", "{path}", "--port", "0"), seconds=6,
         then=_inputs_intact),
    Case("live-save-over-map", "prima live told to save its session over its map",
         _speaker("hello"), Exits(2, "map.xml is the map ("),
         command=("live", "{path}", "--save", "{dir}/./sub/../map.xml", "--port", "0"),
         seconds=6),
    Case("live-save-dir-is-ea", "prima live told to save into its EA, as a folder",
         _speaker("hello"), Exits(2, "ea.pxml is a file: an EA ("),
         command=("live", "{path}", "--save-dir", "{dir}/ea.pxml", "--port", "0"), seconds=6,
         then=_inputs_intact),
    # 9: the shipped files
    Case("validate-apps", "prima validate apps/ (FA7 is the guide robot's)",
         made(_shipped_apps), Accepted(), seconds=10),
    Case("validate-scenarios", "prima validate scenarios/",
         made(_shipped_scenarios), Accepted(), seconds=20),
]
