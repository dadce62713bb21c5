"""Records: dataclasses that share one ``__repr__`` instead of each compiling its own.

Python 3.11's ``dataclass`` writes each method it adds (``__init__``, ``__repr__``,
``__eq__``, ...) as source and compiles it, one method at a time: about half a million
instructions each, at import. A cold ``prima validate`` imports about fifty dataclasses,
and compiling their methods was about a third of its instructions. A class declared
``@dataclass(..., repr=False)`` that derives from :class:`Record` shows as the generated
``__repr__`` would have shown it, from this one method (``test_record.py`` checks both).
"""

from __future__ import annotations

import reprlib
from dataclasses import fields
from typing import Any

__all__ = ["Record"]


class Record:
    """A base for a dataclass declared with ``repr=False``: its ``__repr__``."""

    __slots__ = ()

    @reprlib.recursive_repr()
    def __repr__(self) -> str:
        this: Any = self  # (a dataclass, which the type of ``self`` cannot say)
        shown = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in fields(this) if f.repr)
        return f"{type(self).__qualname__}({shown})"
