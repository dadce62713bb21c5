"""Which pool a command line asks for: ``--jobs`` and ``--executor``."""

from __future__ import annotations

import os
import re

from prima.batch._dispatch import Inline, Pool, Processes

__all__ = ["executor_problem", "pool_for"]

_DASK = re.compile(r"dask://(?P<host>[^\s:/]+|\[[0-9a-fA-F:.]+\]):(?P<port>[0-9]{1,5})/?")
EXECUTORS = "processes (the default) or dask://HOST:PORT"


def executor_problem(executor: str | None) -> str | None:
    """What is wrong with an ``--executor`` (checked before anything runs), or None."""
    if executor is None or executor == "processes":
        return None
    match = _DASK.fullmatch(executor)
    if match is None:
        return f"--executor {executor}: give {EXECUTORS}"
    if not 0 < int(match["port"]) < 65536:
        return f"--executor {executor}: the port must be from 1 to 65535"
    try:
        import distributed  # noqa: F401
    except ImportError:
        return ("Dask's distributed is not installed; install the dask extra: pip install "
                "'prima[dask]' (in a checkout of PRIMA: pip install -e '.[dask]')")
    return None


def pool_for(executor: str | None, jobs: int | None, runs: int) -> Pool:
    """The pool for ``--executor`` and ``--jobs``: this machine's processes (``jobs``,
    default every core, never more than ``runs``; one: this process), or the Dask
    cluster at ``dask://HOST:PORT``. Raises OSError when the cluster cannot be reached."""
    if executor is not None and executor != "processes":
        match = _DASK.fullmatch(executor)
        if match is None:
            raise ValueError(executor_problem(executor) or executor)
        from prima.batch._dask import Dask

        return Dask(f"tcp://{match['host']}:{match['port']}")
    workers = min(jobs or os.cpu_count() or 1, runs)
    return Inline() if workers <= 1 else Processes(workers)
