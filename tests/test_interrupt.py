"""Ctrl-C and SIGTERM at any moment of a sweep end it with one line and the signal's exit
status, never a traceback, the finished runs kept whole in the results file.

A real ``prima sweep`` runs in a process group of its own, on two worker processes, and
the signal goes to the whole group, as a terminal's Ctrl-C does (the workers get it
too). Each point is reached by waiting for what the sweep has written, not for a time:
at start-up (as soon as PRIMA has taken the signals, while the command's modules load),
as the pool is made (the results file has its header), while the runs go (it has
records) and while they are written (many records). A signal while Python itself starts
(its ``site`` module, before any of PRIMA's code) is Python's to handle, not PRIMA's.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import weakref
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from prima.signals import Terminated, deferred, sticky, terminate_as_interrupt

ROOT = Path(__file__).parents[1]
SCENARIO = ROOT / "scenarios" / "thesis" / "sample-08.xml"
RUNS = "60"
BOUND = 120.0
"""Seconds any wait may take at most (a sweep of these runs takes a few)."""

STATUS = {signal.SIGINT: (130, -signal.SIGINT), signal.SIGTERM: (143, -signal.SIGTERM)}
"""The statuses a signal may end the sweep with: 128 + its number, or killed by it (a
shell says 128 + its number of both). CPython ends a process whose KeyboardInterrupt
went through an ``exec`` of text (a dataclass being made, as a module loads) by
SIGINT itself at exit, whoever caught the exception; and a signal before Python has
set its handlers kills the process at once, with nothing said."""


def _sweep(results: Path, *more: str, jobs: str = "2") -> list[str]:
    return [sys.executable, "-m", "prima", "sweep", str(SCENARIO), "--runs", RUNS, "--jitter",
            "3", "--seed", "4", "--jobs", jobs, "--worst", "0", *more, str(results)]


def _records(results: Path) -> int:
    """The lines the results file has (-1: none yet)."""
    try:
        return results.read_bytes().count(b"\n")
    except FileNotFoundError:
        return -1


def _took_the_signals(pid: int) -> bool:
    """Whether the process ``pid`` catches SIGTERM: ``prima``'s entry point does so first
    thing (Python itself leaves it at its default), so PRIMA's code is running."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True  # (gone, or no /proc: nothing to wait for)
    caught = next((line.split()[1] for line in status.splitlines()
                   if line.startswith("SigCgt:")), "0")
    return bool(int(caught, 16) >> (signal.SIGTERM - 1) & 1)


def _interrupted(results: Path, sig: signal.Signals, lines: int | None, jobs: str = "2",
                 env: dict[str, str] | None = None) -> tuple[int, str]:
    """A sweep on ``jobs`` given ``sig`` (its process group) once its results file has
    ``lines`` lines (None: as soon as PRIMA has taken the signals): its exit status and
    what it said on standard error."""
    process = subprocess.Popen(_sweep(results, "--results", jobs=jobs),
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               start_new_session=True, cwd=ROOT, env=env)
    try:
        deadline = time.monotonic() + BOUND
        while lines is None and not _took_the_signals(process.pid) \
                and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.0005)
        while lines is not None and _records(results) < lines and process.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.002)
        if process.poll() is None:
            os.killpg(process.pid, sig)
        _, err = process.communicate(timeout=BOUND)
    finally:
        if process.poll() is None:  # never left running, whatever failed
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
    return process.returncode, err.decode("utf-8", "replace")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
@pytest.mark.parametrize("lines", [None, 1, 2, 30], ids=["start-up", "pool", "running",
                                                          "writing"])
def test_a_signal_at_any_moment_of_a_sweep_ends_it_in_one_line(
        tmp_path: Path, sig: signal.Signals, lines: int | None) -> None:
    results = tmp_path / "r.jsonl"
    status, err = _interrupted(results, sig, lines)
    said = [line for line in err.replace("\r", "\n").splitlines()
            if line.strip() and not line.startswith("[")]  # (the progress bar's lines)
    assert "Traceback" not in err and "Exception" not in err, err
    if status == 0:  # (the sweep was done before the signal came)
        return
    assert status in STATUS[sig], err
    assert len(said) <= 1 and all("interrupted" in line for line in said), err
    if lines is not None:
        assert said, err  # (Python's handlers were set: the sweep said why it ended)
        rows = [json.loads(line) for line in results.read_text().splitlines()]
        assert rows[0]["prima"] == "sweep results"
        assert [(r["job"], r["run"]) for r in rows[1:]] == [(0, i) for i in range(len(rows) - 1)]


