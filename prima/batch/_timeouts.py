"""How long a Dask cluster may keep a batch waiting, and the environment variables that
say so: apart from the pools (:mod:`._pools`) and the cluster (:mod:`._dask`), which
both read them, so neither imports the other to learn them."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["TIMEOUTS", "ClusterTimeouts"]


@dataclass(frozen=True)
class ClusterTimeouts:
    """How long (s) a batch waits for a Dask cluster before it stops with an error
    (:class:`~prima.errors.ClusterError`), the runs done kept."""

    connect: float = 30.0
    """For the scheduler to answer (at the start, and again after it went silent)."""
    worker: float = 60.0
    """For a worker to join the scheduler (at the start, and after the last one left)."""
    progress: float = 600.0
    """For a run to finish while runs are out (a cluster that takes tasks and never
    finishes one)."""


TIMEOUTS = {"connect": "PRIMA_DASK_CONNECT_TIMEOUT", "worker": "PRIMA_DASK_WORKER_TIMEOUT",
            "progress": "PRIMA_DASK_PROGRESS_TIMEOUT"}
"""The environment variable that sets each of :class:`ClusterTimeouts` (seconds)."""
