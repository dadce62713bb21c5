"""A Dask cluster as a pool (the ``dask`` extra: Dask's ``distributed``): imported only
when ``--executor dask://HOST:PORT`` asks for one.

Chunks go to the cluster's workers through the client's own
:class:`concurrent.futures.Executor`, each with the documents its runs need (its
job's bundle), so a worker needs PRIMA installed and nothing else. A worker that
dies takes its tasks with it: the scheduler runs them again elsewhere, and a task
it gives up on (``KilledWorker``) is sent again by :func:`prima.batch.dispatch`.

A cluster that cannot take the work never leaves a batch waiting for ever: each
wait is bounded (:class:`~._timeouts.ClusterTimeouts`) and ends with a
:class:`~prima.errors.ClusterError`, the runs done kept. The scheduler must answer
Dask's own handshake within the connect timeout (distributed's client waits for
that answer without one: a port that accepts and never answers, or an HTTP server,
would hold it for ever), a worker must join within the worker timeout, and while
runs are out :meth:`Dask.watch` asks the scheduler every :attr:`Dask.poll` seconds
whether it is there and has workers, and gives up when no run finished for the
progress timeout.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import time
from typing import Any

from prima.batch._dispatch import CHUNK
from prima.batch._timeouts import TIMEOUTS, ClusterTimeouts
from prima.errors import ClusterError

__all__ = ["Dask"]


def _identity(address: str, timeout: float) -> dict[str, Any]:
    """The scheduler's answer to Dask's handshake and ``identity``, within ``timeout``
    seconds in all (in an event loop of its own). Raises ClusterError."""
    from distributed.comm.core import connect as untyped

    connect: Any = untyped  # (distributed's own functions are not typed)

    async def ask() -> Any:
        comm = await connect(address, timeout=timeout)  # (its handshake has no timeout)
        try:
            await comm.write({"op": "identity", "reply": True, "n_workers": 0})
            return await comm.read()
        finally:
            comm.abort()

    async def bounded() -> Any:
        return await asyncio.wait_for(ask(), timeout)

    try:
        answer = asyncio.run(bounded())
    except TimeoutError:
        raise ClusterError(f"the Dask scheduler at {address} did not answer within "
                           f"{timeout:g} s ({TIMEOUTS['connect']}): is a Dask scheduler "
                           "listening there?") from None
    except OSError as exc:  # (a host name that does not resolve, say)
        cause = exc.__cause__ or exc.__context__
        why = cause.strerror if isinstance(cause, OSError) and cause.strerror else None
        raise ClusterError(f"cannot reach the Dask scheduler at {address}: "
                           f"{why or exc.strerror or exc}") from None
    except Exception as exc:  # noqa: BLE001 - what a server that is no Dask's says
        raise ClusterError(f"cannot reach the Dask scheduler at {address}: "
                           f"{type(exc).__name__}: {str(exc)[:200]}") from None
    if not isinstance(answer, dict) or answer.get("type") != "Scheduler":
        raise ClusterError(f"what listens at {address} is not a Dask scheduler")
    return answer


class Dask:
    """The Dask cluster whose scheduler is at ``address`` (``tcp://HOST:PORT``, or any
    address Dask's client takes: an in-process cluster's too), waited for no longer
    than ``timeouts`` say. Raises ClusterError when it cannot take the work."""

    chunk = CHUNK

    def __init__(self, address: str, timeouts: ClusterTimeouts | None = None) -> None:
        import distributed

        self.address = address
        self.timeouts = timeouts = timeouts or ClusterTimeouts()
        self.poll = min(2.0, timeouts.connect, timeouts.worker, timeouts.progress)
        """Seconds between two looks at the cluster while no run finishes."""
        self._silent_since: float | None = None
        self._idle_since: float | None = None
        _identity(address, timeouts.connect)
        self._logs = _Quiet()  # (its own lines would say what ClusterError says, in pieces)
        client: Any = distributed.Client  # (distributed's own functions are not typed)
        try:
            self.client: Any = client(address, timeout=timeouts.connect, set_as_default=False)
        except BaseException as exc:
            self._logs.restore()
            if isinstance(exc, Exception):
                raise ClusterError(f"cannot reach the Dask scheduler at {address}: "
                                   f"{exc}") from None
            raise
        try:
            self.workers = self._first_workers()
            self._executor: concurrent.futures.Executor = self.client.get_executor(pure=False)
        except BaseException:
            self.stop()
            raise

    def _ask(self) -> dict[str, Any]:
        """The scheduler's ``identity`` (how many workers and threads), within the connect
        timeout; ClusterError when it is gone or silent."""
        if self.client.status in ("closing", "closed"):
            raise self._lost()
        try:
            answer: dict[str, Any] = self.client.sync(self.client.scheduler.identity,
                                                      n_workers=0,
                                                      callback_timeout=self.timeouts.connect)
        except Exception:  # noqa: BLE001 - gone, or silent: either way, lost
            raise self._lost() from None
        return answer

    def _lost(self) -> ClusterError:
        return ClusterError(f"lost the Dask scheduler at {self.address}: it went away or "
                            f"did not answer within {self.timeouts.connect:g} s "
                            f"({TIMEOUTS['connect']})")

    def _first_workers(self) -> int:
        """Wait for a worker to join (at most the worker timeout): the threads there are."""
        deadline = time.monotonic() + self.timeouts.worker
        while True:
            answer = self._ask()
            if answer.get("n_workers"):
                return max(1, int(answer.get("total_threads") or 1))
            left = deadline - time.monotonic()
            if left <= 0:
                raise self._no_worker()
            time.sleep(min(self.poll, left))

    def _no_worker(self, left: bool = False) -> ClusterError:
        said = (f"the Dask scheduler at {self.address} had no worker for" if left
                else f"no worker joined the Dask scheduler at {self.address} within")
        return ClusterError(f"{said} {self.timeouts.worker:g} s ({TIMEOUTS['worker']}): "
                            f"start one with: dask worker {self.address}")

    def executor(self) -> concurrent.futures.Executor:
        return self._executor

    def broken(self, exc: BaseException) -> bool:
        """A task failed: the scheduler stays (its lost tasks are sent again to the other
        workers) unless it went away itself (ClusterError)."""
        if self.client.status != "running":
            raise self._lost()
        return False

    def watch(self, idle: float) -> None:
        """No run finished for ``idle`` seconds: ClusterError if the scheduler is gone or
        silent, has had no worker for the worker timeout, or no run finished for the
        progress timeout."""
        now = time.monotonic()
        answer = self._ask()
        if answer.get("n_workers"):
            self._idle_since = None
        elif self._idle_since is None:
            self._idle_since = now
        elif now - self._idle_since > self.timeouts.worker:
            raise self._no_worker(left=True)
        if idle > self.timeouts.progress:
            raise ClusterError(f"no run finished on the Dask cluster at {self.address} for "
                               f"{self.timeouts.progress:g} s ({TIMEOUTS['progress']})")

    def stop(self) -> None:
        executor = getattr(self, "_executor", None)
        if executor is not None:
            executor.shutdown(wait=False)
        self._close()

    def close(self) -> None:
        self._executor.shutdown(wait=True)
        self._close()

    def _close(self) -> None:
        """Let the client go (within the connect timeout, whatever the scheduler does)."""
        try:
            self.client.close(timeout=self.timeouts.connect)
        except Exception:  # noqa: BLE001,S110 - a scheduler already gone: nothing to close
            pass
        finally:
            self._logs.restore()


class _Quiet:
    """distributed's loggers silenced while a pool uses the cluster (its client logs a
    lost scheduler in lines of its own, at ERROR); restored when it is done."""

    NAMES = ("distributed", "distributed.client", "tornado")

    def __init__(self) -> None:
        self.levels = {name: logging.getLogger(name).level for name in self.NAMES}
        for name in self.NAMES:
            logging.getLogger(name).setLevel(logging.CRITICAL + 1)

    def restore(self) -> None:
        for name, level in self.levels.items():
            logging.getLogger(name).setLevel(level)