def test_a_sweep_stopped_mid_run_resumes_to_the_file_an_uninterrupted_one_writes(
        tmp_path: Path) -> None:
    results = tmp_path / "stopped.jsonl"
    status, err = _interrupted(results, signal.SIGINT, 20)
    assert status in STATUS[signal.SIGINT] and "interrupted after" in err, err
    assert 20 <= _records(results) < int(RUNS) + 1
    whole = tmp_path / "whole.jsonl"
    for argv in (_sweep(results, "--resume"), _sweep(whole, "--results")):
        done = subprocess.run(argv, capture_output=True, cwd=ROOT, timeout=BOUND, check=False)
        assert done.returncode == 0, done.stderr.decode()
    assert results.read_bytes() == whole.read_bytes()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
def test_a_sweep_in_one_process_a_signal_stopped_leaves_no_folder_behind(
        tmp_path: Path, sig: signal.Signals) -> None:
    """With --jobs 1 the runs are unpacked in a folder of the sweep's own process; a
    command a signal stopped ends its process without Python's exit handlers, so the
    sweep deletes that folder itself as it stops."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    results = tmp_path / "r.jsonl"
    status, err = _interrupted(results, sig, 5, jobs="1",
                               env={**os.environ, "TMPDIR": str(scratch)})
    assert status in STATUS[sig] and "interrupted after" in err, err
    assert list(scratch.iterdir()) == []


def test_a_sweep_killed_outright_keeps_its_records_to_go_on_from(tmp_path: Path) -> None:
    """SIGKILL (the out-of-memory killer, a machine gone): nothing of the sweep runs
    after it, and the records it wrote are in the results file all the same, read back
    by --resume to the file an uninterrupted sweep writes."""
    results = tmp_path / "killed.jsonl"
    scratch = tmp_path / "tmp"  # (a sweep killed outright leaves its workers' folder)
    scratch.mkdir()
    process = subprocess.Popen(_sweep(results, "--results"), stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True, cwd=ROOT,
                               env={**os.environ, "TMPDIR": str(scratch)})
    try:
        deadline = time.monotonic() + BOUND
        while _records(results) < 10 and process.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.002)
        assert process.poll() is None, "the sweep was over before it could be killed"
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate(timeout=BOUND)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()
    assert 10 <= _records(results) < int(RUNS) + 1
    whole = tmp_path / "whole.jsonl"
    for argv in (_sweep(results, "--resume"), _sweep(whole, "--results")):
        done = subprocess.run(argv, capture_output=True, cwd=ROOT, timeout=BOUND, check=False)
        assert done.returncode == 0, done.stderr.decode()
    assert results.read_bytes() == whole.read_bytes()


@pytest.mark.parametrize("sig, raised", [(signal.SIGINT, KeyboardInterrupt),
                                         (signal.SIGTERM, Terminated)])
def test_a_deferred_signal_is_raised_when_the_block_ends(
        sig: signal.Signals, raised: type[BaseException]) -> None:
    """What a signal must not cut in two (a fork, a record written) finishes, then the
    signal is raised as it would have been; nested blocks wait for the outermost."""
    finished = []
    with pytest.raises(raised), terminate_as_interrupt(), deferred():
        with deferred():
            signal.raise_signal(sig)
            finished.append("inner")
        finished.append("outer")
    assert finished == ["inner", "outer"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def _in_a_finalizer(action: Callable[[], object]) -> None:
    """``action`` runs in a weakref's callback (as the cycle collector may run one at any
    moment): what it raises there, Python prints as ignored, and drops."""

    class Box:
        pass

    def callback(_ref: object) -> None:
        action()
        for _ in range(100):  # (a signal's handler runs here, inside the callback)
            pass

    box = Box()
    kept = weakref.ref(box, callback)
    del box
    assert kept() is None


def _value_error() -> None:
    raise ValueError


@pytest.mark.parametrize("sig, raised", [(signal.SIGINT, KeyboardInterrupt),
                                         (signal.SIGTERM, Terminated)])
def test_a_signal_a_finalizer_dropped_is_raised_at_the_next_check(
        sig: signal.Signals, raised: type[BaseException],
        monkeypatch: pytest.MonkeyPatch) -> None:
    printed: list[object] = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: printed.append(u.exc_type))
    with terminate_as_interrupt():
        _in_a_finalizer(lambda: signal.raise_signal(sig))
    assert printed == [raised]  # without: printed as ignored, and dropped
    printed.clear()
    with terminate_as_interrupt(), sticky() as check:
        check()  # (nothing came: nothing raised)
        _in_a_finalizer(lambda: signal.raise_signal(sig))
        with pytest.raises(raised):
            check()  # the check raises it, and it was not printed
        check()  # (once)
        _in_a_finalizer(_value_error)  # what else a finalizer raises is printed
    assert printed == [ValueError]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_sweep_stops_on_a_ctrl_c_a_finalizer_dropped(monkeypatch: pytest.MonkeyPatch) -> None:
    """The Ctrl-C of the CI run that found this: it came while the collector ran a module
    lock's weakref callback, and the sweep ran to its end."""
    printed: list[object] = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: printed.append(u.exc_type))
    from prima.sweep import sweep

    seen: list[int] = []

    def progress(done: int, total: int) -> None:
        seen.append(done)
        if len(seen) == 1:
            _in_a_finalizer(lambda: signal.raise_signal(signal.SIGINT))

    result = sweep(SCENARIO, runs=6, jitter=1.0, jobs=1, progress=progress)
    assert result.interrupted
    assert seen == [seen[0]] and seen[0] < 6
    assert printed == []  # (it says it was interrupted, in one line: nothing else)


