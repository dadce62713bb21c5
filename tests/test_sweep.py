"""prima sweep: jittered variants keep the scenario's order, runs are deterministic
whatever the parallelism, and a written worst run replays exactly."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest
from lxml import etree

import prima.batch
import prima.batch._work
import prima.sweep
from prima.cli import main
from prima.judge import judge_file
from prima.scenario import load_scenario
from prima.batch import pool_for, record_of
from prima.sweep import MIN_ANSWER_DELAY, SweepRun, format_sweep, sweep, write_variant

ROOT = Path(__file__).parents[1]
THESIS = ROOT / "scenarios" / "thesis"
SHORT = THESIS / "fig5-7.xml"
"""A 60-second scenario: a run takes a fraction of a second."""
BUSY = ROOT / "scenarios" / "examples" / "office-kidode.xml"
"""A scenario with many user actions, answers and a message."""
NS = {"s": "urn:prima:scenario:1"}


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def timings(path: Path) -> dict[str, list[float]]:
    root = etree.parse(str(path)).getroot()
    user = root.find("s:user", NS)
    assert user is not None
    return {
        "actions": [float(e.get("at", "0")) for e in user if e.tag != f"{{{NS['s']}}}answer"
                    and isinstance(e.tag, str)],
        "answers": [float(e.get("after", "1.0")) for e in user.findall("s:answer", NS)],
        "scheduled": [float(e.get("at", "0")) for e in root
                      if isinstance(e.tag, str) and etree.QName(e).localname in
                      ("message", "sound", "event")],
    }


def test_a_variant_keeps_the_order_and_the_bounds(tmp_path: Path) -> None:
    path = write_variant(BUSY, tmp_path / "v.xml", seed=1, index=0, jitter=50.0)
    got = timings(path)
    assert got["actions"] == sorted(got["actions"]) and min(got["actions"]) >= 0
    assert got["scheduled"] == sorted(got["scheduled"]) and min(got["scheduled"]) >= 0
    assert min(got["answers"]) >= MIN_ANSWER_DELAY
    assert got != timings(BUSY)
    assert load_scenario(path).map.name == "office"  # paths relative to the new file


@pytest.mark.parametrize(("given", "settings"), [
    ((("interrupt", False),), {"interrupt": False}),
    ((("all", False), ("interrupt", True)), {"all": False, "interrupt": True}),
], ids=["one-over-the-scenarios", "all-over-the-scenarios"])
def test_a_variant_holds_the_command_lines_policies_over_the_scenarios(
        tmp_path: Path, given: tuple[tuple[str, bool], ...], settings: dict[str, bool]) -> None:
    """A scenario that switches a policy itself (``interrupt``), run with ``--policy``
    switches: the variant switches each policy once (the command line's winning) and
    runs as the scenario does with those switches."""
    from prima.run import Run, Switches

    scenario = ROOT / "scenarios" / "policies" / "interrupt-on.xml"
    path = write_variant(scenario, tmp_path / "v.xml", seed=0, index=0, jitter=0.0,
                         switches=Switches(policies=given))
    assert dict(load_scenario(path).policies) == settings
    assert [line.to_dict() for line in Run(path).run()] == \
        [line.to_dict() for line in Run(scenario, policies=dict(given)).run()]


@pytest.mark.pure
def test_a_sweeps_policy_switches_reach_its_runs_as_prima_runs_do(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--policy`` switches go to every run of a sweep through ``Setup.load``, as ``prima
    run --policy`` gives them (the scenario the runs read keeps its own switches); the
    results file's header says which switches its runs had (a resume must match them);
    the worst runs' files have them written in, so that they replay alone."""
    from prima.run import Run, Setup, Switches

    scenario = ROOT / "scenarios" / "policies" / "interrupt-on.xml"
    given = (("all", False), ("interrupt", True))
    asked: list[object] = []
    load = Setup.load.__func__  # type: ignore[attr-defined]

    def spy(cls: type[Setup], *args: Any, **kwargs: Any) -> Setup:
        asked.append(kwargs.get("policies"))
        return load(cls, *args, **kwargs)  # type: ignore[no-any-return]

    monkeypatch.setattr(Setup, "load", classmethod(spy))
    result = sweep(scenario, runs=2, jitter=1.0, jobs=1, keep=1,
                   switches=Switches(policies=given), results=tmp_path / "r.jsonl")
    assert result.done == 2
    assert asked and all(policies == dict(given) for policies in asked)
    header = json.loads((tmp_path / "r.jsonl").read_text().splitlines()[0])
    monkeypatch.undo()
    plain = sweep(scenario, runs=1, jitter=1.0, jobs=1, keep=0, results=tmp_path / "p.jsonl")
    assert plain.done == 1
    assert header["jobs"][0]["digest"] != json.loads(
        (tmp_path / "p.jsonl").read_text().splitlines()[0])["jobs"][0]["digest"]
    worst = result.write_worst(1, tmp_path / "worst")[0]
    assert dict(load_scenario(worst).policies) == dict(given)
    assert [line.to_dict() for line in Run(worst).run()] == [
        line.to_dict() for line in Run(write_variant(scenario, tmp_path / "v.xml", seed=0,
                                                     index=result.kept[0].index, jitter=1.0),
                                       policies=dict(given)).run()]


def test_no_jitter_no_change(tmp_path: Path) -> None:
    path = write_variant(BUSY, tmp_path / "v.xml", seed=1, index=0, jitter=0.0)
    assert timings(path) == timings(BUSY)


def test_the_offsets_depend_on_the_seed_and_the_run_only(tmp_path: Path) -> None:
    def variant(name: str, seed: int, index: int) -> str:
        out = write_variant(BUSY, tmp_path / name, seed=seed, index=index, jitter=3.0)
        return "\n".join(out.read_text(encoding="utf-8").splitlines()[1:])  # no comment line

    assert variant("a.xml", 1, 2) == variant("b.xml", 1, 2)
    assert variant("a.xml", 1, 2) != variant("c.xml", 1, 3)
    assert variant("a.xml", 1, 2) != variant("d.xml", 2, 2)


def test_variant_paths_are_relative_to_the_written_file(tmp_path: Path) -> None:
    folder = tmp_path / "deep" / "er"
    folder.mkdir(parents=True)
    path = write_variant(SHORT, folder / "v.xml", seed=0, index=0, jitter=1.0)
    root = etree.parse(str(path)).getroot()
    href = root.find("s:map", NS).get("href")  # type: ignore[union-attr]
    assert not Path(href).is_absolute()
    assert (folder / href).resolve() == (THESIS.parent / "maps" / "office.xml").resolve()


def test_same_seed_same_output_whatever_the_jobs(tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    args = ["sweep", str(SHORT), "--runs", "4", "--jitter", "3", "--seed", "7", "--worst", "2"]
    one = cli(*args, "--jobs", "1", "--out", "worst-of-jobs-1")
    two = cli(*args, "--jobs", "2", "--out", "worst-of-jobs-2")
    assert one[0] == two[0]
    assert one[1].replace("worst-of-jobs-1", "X") == two[1].replace("worst-of-jobs-2", "X")
    assert "4 of 4 runs, jitter ±3 s, seed 7" in one[1]
    assert "4/4 runs" in one[2]  # the progress bar
    assert sorted(p.name for p in (tmp_path / "worst-of-jobs-1").iterdir()) == sorted(
        p.name for p in (tmp_path / "worst-of-jobs-2").iterdir())
    for name in (p.name for p in (tmp_path / "worst-of-jobs-1").iterdir()):
        assert (tmp_path / "worst-of-jobs-1" / name).read_bytes() == \
            (tmp_path / "worst-of-jobs-2" / name).read_bytes()


def test_the_worst_runs_have_the_most_faults_after_the_most_thresholds() -> None:
    """Ranked worst first: thresholds exceeded, then faults found (a run unfaced five
    times is worse than one unfaced once), then the latest reaction."""
    def run(index: int, counts: dict[str, int], late: float = 0.0) -> SweepRun:
        breaches = [f"{k}: {n} > 0 (seq 1)" for k, n in counts.items() if n]
        return SweepRun(index, {"breaches": breaches, "counts": counts, "worst_lateness": late})

    once, often = run(0, {"unfaced": 1}, late=2.0), run(1, {"unfaced": 5})
    two = run(2, {"unfaced": 1, "late": 1})
    assert sorted([once, often, two], key=SweepRun.rank) == [two, often, once]


def test_a_written_worst_run_replays_its_measures(tmp_path: Path) -> None:
    result = sweep(THESIS / "sample-05.xml", runs=3, jitter=4.0, seed=3, jobs=1)
    (worst,) = result.worst(1)
    (path,) = result.write_worst(1, tmp_path / "out")
    assert path.name == f"sample-05-run{worst.index}-seed3.xml"
    replayed = record_of(judge_file(path))
    assert replayed == {k: v for k, v in worst.record.items() if k not in ("job", "run")}
    code, out, _ = cli("judge", str(path))
    assert code == (1 if worst.breaches else 0)


def test_the_summary_lists_every_measure() -> None:
    result = sweep(SHORT, runs=2, jitter=1.0, jobs=1)
    text = format_sweep(result)
    for name in ("worst lateness (s)", "worst first start (s)", "late reactions",
                 "talking unfaced", "leaving while talking", "split exchanges", "silences",
                 "stuck", "runs exceeding a threshold: 0 of 2"):
        assert name in text


def test_an_interrupted_sweep_keeps_what_was_done() -> None:
    def stop(done: int, total: int) -> None:
        if done == 1:
            raise KeyboardInterrupt

    result = sweep(SHORT, runs=3, jitter=1.0, jobs=1, progress=stop)
    assert result.interrupted and result.done == 1
    assert "1 of 3 runs" in format_sweep(result) and "(interrupted)" in format_sweep(result)


def test_ctrl_c_prints_what_was_done_and_exits_130(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    def bar(_out: Any, live: bool = True) -> Any:
        def draw(done: int, total: int) -> None:
            if done == 2:
                raise KeyboardInterrupt
        return draw

    monkeypatch.setattr(prima.sweep, "progress_bar", bar)
    monkeypatch.chdir(tmp_path)
    code, out, err = cli("sweep", str(SHORT), "--runs", "5", "--jitter", "1", "--jobs", "1")
    assert code == 130
    assert "2 of 5 runs" in out and "interrupted after 2 of 5 runs" in err
    assert list(tmp_path.iterdir()) == []  # nothing written


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_progress_bar_line_is_ended_before_anything_else_is_printed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Standard output and error on one terminal: an interrupted sweep's summary starts a
    line of its own, not the end of the bar's; so does an error's message."""
    real = prima.sweep.progress_bar

    def bar(out: Any, live: bool = True) -> Any:
        draw = real(out, live=live)

        def stop_at_two(done: int, total: int) -> None:
            draw(done, total)
            if done == 2:
                raise KeyboardInterrupt
        return stop_at_two

    monkeypatch.setattr(prima.sweep, "progress_bar", bar)
    monkeypatch.chdir(tmp_path)
    screen = _Terminal()
    code = main(["sweep", str(SHORT), "--runs", "5", "--jitter", "1", "--jobs", "1",
                 "--color", "never"], out=screen, err=screen)
    assert code == 130
    lines = screen.getvalue().split("\n")
    [summary] = [x for x in lines if "2 of 5 runs, jitter" in x]
    assert summary.startswith(str(SHORT)), lines[:3]
    assert "prima sweep: interrupted after 2 of 5 runs" in lines

    written = [0]

    def full(_self: Any, _record: Any) -> None:
        written[0] += 1
        if written[0] == 3:
            from prima.errors import OutputError
            raise OutputError("cannot write r.jsonl: no space left on device")

    monkeypatch.setattr(prima.sweep, "progress_bar", real)
    monkeypatch.setattr(prima.batch.ResultsFile, "write", full)
    screen = _Terminal()
    code = main(["sweep", str(SHORT), "--runs", "4", "--jitter", "1", "--jobs", "1",
                 "--color", "never", "--results", str(tmp_path / "r.jsonl")], out=screen,
                err=screen)
    assert code == 1
    shown = screen.getvalue()
    assert "runs\nprima sweep: error: cannot write r.jsonl" in shown, shown


def test_a_breach_exits_1_and_the_worst_runs_go_to_the_default_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    streams_off = ROOT / "scenarios" / "policies" / "streams-off.xml"
    code, out, _ = cli("sweep", str(streams_off), "--runs", "2", "--jitter", "0",
                       "--worst", "1", "--jobs", "1")
    assert code == 1
    assert "runs exceeding a threshold: 2 of 2" in out
    assert [p.name for p in (tmp_path / "sweep-streams-off").iterdir()] == [
        "streams-off-run0-seed0.xml"]
    assert "split exchanges 1 > 0" in out


@pytest.mark.parametrize("argv, fragment", [
    (["sweep", "no/such.xml", "--runs", "2", "--jitter", "1"], "no such file"),
    (["sweep", str(SHORT), "--runs", "0", "--jitter", "1"], "--runs must be"),
    (["sweep", str(SHORT), "--runs", "2", "--jitter", "-1"], "--jitter must be"),
    (["sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--jobs", "0"], "--jobs must be"),
    (["sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--worst", "-1"], "--worst must"),
    (["sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--out", str(SHORT)], "is a file"),
    (["sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--max-stuck", "-2"],
     "--max-stuck must be"),
    (["sweep", str(SHORT), "--jitter", "1"], "required"),
    (["sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--seed", "-1"], "from 0 to 2^63"),
])
def test_sweep_usage_errors_exit_2(argv: list[str], fragment: str,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = cli(*argv)
    assert code == 2
    assert fragment in err + capsys.readouterr().err


def test_a_bad_scenario_is_located(tmp_path: Path) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_text('<scenario xmlns="urn:prima:scenario:1" name="x" until="10">\n'
                   '  <map href="nowhere.xml"/>\n  <robot x="0" y="0"/>\n</scenario>\n',
                   encoding="utf-8")
    code, _, err = cli("sweep", str(bad), "--runs", "2", "--jitter", "1")
    assert code == 1
    assert f"{bad}:2:" in err and "Traceback" not in err


def test_the_progress_bar_is_redrawn_on_a_terminal_and_a_line_a_tenth_in_a_log() -> None:
    from prima.sweep import progress_bar

    for live, expected in ((True, 200), (False, 11)):
        written: list[str] = []
        draw = progress_bar(written.append, width=10, live=live)
        for done in range(1, 201):
            draw(done, 200)
        assert len(written) == expected
        assert all(("\r" in w) == live for w in written)
        assert written[-1].endswith("[##########] 200/200 runs\n")
    assert written[0] == "[..........] 1/200 runs\n"


# ------------------------------------------------------------ a worker process dies

DEATHS = Path("/nonexistent")
"""The folder the dying worker below counts its deaths in (set by the fixture)."""


def dying_run(job: Any, index: int, root: Any, folder: Path, *files: Any) -> Any:
    """Run 1's worker is killed (as by the kernel's out-of-memory killer) as long as the
    count of deaths is below the count allowed."""
    import os
    import signal

    marks = DEATHS / "deaths"
    allowed = int((DEATHS / "allowed").read_text())
    if index == 1 and len(marks.read_text()) < allowed:
        with marks.open("a") as out:
            out.write("x")
        os.kill(os.getpid(), signal.SIGKILL)
    return _real_run(job, index, root, folder, *files)


_real_run = prima.batch._work.run_one


@pytest.fixture
def dying(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setattr(prima.batch._work, "run_one", dying_run)
    monkeypatch.setitem(globals(), "DEATHS", tmp_path)
    (tmp_path / "deaths").write_text("")
    return tmp_path


def test_a_run_whose_worker_died_is_run_again(dying: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    (dying / "allowed").write_text("1")
    monkeypatch.chdir(dying)
    status, out, err = cli("sweep", str(SHORT), "--runs", "4", "--jitter", "3", "--jobs", "2",
                           "--worst", "0")
    assert status == 0, err
    assert "4 of 4 runs" in out and (dying / "deaths").read_text() == "x"


def test_a_run_whose_worker_always_dies_is_named_and_the_others_finish(dying: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    (dying / "allowed").write_text("9")
    monkeypatch.chdir(dying)
    status, out, err = cli("sweep", str(SHORT), "--runs", "4", "--jitter", "3", "--jobs", "2",
                           "--worst", "1", "--out", "worst", "--results", "all.jsonl")
    assert status == 1, err
    assert "prima sweep: run(s) 1 lost: the worker process died" in err, err
    assert "the other 3 run(s) are judged" in err and "Traceback" not in err
    assert "3 of 4 runs" in out and "(1 lost)" in out
    assert len(list((dying / "worst").iterdir())) == 1  # the finished runs are kept
    assert (dying / "deaths").read_text() == "xxx"  # with the pool, again, and alone
    lines = (dying / "all.jsonl").read_text().splitlines()
    assert [json.loads(line).get("run") for line in lines[1:]] == [0, 1, 2, 3]
    assert json.loads(lines[2]) == {"job": 0, "run": 1, "lost": True}


def test_a_killed_worker_leaves_no_files_behind(dying: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """A worker killed outright deletes nothing; the sweep deletes the folder its
    workers unpacked their runs in, theirs too."""
    import tempfile

    temporary = dying / "tmp"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))  # (the workers' too: forked)
    (dying / "allowed").write_text("1")
    monkeypatch.chdir(dying)
    status, out, err = cli("sweep", str(SHORT), "--runs", "4", "--jitter", "3", "--jobs", "2",
                           "--worst", "0")
    assert status == 0, err
    assert (dying / "deaths").read_text() == "x"  # (one was killed)
    assert list(temporary.iterdir()) == []


def test_never_more_workers_than_runs() -> None:
    assert pool_for(None, 1024, 2).workers == 2
    assert pool_for(None, 1, 5).workers == 1 and pool_for(None, 3, 5).workers == 3
    result = sweep(SHORT, runs=2, jitter=1.0, jobs=1024)
    assert result.done == 2


def test_a_scenario_named_in_bytes_that_are_not_utf8_or_with_dashes(tmp_path: Path) -> None:
    import os

    odd = tmp_path / os.fsdecode(b"run--\xff.xml")
    text = SHORT.read_text().replace('href="../maps', f'href="{ROOT}/scenarios/maps')
    text = text.replace('"../../apps', f'"{ROOT}/apps')
    odd.write_text(text)
    status, out, err = cli("sweep", str(odd), "--runs", "2", "--jitter", "1", "--jobs", "1",
                           "--out", str(tmp_path / "worst"), "--worst", "1")
    assert status in (0, 1) and "Traceback" not in err, err
    written = next((tmp_path / "worst").iterdir())
    assert load_scenario(written).name  # the variant is a scenario again
    assert "run- -\\xff.xml" in written.read_text()


def _pid() -> int:
    import os

    return os.getpid()


def test_worker_processes_are_replaced_every_few_tasks() -> None:
    """A worker takes RECYCLE tasks, then a fresh process takes over (what runs leave
    behind in a process goes with it: a long sweep's memory stays flat)."""
    from prima.batch import Processes

    pool = Processes(1, recycle=2)
    executor = pool.executor()
    pids = [executor.submit(_pid).result() for _ in range(6)]
    pool.close()
    assert pids[0] == pids[1] and pids[2] == pids[3] and pids[4] == pids[5]
    assert len(set(pids)) == 3


def _nap() -> int:
    import os
    import time

    time.sleep(0.2)
    return os.getpid()


def test_a_retiring_pool_never_overlaps_a_fresh_one() -> None:
    """The fresh workers are forked only once the retiring ones have finished their
    last task and exited: the process tree never holds more than ``jobs`` workers (its
    memory stays flat however many pools a long sweep goes through)."""
    import multiprocessing

    from prima.batch import Processes

    pool = Processes(2, recycle=1)
    executor = pool.executor()
    alive = []
    futures = []
    for _ in range(6):  # three pools of two workers, each taking two tasks
        futures.append(executor.submit(_nap))
        alive.append(len(multiprocessing.active_children()))
    pids = [f.result() for f in futures]
    pool.close()
    assert max(alive) == 2, alive
    assert len(set(pids)) >= 4  # (fresh workers took over)


def test_a_sweep_whose_workers_are_replaced_says_the_same(tmp_path: Path) -> None:
    from prima.batch import Processes

    alone = sweep(SHORT, runs=6, jitter=3.0, seed=5, jobs=1, results=tmp_path / "one.jsonl")
    recycled = sweep(SHORT, runs=6, jitter=3.0, seed=5, pool=Processes(2, recycle=1),
                     results=tmp_path / "two.jsonl")
    assert alone.done == recycled.done == 6
    assert (tmp_path / "one.jsonl").read_bytes() == (tmp_path / "two.jsonl").read_bytes()
