"""A Dask cluster that cannot take a batch's runs is a clear error within a bounded time,
never a wait for ever: a port that accepts and never answers, an HTTP server, a
scheduler without workers, one killed mid-sweep, one whose workers stall. The runs done
stay in the results file, and ``--resume`` goes on with the rest.

The timeouts are made small here (``ClusterTimeouts``, or the environment variables a
command reads); every wait on a process of the test's own has a generous bound."""

from __future__ import annotations

import http.server
import io
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import prima.batch._dispatch
from prima.batch import Chunk, Inline
from prima.batch._pools import ClusterTimeouts
from prima.cli import main
from prima.errors import ClusterError
from prima.sweep import sweep

distributed = pytest.importorskip("distributed")

from prima.batch._dask import Dask  # noqa: E402 - (with the dask extra only)

ROOT = Path(__file__).parents[2]
TOUCHED = ROOT / "scenarios" / "thesis" / "sample-08.xml"
SHORT = ROOT / "scenarios" / "thesis" / "fig5-7.xml"
QUICK = ClusterTimeouts(connect=0.5, worker=0.5, progress=0.5)
BOUND = 60.0
"""Seconds any wait of these tests may take at most (they take a few)."""


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture
def silent_port() -> Iterator[int]:
    """A port that accepts connections (the kernel's backlog) and never answers."""
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen(8)
        yield listener.getsockname()[1]


