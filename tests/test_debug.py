"""``prima debug``: a scripted session (commands from standard input) steps through
sample-03, breaks on the user's touch, and shows the stream the touch suspended."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import pytest

from prima import cli
from prima.debug import Debugger

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"


def session(script: str, scenario: Path = SAMPLE_03) -> str:
    out = io.StringIO()
    Debugger(scenario, io.StringIO(script), out).start()
    return out.getvalue()


def test_a_scripted_session_breaks_on_the_touch_and_shows_the_suspended_stream() -> None:
    """As a terminal session would be typed, through the command line."""
    proc = subprocess.run([sys.executable, "-m", "prima", "debug", str(SAMPLE_03)],
                          input="break user touch\ncontinue\nstep 10\nmemory\napps\nquit\n",
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert "breakpoint 1 (user touch)" in out
    assert "26.34   U                touches the robot" in out
    # FA2 stopped the robot for its reaction: EA3's guiding stream is suspended
    assert "suspended: stream 0 of ea3-navigate (most recent): AB49 TopologicalMove" in out
    assert "fa2-follow (fa): state asking" in out and "goal = 'kidode-room'" in out
    # ten lines on, still in the touch's instant: EA3's stream held while FA2 answers
    assert "26.34   R   ea3-navigate holds TopologicalMove back (while fa2-follow answers " \
        "the user)  [answering]" in out
    assert out.rstrip().endswith("stopped at t=26.34 s")


def test_breakpoints_on_a_command_a_state_an_event_an_app_and_a_time() -> None:
    out = session("b command QA\nc\ndelete 1\nb state asking\nc\ndelete 1\n"
                  "b event message\nc\ndelete 1\nb time 100\nc\nbreaks\ndelete 9\n"
                  "b app fa2-follow\nc\nwhere\nq\n")
    stops = [line for line in out.splitlines() if line.startswith("breakpoint ") and "(" in line]
    assert stops == ["breakpoint 1 (command QA)", "breakpoint 1 (state asking)",
                     "breakpoint 1 (event message)", "breakpoint 1 (time 100)",
                     "breakpoint 2 (app fa2-follow)"]
    assert '0.96   R   ea3-navigate QA "Where are you going?"  [free-devices]' in out
    assert "26.34   R   fa2-follow   state asking" in out
    assert "1: time 100 (hit 1 time)" in out
    assert "deleted breakpoint 1 (state asking)" in out
    assert "delete takes a breakpoint's number (1 to 1)" in out


def test_a_line_that_is_no_command_line_is_never_held_whole() -> None:
    # (standard input that is not text, < /dev/zero, has no line end: read whole, it took
    # all the memory there is; split as words, all the time)
    out = session("\0" * 70_000 + "\nstep\nq\n")
    assert "(prima) cannot read that line: it is longer than 65,536 characters" in out
    assert "    0     0.00   R   fa2-follow   loads fa2-follow.pxml (fa)" in out


def test_bad_commands_are_told_and_the_end_of_input_stops_the_run() -> None:
    out = session("frobnicate\nstep x\nbreak colour red\nbreak time soon\nh\nstep 2\n")
    assert "unknown command 'frobnicate'" in out
    assert "step takes a number of lines, not 'x'" in out
    assert "break app|command|state|event NAME" in out
    assert "break time takes seconds, not 'soon'" in out
    assert "commands (a prefix will do" in out
    assert out.rstrip().endswith("s")  # "stopped at t=... s": end of input quits
    assert "stopped at t=" in out


def test_a_number_that_is_no_number_is_told_not_a_traceback() -> None:
    huge = "9" * 5000  # (past what int() converts)
    out = session(f"b time 100\nhistory \u00b2\nhistory {huge}\ndelete \u00b2\n"
                  f"delete {huge}\nstep 2\nhistory {huge}\nq\n")
    assert out.count("delete takes a breakpoint's number (1 to 1)") == 2
    assert "1     0.00   R   fa2-follow   state sleeping" in out
    assert out.rstrip().endswith("stopped at t=0 s")


def test_a_time_that_is_no_finite_number_is_refused() -> None:
    out = session("b time nan\nb time inf\nb time -inf\nb time 1e999\nbreaks\nq\n")
    for typed in ("nan", "inf", "-inf", "1e999"):
        assert f"break time takes seconds, not {typed!r}" in out
    assert "no breakpoints" in out


def test_history_of_no_number_is_refused() -> None:
    out = session("step 3\nhistory abc\nq\n")
    assert out.split("(prima) history abc\n")[1].startswith(
        "history takes a number of lines, not 'abc'\n(prima) ")


def test_history_0_shows_no_line() -> None:
    out = session("step 3\nhistory 0\nhistory 2\nq\n")
    told = out.split("(prima) history 0\n")[1].split("(prima) ")[0]
    assert told == ""
    told = out.split("(prima) history 2\n")[1].split("(prima) ")[0]
    assert len(told.splitlines()) == 2


def test_continue_with_no_breakpoint_runs_to_the_end() -> None:
    out = session("c\n")
    assert out.rstrip().endswith("the run ended at t=250 s")


def test_prima_debug_checks_its_options(monkeypatch: pytest.MonkeyPatch) -> None:
    err = io.StringIO()
    assert cli.main(["debug", "no-such.xml"], out=io.StringIO(), err=err) == 2
    assert "no such file: no-such.xml" in err.getvalue()
    monkeypatch.setattr("prima.cli._debug._stdin", lambda: io.StringIO("quit\n"))
    out = io.StringIO()
    assert cli.main(["debug", str(SAMPLE_03), "--policy", "all=off"], out=out,
                    err=io.StringIO()) == 0
    assert "stopped at t=0 s" in out.getvalue()


def test_lines_are_numbered_as_the_jsonl_trace_numbers_them() -> None:
    """A line's number is its ``seq`` in ``prima run --format jsonl``'s trace (with its
    pose samples), as ``prima judge`` and ``prima show`` give it."""
    from prima.run import Run

    touch = next(line for line in Run(SAMPLE_03).run() if line.action == "touch")
    out = session("break user touch\ncontinue\nquit\n")
    assert f"{touch.seq:5d}    26.34   U                touches the robot" in out


@pytest.mark.parametrize("typed, said", [
    ("break state guid", "no state 'guid' in this run, no breakpoint set; did you mean 'guide'?"),
    ("break app ea3-navigat", "no application 'ea3-navigat' in this run, no breakpoint set; "
                              "did you mean 'ea3-navigate'?"),
    ("break command Speek", "no Command 'Speek' in this run, no breakpoint set; did you mean "
                            "'Speak'?"),
    ("break command Nope", "no Command 'Nope' in this run, no breakpoint set (known: "
                           "ActiveSensingHuman, FaceHuman, QA,"),
    ("break app don't", "cannot read that line: no closing quotation"),
    ("break state \"don't\"", "no state \"don't\" in this run"),
])
def test_a_breakpoint_that_could_never_stop_is_refused(typed: str, said: str) -> None:
    out = session(f"{typed}\nbreaks\nquit\n")
    assert said in out, out
    assert "no breakpoints" in out and "Traceback" not in out
