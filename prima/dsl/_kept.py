"""What the loader keeps from one document to the next, for a process that checks the
same texts again and again (``prima lsp``, at every pause in the typing).

Only inside :func:`keeping` does the loader keep and replay anything: a chain
bound without a problem, a top-level state built without one. Elsewhere (``prima
validate``, ``prima run``) every document is built afresh, as before, at no cost.
The :class:`Kept` object is its owner's (the language server's workspace), not the
process's.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Generic, TypeVar

__all__ = ["MAX_KEPT_CHAINS", "MAX_KEPT_TEXT", "Kept", "keeping", "kept_now"]

MAX_KEPT_TEXT = 2 << 20
"""Most characters of states kept in all (the least recently used go first): a bound on
the memory untrusted documents can make a process keep."""

MAX_KEPT_CHAINS = 4096
"""Most chains kept (each at most :data:`~prima.dsl._expr.MEMO_TEXT` characters)."""

V = TypeVar("V")


class Store(Generic[V]):
    """Values by key, the least recently used going first past ``limit`` in size."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self._values: OrderedDict[tuple[object, ...], tuple[V, int]] = OrderedDict()
        self._size = 0

    def get(self, key: tuple[object, ...]) -> V | None:
        found = self._values.get(key)
        if found is None:
            return None
        self._values.move_to_end(key)
        return found[0]

    def put(self, key: tuple[object, ...], value: V, size: int = 1) -> None:
        if key in self._values:
            return
        self._values[key] = (value, size)
        self._size += size
        while self._size > self.limit:
            _old, (_gone, gone_size) = self._values.popitem(last=False)
            self._size -= gone_size

    def __len__(self) -> int:
        return len(self._values)


class Kept:
    """The chains and states one owner keeps (see the module): the binder's
    :class:`~prima.dsl._commands.KeptChain` and the loader's
    :class:`~prima.dsl._loader.KeptState`, which each asks back for by its own type (this
    module imports neither, so neither imports it back through the other)."""

    def __init__(self) -> None:
        self.chains: Store[object] = Store(MAX_KEPT_CHAINS)
        self.states: Store[object] = Store(MAX_KEPT_TEXT)


_KEPT: ContextVar[Kept | None] = ContextVar("prima_kept", default=None)


@contextmanager
def keeping(kept: Kept) -> Iterator[Kept]:
    """While inside, documents built keep what they can in ``kept`` and replay what it
    holds (in this thread or task)."""
    token = _KEPT.set(kept)
    try:
        yield kept
    finally:
        _KEPT.reset(token)


def kept_now() -> Kept | None:
    """What the documents built now keep, if anything (:func:`keeping`)."""
    return _KEPT.get()
