"""``bench/random_driver.py``: a worker process that dies stops the driver at once with
the seeds left unchecked named (it waited forever), and it starts no more workers than
it has chunks of seeds."""

from __future__ import annotations

import os
import signal
import sys
from types import ModuleType
from typing import Any

import pytest

from tests.benches import load


def _driver() -> ModuleType:
    return load("random_driver")


def dying_range(seeds: range) -> Any:
    """The chunk from seed 5 kills its worker (as the out-of-memory killer would)."""
    if seeds.start == 5:
        os.kill(os.getpid(), signal.SIGKILL)
    return sys.modules["random_driver_bench"].Tally(scenarios=len(seeds))


def test_a_dead_worker_stops_the_driver_and_names_the_seeds(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    driver = _driver()
    monkeypatch.setattr(driver, "CHUNK", 5)
    monkeypatch.setattr(driver, "run_range", dying_range)
    assert driver.main(["--scenarios", "20", "--jobs", "2"]) == 1
    out = capsys.readouterr().out
    assert "stopped: a worker process died (out of memory?); seeds not checked: " in out
    assert "5-9" in out and "Traceback" not in out
