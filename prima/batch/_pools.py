"""Which pool a command line asks for: ``--jobs`` and ``--executor``, and how long a Dask
cluster may keep a batch waiting (:class:`ClusterTimeouts`, from the environment)."""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping

from prima.batch._dispatch import Inline, Pool, Processes
from prima.batch._timeouts import TIMEOUTS, ClusterTimeouts

__all__ = ["TIMEOUTS", "ClusterTimeouts", "executor_problem", "pool_for"]

_DASK = re.compile(r"dask://(?P<host>[^\s:/]+|\[[0-9a-fA-F:.]+\]):(?P<port>[0-9]{1,5})/?")
EXECUTORS = "processes (the default) or dask://HOST:PORT"


_MAX_TIMEOUT = 1e6


def _timeouts(environ: Mapping[str, str]) -> ClusterTimeouts | str:
    """The timeouts the environment sets, or what is wrong with one."""
    given: dict[str, float] = {}
    for field, variable in TIMEOUTS.items():
        text = environ.get(variable)
        if text is None or not text.strip():
            continue
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not 0 < value <= _MAX_TIMEOUT:
            return (f"{variable}={text[:20]}: give a number of seconds above 0 and at most "
                    f"{_MAX_TIMEOUT:g}")
        given[field] = value
    return ClusterTimeouts(**given)


def _host_problem(host: str) -> str | None:
    """What is wrong with a host name as DNS sees it (at most 253 characters, each label
    at most 63), or None."""
    if host.startswith("["):
        return None
    if len(host) > 253:
        return f"the host name is {len(host)} characters long (at most 253)"
    if any(len(label) > 63 for label in host.split(".")):
        return "a part of the host name between dots is longer than 63 characters"
    return None


def executor_problem(executor: str | None,
                     environ: Mapping[str, str] | None = None) -> str | None:
    """What is wrong with an ``--executor`` (checked before anything runs), or None: for a
    Dask cluster, also the timeouts of :data:`TIMEOUTS` in ``environ`` (default: this
    process' environment)."""
    if executor is None or executor == "processes":
        return None
    match = _DASK.fullmatch(executor)
    shown = executor if len(executor) <= 60 else executor[:57] + "..."
    if match is None:
        return f"--executor {shown}: give {EXECUTORS}"
    if not 0 < int(match["port"]) < 65536:
        return f"--executor {shown}: the port must be from 1 to 65535"
    problem = _host_problem(match["host"])
    if problem:
        return f"--executor {shown}: {problem}"
    timeouts = _timeouts(os.environ if environ is None else environ)
    if isinstance(timeouts, str):
        return timeouts
    try:
        import distributed  # noqa: F401
    except ImportError:
        return ("Dask's distributed is not installed; install the dask extra: pip install "
                "'prima[dask]' (in a checkout of PRIMA: pip install -e '.[dask]')")
    return None


def pool_for(executor: str | None, jobs: int | None, runs: int) -> Pool:
    """The pool for ``--executor`` and ``--jobs``: this machine's processes (``jobs``,
    default every core, never more than ``runs``; one: this process), or the Dask
    cluster at ``dask://HOST:PORT``, waited for as long as :data:`TIMEOUTS` say. Raises
    ClusterError when the cluster cannot take the runs."""
    if executor is not None and executor != "processes":
        match = _DASK.fullmatch(executor)
        problem = executor_problem(executor)
        if match is None or problem is not None:
            raise ValueError(problem or executor)
        from prima.batch._dask import Dask

        timeouts = _timeouts(os.environ)
        if isinstance(timeouts, str):  # (executor_problem says so first)
            raise ValueError(timeouts)
        return Dask(f"tcp://{match['host']}:{match['port']}", timeouts)
    workers = min(jobs or os.cpu_count() or 1, runs)
    return Inline() if workers <= 1 else Processes(workers)
