"""Records: dataclasses that share one ``__repr__`` instead of each compiling its own.

Python 3.11's ``dataclass`` writes each method it adds (``__init__``, ``__repr__``,
``__eq__``, ...) as source and compiles it, one method at a time: about half a million
instructions each, at import. A cold ``prima validate`` imports about fifty dataclasses,
and compiling their methods was about a third of its instructions. A class declared
``@dataclass(..., repr=False)`` that derives from :class:`Record` shows as the generated
``__repr__`` would have shown it, from this one method (``test_record.py`` checks both).

The compiled build compiles this module: the records of its compiled modules (the
catalog's) are then compiled classes, which compiled code reads at C speed, and those of
the rest derive from a compiled class, which ``mypyc_attr`` allows.
"""

from __future__ import annotations

from _thread import get_ident
from collections.abc import Callable
from dataclasses import fields
from typing import Any, TypeVar

_T = TypeVar("_T")

_COMPILER = False
"""Never true: the compiler, reading both branches below, takes ``mypyc_attr`` by its
name; at run time nothing imports mypy's (an import, or a failed one, is about a
millisecond of a cold start)."""

if _COMPILER:
    from mypy_extensions import mypyc_attr
else:
    def mypyc_attr(*_attrs: str, **_kwattrs: object) -> Callable[[_T], _T]:
        return lambda cls: cls

__all__ = ["Record"]

_showing: set[tuple[int, int]] = set()
"""The records being shown, each with its thread: one met again inside its own
``__repr__`` shows as ``...`` (what ``reprlib.recursive_repr`` does, which a compiled
method cannot take)."""


@mypyc_attr(allow_interpreted_subclasses=True)
class Record:
    """A base for a dataclass declared with ``repr=False``: its ``__repr__``."""

    __slots__ = ()

    def __repr__(self) -> str:
        key = (id(self), get_ident())
        if key in _showing:
            return "..."
        _showing.add(key)
        try:
            this: Any = self  # (a dataclass, which the type of ``self`` cannot say)
            shown = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in fields(this)
                              if f.repr)
        finally:
            _showing.discard(key)
        return f"{type(self).__qualname__}({shown})"
