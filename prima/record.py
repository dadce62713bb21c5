"""Records: dataclasses that share one ``__repr__``, and one ``__eq__`` and ``__hash__``,
instead of each compiling its own.

Python 3.11's ``dataclass`` writes each method it adds (``__init__``, ``__repr__``,
``__eq__``, ...) as source and compiles it, one method at a time: about half a million
instructions each, at import. A cold ``prima validate`` imports about fifty dataclasses,
and compiling their methods was about a third of its instructions. A class declared
``@dataclass(..., repr=False)`` that derives from :class:`Record` shows as the generated
``__repr__`` would have shown it, from this one method; one declared ``@dataclass(frozen=True,
repr=False, eq=False)`` compares and hashes as the generated ``__eq__`` and ``__hash__``
would (its fields' values in a tuple, with ``compare`` and ``hash`` as ``field`` says),
from the two methods here (``test_record.py`` checks all three). (``eq=False`` only with
``frozen=True``: a mutable record must stay unhashable, as ``dataclass`` makes it.)

The compiled build compiles this module: the records of its compiled modules (the
catalog's) are then compiled classes, which compiled code reads at C speed, and those of
the rest derive from a compiled class, which ``mypyc_attr`` allows.
"""

from __future__ import annotations

from _thread import get_ident
from collections.abc import Callable
from dataclasses import Field, fields
from operator import attrgetter
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


_Key = Callable[[Any], tuple[object, ...]]

_keys: dict[type, tuple[_Key, _Key]] = {}
"""Each record class's two keys, made on their first use: the tuple of its fields'
values it is compared by, and the one it is hashed by."""


def _key(names: list[str]) -> _Key:
    """What reads the fields ``names`` of a record, as a tuple (``attrgetter`` gives
    one only for two names or more)."""
    if len(names) > 1:
        return attrgetter(*names)
    if names:
        one = attrgetter(names[0])
        return lambda record: (one(record),)
    return lambda _record: ()


def _keys_of(cls: type) -> tuple[_Key, _Key]:
    found = _keys.get(cls)
    if found is None:
        this: Any = cls  # (a dataclass, which the type of ``cls`` cannot say)
        every: tuple[Field[Any], ...] = fields(this)
        found = _keys[cls] = (
            _key([f.name for f in every if f.compare]),
            _key([f.name for f in every if (f.compare if f.hash is None else f.hash)]))
    return found


@mypyc_attr(allow_interpreted_subclasses=True)
class Record:
    """A base for a dataclass declared with ``repr=False``: its ``__repr__``; and, declared
    ``frozen=True, eq=False`` too, its ``__eq__`` and ``__hash__``."""

    __slots__ = ()

    def __eq__(self, other: object) -> bool:
        """As the generated one: records of one class whose compared fields are equal, as
        tuples compare (a value is equal to itself, even a NaN)."""
        if other.__class__ is not self.__class__:
            return NotImplemented
        key = _keys_of(type(self))[0]
        return key(self) == key(other)

    def __hash__(self) -> int:
        """As the generated one of a frozen dataclass: the hash of its hashed fields' tuple."""
        return hash(_keys_of(type(self))[1](self))

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
