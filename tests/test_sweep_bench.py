"""``bench/sweep.py --instructions``: instructions per judged run, from callgrind's count of
a cold process of ``--runs`` + 1 runs less that of one run (here a stand-in for valgrind
that counts 5 M instructions a run beside a fixed 10 M)."""

from __future__ import annotations

import os
import stat
from pathlib import Path
from types import ModuleType

import pytest

from tests.benches import load

ROOT = Path(__file__).resolve().parents[1]

_VALGRIND = """#!/bin/sh
# (a stand-in: says what callgrind says of a process of as many runs as it was given)
runs=0
while [ $# -gt 0 ]; do
  if [ "$1" = "--runs" ]; then runs=$2; fi
  shift
done
echo "==1== Collected : $((10000000 + 5000000 * runs))" >&2
"""


def _bench() -> ModuleType:
    return load("sweep")


def test_instructions_are_counted_per_run_less_the_first(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    valgrind = tmp_path / "valgrind"
    valgrind.write_text(_VALGRIND)
    valgrind.chmod(valgrind.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("PATH", f"{tmp_path}{os.pathsep}{os.environ['PATH']}")
    scenario = str(ROOT / "scenarios" / "thesis" / "sample-01.xml")
    assert _bench().main(["--instructions", "--runs", "3", "--against", str(ROOT),
                          scenario]) == 0
    out = capsys.readouterr().out
    assert ("sample-01: 5.0 M instructions a judged run; the earlier build's 5.0 M: "
            "1.000x fewer") in out
    assert "(callgrind, runs 2 to 4 of a cold process)" in out


def test_instructions_without_valgrind_say_so(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(SystemExit, match="needs valgrind"):
        _bench().main(["--instructions", str(ROOT / "scenarios" / "thesis" / "sample-01.xml")])