@pytest.mark.pure
@pytest.mark.parametrize("command, said", [
    (["run", str(SCENARIO), "--out", "{tmp}/t.txt"], "prima run: interrupted at t="),
    (["debug", str(SCENARIO)], "prima debug: interrupted at t="),
    (["test", str(ROOT / "scenarios" / "thesis" / "sample-0*.xml")], "prima test: interrupted"),
    (["judge", str(SCENARIO), str(SCENARIO)], "prima judge: interrupted"),
    (["show", str(SCENARIO), "--out", "{tmp}/t.html"], "prima show: interrupted"),
])
def test_a_command_that_runs_a_scenario_stops_on_a_ctrl_c_a_finalizer_dropped(
        command: list[str], said: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """A run checks at every line of its trace (``stop_if_signalled``): whichever command
    runs it stops at the next one, in one line, what it wrote kept."""
    import glob

    from prima.cli import main
    from prima.run import Run

    printed: list[object] = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: printed.append(u.exc_type))
    monkeypatch.setattr(sys, "stdin", __import__("io").StringIO("continue\n"))
    real = Run._event

    def event(self: Run, happened: Any) -> None:
        if not printed:
            _in_a_finalizer(lambda: signal.raise_signal(signal.SIGINT))
            printed.append("dropped")
        real(self, happened)

    monkeypatch.setattr(Run, "_event", event)
    argv = [a.format(tmp=tmp_path) for a in command]
    argv = [found for a in argv for found in (sorted(glob.glob(a)) if "*" in a else [a])]
    assert main(argv) == 130
    assert printed == ["dropped"]  # (and nothing printed of it)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(said), err
    if command[0] == "run":
        assert (tmp_path / "t.txt").read_text(encoding="utf-8").strip()


def test_a_sigterm_as_the_entry_point_takes_it_is_one_line(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """CI's start-up case: the signal came the moment ``prima`` set its handler, which
    ran while ``signal.signal`` was still returning, before the entry point's ``try``:
    a traceback. (Here it is raised right as the handler is set.)"""
    import prima.__main__ as entry

    real = signal.signal

    def setting(signum: int, handler: Any) -> Any:
        previous = real(signum, handler)
        if signum == signal.SIGTERM and handler is entry._terminated:
            signal.raise_signal(signal.SIGTERM)
        return previous

    before = signal.getsignal(signal.SIGTERM)
    monkeypatch.setattr(signal, "signal", setting)
    monkeypatch.setattr(entry, "_done", lambda status: None)  # (it would end this process)
    try:
        status = entry.main()
    except Terminated:  # (a KeyboardInterrupt: it would stop the whole test session)
        pytest.fail("the SIGTERM escaped the entry point")
    finally:
        real(signal.SIGTERM, before)
    assert status == 143
    assert capsys.readouterr().err == "prima: interrupted\n"


_BLOCKED_AT_EXIT = """
import multiprocessing, sys, threading, time
import prima.__main__ as entry
import prima.cli

def interrupted():
    # (what a worker pool's manager thread may do once a signal ended the sweep: wait
    # for ever on a result a killed worker was writing; Python's shutdown joins it)
    threading.Thread(target=threading.Event().wait).start()
    # (a worker that did not see the signal, busy with its task, holding standard error)
    multiprocessing.get_context("fork").Process(target=time.sleep, args=(3600,)).start()
    print("prima sweep: interrupted after 32 of 60 runs", file=sys.stderr)
    return int(sys.argv[1])

prima.cli.main = interrupted
sys.exit(entry.main())
"""


@pytest.mark.parametrize("status", [130, 143])
def test_a_command_a_signal_ended_ends_the_process_whatever_threads_it_leaves(
        status: int) -> None:
    """A sweep said "interrupted after 32 of 60 runs" and then did not exit: Python's
    shutdown waited for a thread its worker pool left. Here a thread that never ends
    stands for it, and a worker still busy: the process ends with the command's status
    all the same, and the worker with it (its standard error is closed)."""
    process = subprocess.Popen([sys.executable, "-c", _BLOCKED_AT_EXIT, str(status)],
                               stderr=subprocess.PIPE, cwd=ROOT)
    try:
        _, err = process.communicate(timeout=BOUND)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        pytest.fail("the process waited for its thread at exit")
    assert process.returncode == status
    assert err.decode() == "prima sweep: interrupted after 32 of 60 runs\n"
