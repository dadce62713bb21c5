"""Every red-team case gets its verdict, in time, within its memory, without a traceback."""

from __future__ import annotations

import multiprocessing
import os
import re
import time
from pathlib import Path

import pytest

from prima.dsl import default_profile, parser
from prima.xmlio import schema, verdict_schema
from tests.redteam.cases import CASES, STATE, pxml, write
from tests.redteam.surfaces import SURFACES
from tests.redteam.runner import Accepted, Case, Exits, position, run_case

_PROBLEM = re.compile(r"^(?P<file>.*):(?P<line>\d+):(?P<col>\d+): error: (?P<message>.*)$")


@pytest.fixture(scope="module", autouse=True)
def _built_once() -> None:
    """Build the schemas, the parser and the default profile before the cases fork."""
    for name in ("pxml.xsd", "robot.xsd", "scenario.xsd", "map.xsd"):
        verdict_schema(name)
        schema(name)
    parser()
    default_profile()


def test_the_corpus_is_large_and_each_case_says_what_it_attacks() -> None:
    every = [*CASES, *SURFACES]
    assert len(CASES) >= 60 and len(SURFACES) >= 20
    assert len({c.id for c in every}) == len(every)
    assert all(c.attack for c in every)


@pytest.mark.parametrize("case", [*CASES, *SURFACES], ids=lambda c: c.id)
def test_case(case: Case, tmp_path: Path) -> None:
    path, outcome = run_case(case, tmp_path)
    assert not outcome.crash, outcome.crash
    shown = outcome.out + outcome.err
    assert "Traceback" not in shown, shown
    assert outcome.seconds <= case.seconds, f"{outcome.seconds:.2f} s"
    errors = [m for m in map(_PROBLEM.match, shown.splitlines()) if m]
    if isinstance(case.expect, Exits):
        assert outcome.code == case.expect.code, shown[:2000]
        assert case.expect.fragment in shown, shown[:2000]
        assert not (case.expect.absent and re.search(case.expect.absent, shown)), shown[:2000]
        return
    if isinstance(case.expect, Accepted):
        assert (outcome.code, errors) == (0, []), shown[:2000]
        return
    assert outcome.code == 1 and errors, shown[:2000]
    expect = case.expect
    first = errors[0]
    if expect.file is not None:  # a file the input names, or (".") the case's folder
        path = tmp_path / expect.file
    text = path.read_bytes().decode("utf-8", "replace") if path.is_file() else ""
    assert os.path.normpath(first.group("file")) == os.path.normpath(path)
    assert (int(first.group("line")), int(first.group("col"))) == \
        position(text, expect.at, expect.offset), first.group(0)[:300]
    assert expect.fragment in first.group("message"), first.group(0)[:300]



def _allocate(_path: Path) -> None:
    bytearray(4 << 30)


def _hang(_path: Path) -> None:
    time.sleep(3600)


def _spin(_path: Path) -> None:
    while True:
        pass


def test_the_runner_enforces_its_limits(tmp_path: Path) -> None:
    # the harness itself: a case that allocates 4 GiB fails, one that hangs is ended
    greedy = Case("greedy", "memory", write("t.pxml", pxml(STATE)), Accepted(), then=_allocate)
    for name in "abc":
        (tmp_path / name).mkdir()
    _path, outcome = run_case(greedy, tmp_path / "a")
    assert "MemoryError" in outcome.crash
    # one that spins, by its CPU time (four times its limit and a second), however long a
    # loaded machine takes to give it that much
    spinning = Case("spinning", "time", write("t.pxml", pxml(STATE)), Accepted(), then=_spin,
                    seconds=0.2)
    with pytest.raises(AssertionError, match="no verdict within 2 s of CPU time"):
        run_case(spinning, tmp_path / "b")
    # one that waits without spinning, when the parent stops waiting for it (here after a
    # second; the corpus's bound is runner.HANG), killed and gone
    stuck = Case("stuck", "time", write("t.pxml", pxml(STATE)), Accepted(), then=_hang)
    with pytest.raises(AssertionError, match="no verdict after waiting 1 s"):
        run_case(stuck, tmp_path / "c", hang=1.0)
    assert multiprocessing.active_children() == []