@pytest.fixture
def http_port() -> Iterator[int]:
    """A port where an HTTP server answers (what Dask's handshake is not)."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0),
                                             http.server.SimpleHTTPRequestHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server.server_address[1]
    server.shutdown()
    server.server_close()


@pytest.mark.parametrize("port", ["silent_port", "http_port"])
def test_a_port_that_is_no_scheduler_is_an_error_within_the_connect_timeout(
        port: str, request: pytest.FixtureRequest) -> None:
    address = f"tcp://127.0.0.1:{request.getfixturevalue(port)}"
    start = time.monotonic()
    with pytest.raises(ClusterError, match=re.escape(
            f"the Dask scheduler at {address} did not answer within 0.5 s "
            "(PRIMA_DASK_CONNECT_TIMEOUT)")):
        Dask(address, QUICK)
    assert time.monotonic() - start < BOUND


def test_a_sweep_to_a_silent_port_says_so_in_one_line(
        silent_port: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PRIMA_DASK_CONNECT_TIMEOUT", "0.5")
    code, _, err = cli("sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--worst", "0",
                       "--executor", f"dask://127.0.0.1:{silent_port}")
    assert code == 1 and err.count("\n") == 1, err
    assert err.startswith("prima sweep: error: the Dask scheduler at tcp://127.0.0.1:")


def test_a_scheduler_without_workers_is_an_error_within_the_worker_timeout() -> None:
    with distributed.LocalCluster(n_workers=0, processes=False,
                                  dashboard_address=None) as cluster:
        start = time.monotonic()
        with pytest.raises(ClusterError, match="no worker joined the Dask scheduler at .* "
                                               "within 0.5 s .PRIMA_DASK_WORKER_TIMEOUT."):
            Dask(cluster.scheduler_address, ClusterTimeouts(connect=5, worker=0.5))
        assert time.monotonic() - start < BOUND


_RUN_CHUNK = prima.batch._dispatch.run_chunk
_RELEASE = threading.Event()


def _stalled(chunk: Chunk) -> list[dict[str, Any]]:
    """A worker that takes the tasks after the first and never ends them (until the test
    is over). At module level: Dask sends it to the worker threads by name."""
    if chunk.first > 0:
        _RELEASE.wait(BOUND)
    return _RUN_CHUNK(chunk)


def test_a_cluster_that_finishes_no_run_is_an_error_within_the_progress_timeout(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(prima.batch._dispatch, "run_chunk", _stalled)
    target = tmp_path / "r.jsonl"
    _RELEASE.clear()
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        pool = Dask(cluster.scheduler_address, ClusterTimeouts(connect=5, worker=5,
                                                               progress=0.5))
        try:
            with pytest.raises(ClusterError, match="no run finished on the Dask cluster at "
                                                   ".* for 0.5 s .PRIMA_DASK_PROGRESS"):
                sweep(TOUCHED, runs=6, jitter=5.0, seed=2, results=target, pool=pool)
        finally:
            _RELEASE.set()
    assert len(target.read_text().splitlines()) == 2  # the header, and run 0's record


def _started(argv: list[str], log: Path, marker: str) -> tuple[subprocess.Popen[bytes], str]:
    """A process of ``argv`` whose output goes to ``log``, once ``marker`` (a regular
    expression) is in it: the process and what matched."""
    process = subprocess.Popen(argv, stdout=log.open("wb"), stderr=subprocess.STDOUT)
    deadline = time.monotonic() + BOUND
    while time.monotonic() < deadline:
        found = re.search(marker, log.read_text(errors="replace"))
        if found:
            return process, found.group(1)
        if process.poll() is not None:
            break
        time.sleep(0.1)
    process.kill()
    raise AssertionError(f"{argv[:3]} did not start: {log.read_text(errors='replace')}")


def test_a_scheduler_killed_mid_sweep_is_an_error_and_the_runs_done_resume(
        tmp_path: Path) -> None:
    dask = str(Path(sys.executable).with_name("dask"))
    scheduler, address = _started([dask, "scheduler", "--port", "0", "--no-dashboard"],
                                  tmp_path / "scheduler.log", r"Scheduler at:\s*(tcp://\S+)")
    worker, _ = _started([dask, "worker", address, "--nthreads", "1", "--no-dashboard",
                          "--no-nanny"], tmp_path / "worker.log", r"(Registered to)")
    target = tmp_path / "r.jsonl"
    try:
        def kill(done: int, total: int) -> None:
            if scheduler.poll() is None:
                scheduler.send_signal(signal.SIGKILL)

        start = time.monotonic()
        with pytest.raises(ClusterError, match=re.escape(
                f"lost the Dask scheduler at {address}") + ".*; the [1-9][0-9]* run.s. done are "
                f"in {re.escape(str(target))}: --resume"):
            sweep(TOUCHED, runs=40, jitter=5.0, seed=2, results=target, progress=kill,
                  pool=Dask(address, ClusterTimeouts(connect=1, worker=5, progress=30)))
        assert time.monotonic() - start < BOUND
    finally:
        for process in (worker, scheduler):
            process.kill()
            process.wait(BOUND)
    done = len(target.read_text().splitlines()) - 1
    assert 0 < done < 40
    resumed = sweep(TOUCHED, runs=40, jitter=5.0, seed=2, results=target, resume=True,
                    pool=Inline())
    assert resumed.done == 40
    whole = tmp_path / "whole.jsonl"
    sweep(TOUCHED, runs=40, jitter=5.0, seed=2, results=whole, pool=Inline())
    assert target.read_bytes() == whole.read_bytes()


@pytest.mark.parametrize("executor, env, fragment", [
    ("dask://" + "a" * 300 + ":8786", {}, "the host name is 300 characters long (at most 253)"),
    ("dask://" + "a" * 64 + ".example:8786", {}, "longer than 63 characters"),
    ("dask://host:8786", {"PRIMA_DASK_WORKER_TIMEOUT": "soon"},
     "PRIMA_DASK_WORKER_TIMEOUT=soon: give a number of seconds above 0"),
    ("dask://host:8786", {"PRIMA_DASK_PROGRESS_TIMEOUT": "0"},
     "PRIMA_DASK_PROGRESS_TIMEOUT=0: give a number of seconds above 0"),
])
def test_a_cluster_that_cannot_be_asked_is_a_usage_error_at_once(
        executor: str, env: dict[str, str], fragment: str,
        monkeypatch: pytest.MonkeyPatch) -> None:
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    code, _, err = cli("sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--executor",
                       executor)
    assert code == 2 and fragment in err, err

