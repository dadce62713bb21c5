"""Shared by every test: tests marked ``pure`` run only against the pure Python build,
and are skipped against the compiled one (``prima.compiled()``). They change PRIMA's
classes or modules at run time (to plant a fault, to count calls, to subclass), which
compiled classes and modules do not allow, or copy its source as a build of its own.

And the tests that take seconds each are marked ``slow`` here, in one table
(:data:`SLOW`): ``python -m pytest -m 'not slow'`` is the quick subset for daily work
(README); CI runs them all.

A test process started with Ctrl-C ignored (a shell's background job: ``pytest &``)
takes it back: the commands its tests start inherit an ignored SIGINT, as a shell's
background job does, and the tests that stop a command with SIGINT found it going on."""

from __future__ import annotations

import signal

import pytest

import prima

if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:  # (see above)
    signal.signal(signal.SIGINT, signal.default_int_handler)


SLOW = (
    "tests/audio/",  # a page played in headless Chromium, with espeak-ng's sound
    "tests/live/",  # prima live's server and page, in headless Chromium
    "tests/show/test_show.py::test_the_page_in_a_browser",  # every shipped page, in Chromium
    "tests/batch/test_cluster.py",  # a Dask cluster started, killed and resumed
    "tests/test_wheel.py",  # (marked in its module too) the wheel built and installed
    "tests/dsl/test_fastparse.py::test_chains_parse_alike",  # a minute of generated chains
    "tests/mediator/test_random_driver.py::test_the_oracle_catches",  # mutants, many runs
    "tests/mediator/test_random_driver.py::test_thousands_of_random_scenarios",
    "tests/mediator/test_idle_rounds.py::test_a_round_skipped_as_idle",
    "tests/test_interrupt.py::test_a_sweep",  # sweeps stopped by signals, then resumed
    "tests/test_interrupt.py::test_a_signal_at_any_moment_of_a_sweep",
    "tests/scenario/test_validate_places.py::test_the_cost_stays_linear",  # CPU time at two sizes
    "tests/test_term.py::test_colour_on_a_terminal_only",  # each command under a pty
    "tests/check/test_check.py::test_the_example_ea_written_from_the_docs_passes_every_cell",
)
"""Node ids (or their beginnings) of the tests that take seconds each: each is marked
``slow``."""


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    slow = pytest.mark.slow
    for item in items:
        if item.nodeid.startswith(SLOW):
            item.add_marker(slow)
    if not prima.compiled():
        return
    skip = pytest.mark.skip(reason="the pure build only (changes PRIMA at run time, or copies it)")
    for item in items:
        if item.get_closest_marker("pure") is not None:
            item.add_marker(skip)
