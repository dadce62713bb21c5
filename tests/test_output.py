"""Every command writes its file through one path (:mod:`prima.output`): a file that
cannot be written is a message, never a traceback, and nothing is left half-written;
file names that are not UTF-8 are written and shown."""

from __future__ import annotations

import io
import os
from pathlib import Path

import pytest

from prima.cli import main
from tests.signalled import signalled_run
from tests.test_escape import speaking

NOT_UTF8 = os.fsdecode(b"run-\xff")


def _cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    return main(list(argv), out=out, err=err), out.getvalue(), err.getvalue()


def _commands(scenario: Path, target: str) -> list[list[str]]:
    plots = [["plot", str(scenario), "-o", target + suffix] for suffix in (".svg", ".gif")]
    return [["run", str(scenario), "--out", target + ".txt"],
            ["run", str(scenario), "--format", "jsonl", "--out", target + ".jsonl"],
            ["run", str(scenario), "--format", "chrome-trace", "--out", target + ".json"],
            ["show", str(scenario), "-o", target + ".html"], *plots]


def test_a_full_disk_is_a_message(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    pytest.importorskip("plotly")
    scenario = speaking(tmp_path, "hello")
    for argv in _commands(scenario, "/dev/full"):
        argv[-1] = "/dev/full"
        status, _, err = _cli(*argv)
        assert (status, err.splitlines()) == (
            1, [f"prima {argv[0]}: error: cannot write /dev/full: no space left on device"]
        ) or (argv[0] == "plot" and status == 2), (argv, err)


@pytest.mark.parametrize("target", ["/proc/version", "/proc/no/such/folder/x"])
def test_a_target_that_cannot_be_written_is_a_message(tmp_path: Path, target: str) -> None:
    scenario = speaking(tmp_path, "hello")
    status, _, err = _cli("run", str(scenario), "--out", target)
    assert status in (1, 2) and "Traceback" not in err
    assert err.startswith("prima run: error: ") and target in err, err


def test_a_failed_run_leaves_no_file_and_keeps_the_old_one(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    scenario = speaking(tmp_path, "hello")
    kept = tmp_path / "kept.txt"
    kept.write_text("the old trace\n")

    def fails(_self: object) -> None:
        from prima.errors import RunError
        raise RunError("the run loop stopped making progress")

    monkeypatch.setattr("prima.run.Run.run", fails)
    status, _, err = _cli("run", str(scenario), "--out", str(kept))
    assert status == 1 and "stopped making progress" in err
    assert kept.read_text() == "the old trace\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ea.pxml", "kept.txt", "map.xml",
                                                           "s.xml"]


def test_file_names_that_are_not_utf8(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    pytest.importorskip("plotly")
    scenario = speaking(tmp_path, "hello").rename(tmp_path / f"{NOT_UTF8}.xml")
    for argv in _commands(scenario, str(tmp_path / NOT_UTF8)):
        status, out, err = _cli(*argv)
        assert status == 0, (argv, err)
        assert Path(argv[-1]).stat().st_size > 0
        assert "\udcff" not in out + err
    status, _, err = _cli("show", str(tmp_path / f"{NOT_UTF8}.jsonl"), "-o",
                          str(tmp_path / "page.html"))
    assert status == 0 and "\\xff" not in err
    page = (tmp_path / "page.html").read_text(encoding="utf-8")
    assert "<title>prima show: run-\\xff</title>" in page


def test_a_sweep_checks_where_it_writes_before_it_runs(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello")
    (tmp_path / "file").write_text("")
    status, out, err = _cli("sweep", str(scenario), "--runs", "2", "--jitter", "1",
                            "--out", str(tmp_path / "file" / "worst"))
    assert status == 2 and out == "" and "is not a folder" in err, err


@pytest.mark.parametrize("form", ["text", "jsonl", "chrome-trace"])
def test_sigterm_keeps_the_trace_written_so_far(tmp_path: Path, form: str) -> None:
    trace = tmp_path / "run.out"
    scenario = Path(__file__).parents[1] / "scenarios" / "thesis" / "sample-03.xml"
    # SIGTERM once the trace passes 61 s (sample-03 ends at 60 s; this goes on and on)
    child = signalled_run("SIGTERM", 61, "run", str(scenario), "--until", "100000",
                          "--format", form, "--out", str(trace))
    err = child.stderr
    assert child.returncode == 143, err
    assert "prima run: interrupted at t=" in err and "Traceback" not in err
    text = trace.read_text(encoding="utf-8")
    assert text.endswith("\n") and "Come on, follow me." in text  # said at 32.64 s
    if form == "jsonl":
        from prima.tracefile import load_trace
        assert load_trace(trace)[-1]["t"] > 60
    if form == "chrome-trace":
        import json
        assert json.loads(text)[-1]["ph"] in ("e", "X", "i", "M")


# ------------------------------------------------------------ where output goes: one rule

def _every_output(scenario: Path, target: str) -> list[list[str]]:
    """Every command line that writes an output named ``target`` (a file, or sweep's
    folder), the optional viewers' only if their extra is installed."""
    import importlib.util

    lines = [["run", str(scenario), "--out", target + ".txt"],
             ["run", str(scenario), "--format", "chrome-trace", "--out", target + ".json"],
             ["sweep", str(scenario), "--runs", "1", "--jitter", "0", "--jobs", "1", "--worst",
              "1", "--out", target]]
    extras = [("plotly", ["show", str(scenario), "-o", target + ".html"]),
              ("matplotlib", ["plot", str(scenario), "-o", target + ".svg"]),
              ("foxglove", ["run", str(scenario), "--format", "mcap", "--out", target + ".mcap"])]
    return lines + [argv for module, argv in extras if importlib.util.find_spec(module)]


def test_every_command_makes_a_missing_output_folder(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello", until=2)
    for i, argv in enumerate(_every_output(scenario, "{new}")):
        argv[-1] = argv[-1].format(new=tmp_path / f"new{i}" / "deeper" / "x")
        status, _, err = _cli(*argv)
        assert status == 0, (argv, err)
        made = Path(argv[-1])
        assert made.is_file() or any(made.iterdir()), argv


def test_every_command_refuses_a_file_in_the_way_alike(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello", until=2)
    (tmp_path / "file").write_text("")
    for argv in _every_output(scenario, str(tmp_path / "file" / "deeper" / "x")):
        status, out, err = _cli(*argv)
        assert (status, out) == (2, ""), (argv, err)
        assert err == f"prima {argv[0]}: error: --out {argv[-1]}: {tmp_path / 'file'} is not a " \
                      "folder\n", err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ea.pxml", "file", "map.xml", "s.xml"]


def test_a_file_named_with_a_slash_at_its_end_is_refused_not_written_over(
        tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello", until=2)
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    for argv in (["run", str(scenario), "--out", f"{notes}/"],
                 ["run", str(scenario), "--out", f"{tmp_path / 'new'}/"],
                 ["sweep", str(scenario), "--runs", "1", "--jitter", "0", "--jobs", "1",
                  "--worst", "0", "--results", f"{notes}/"]):
        status, out, err = _cli(*argv)
        assert (status, out) == (2, ""), (argv, err)
        assert err.endswith(f"error: {argv[-2]} {argv[-1]} names a folder (it ends with /): "
                            "give the file's name\n"), err
    assert notes.read_text() == "my notes\n" and not (tmp_path / "new").exists()


def test_a_dash_is_refused_where_no_trace_goes_to_standard_output(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """prima run's --out - is its trace on standard output; a page or a report is a file
    (it wrote one named -)."""
    scenario = speaking(tmp_path, "hello", until=2)
    monkeypatch.chdir(tmp_path)
    argv = [["show", str(scenario), "--out", "-"],
            ["sweep", str(scenario), "--runs", "1", "--jitter", "0", "--results", "-"]]
    for command in argv:
        status, out, err = _cli(*command)
        assert (status, out) == (2, ""), (command, err)
        assert err == f"prima {command[0]}: error: {command[-2]} - is standard output, where " \
                      "this command writes no file: name a file (./- for one named -)\n", err
    assert not (tmp_path / "-").exists()


def test_a_failed_write_takes_away_the_folders_it_made(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    scenario = speaking(tmp_path, "hello")

    def fails(_self: object) -> None:
        from prima.errors import RunError
        raise RunError("the run loop stopped making progress")

    monkeypatch.setattr("prima.run.Run.run", fails)
    status, _, err = _cli("run", str(scenario), "--out", str(tmp_path / "a" / "b" / "t.txt"))
    assert status == 1 and "stopped making progress" in err
    assert not (tmp_path / "a").exists()


def test_what_the_command_line_does_not_name_goes_to_the_current_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("plotly")
    (tmp_path / "in").mkdir()
    scenario = speaking(tmp_path / "in", "hello", until=2)
    monkeypatch.chdir(tmp_path)
    assert _cli("show", str(scenario))[0] == 0
    assert _cli("sweep", str(scenario), "--runs", "1", "--jitter", "0", "--jobs", "1")[0] == 0
    assert (tmp_path / "s.html").is_file() and (tmp_path / "sweep-s").is_dir()


@pytest.mark.parametrize("form", ["jsonl", "mcap"])
def test_a_stream_of_the_process_is_written_into_not_replaced(tmp_path: Path, form: str) -> None:
    """``--out /dev/fd/1`` (as ``/dev/stdout``) with standard output a file: written into
    (an MCAP recording through a file copied into it), never renamed over: the name is the
    process's stream, not a file of the folder to replace."""
    import subprocess
    import sys

    if form == "mcap":
        pytest.importorskip("foxglove")
    scenario = speaking(tmp_path, "hello", until=2)
    with (tmp_path / f"out.{form}").open("wb") as out:
        done = subprocess.run([sys.executable, "-m", "prima", "run", str(scenario), "--format",
                               form, "--out", "/dev/fd/1"], stdout=out, stderr=subprocess.PIPE,
                              timeout=120)
    assert done.returncode == 0, done.stderr
    written = (tmp_path / f"out.{form}").read_bytes()
    assert written.startswith(b"\x89MCAP" if form == "mcap" else b'{"t": 0.0')


def test_a_symbolic_link_is_kept_and_its_file_written(tmp_path: Path) -> None:
    scenario = speaking(tmp_path, "hello", until=2)
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "today.txt").write_text("the old trace\n")
    (tmp_path / "latest.txt").symlink_to(Path("runs") / "today.txt")
    assert _cli("run", str(scenario), "--out", str(tmp_path / "latest.txt"))[0] == 0
    assert (tmp_path / "latest.txt").is_symlink()
    assert (tmp_path / "runs" / "today.txt").read_text().startswith("  No.")
