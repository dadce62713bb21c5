"""A Dask cluster as a pool (the ``dask`` extra: Dask's ``distributed``): imported only
when ``--executor dask://HOST:PORT`` asks for one.

Chunks go to the cluster's workers through the client's own
:class:`concurrent.futures.Executor`, each with the documents its runs need (its
job's bundle), so a worker needs PRIMA installed and nothing else. A worker that
dies takes its tasks with it: the scheduler runs them again elsewhere, and a task
it gives up on (``KilledWorker``) is sent again by :func:`prima.batch.dispatch`.
"""

from __future__ import annotations

import concurrent.futures
from typing import Any

from prima.batch._dispatch import CHUNK

__all__ = ["Dask"]


class Dask:
    """The Dask cluster whose scheduler is at ``address`` (``tcp://HOST:PORT``, or any
    address Dask's client takes: an in-process cluster's too)."""

    chunk = CHUNK

    def __init__(self, address: str, timeout: float = 30.0) -> None:
        import distributed

        client: Any = distributed.Client  # (distributed's own functions are not typed)
        try:
            self.client: Any = client(address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise OSError(f"cannot reach the Dask scheduler at {address}: {exc}") from exc
        self.workers = max(1, sum(self.client.nthreads().values()))
        self._executor: concurrent.futures.Executor = self.client.get_executor(pure=False)

    def executor(self) -> concurrent.futures.Executor:
        return self._executor

    def broken(self, exc: BaseException) -> bool:
        return False  # the scheduler stays: a lost task is sent again to the others

    def stop(self) -> None:
        self._executor.shutdown(wait=False)
        self.client.close()

    def close(self) -> None:
        self._executor.shutdown(wait=True)
        self.client.close()
