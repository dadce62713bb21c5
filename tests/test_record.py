"""Records (prima.record): one shared ``__repr__``, the same as the one a dataclass
compiles; and every dataclass a cold ``prima validate`` loads uses it."""

from __future__ import annotations

import dataclasses
import inspect
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from prima.judge import Blame
from prima.mediator import Call, Event, Outcome
from prima.record import Record
from prima.sim import Pose, UserAction
from prima.trace import TraceLine


@dataclass(frozen=True)
class Generated:
    name: str
    size: float = 1.5
    parts: tuple[object, ...] = ()
    hidden: int = field(default=0, repr=False)


@dataclass(frozen=True, repr=False)
class Shared(Record):
    name: str
    size: float = 1.5
    parts: tuple[object, ...] = ()
    hidden: int = field(default=0, repr=False)


@dataclass
class GeneratedLoop:
    items: list[object]


@dataclass(repr=False)
class SharedLoop(Record):
    items: list[object]


def test_a_record_shows_as_its_generated_repr_would() -> None:
    generated = Generated("a'b", 2.0, (Generated("x"), None), hidden=3)
    shared = Shared("a'b", 2.0, (Shared("x"), None), hidden=3)
    assert repr(shared) == repr(generated).replace("Generated", "Shared")
    assert repr(shared) == "Shared(name=\"a'b\", size=2.0, parts=(Shared(name='x', size=1.5, " \
                           "parts=()), None))"


def test_a_record_that_holds_itself_shows_dots_there() -> None:
    generated, shared = GeneratedLoop([]), SharedLoop([])
    generated.items.append(generated)
    shared.items.append(shared)
    assert repr(shared) == repr(generated).replace("Generated", "Shared") \
        == "SharedLoop(items=[...])"


CHECK = """
import dataclasses, sys
from prima.cli import main
main(["validate", sys.argv[1]])
for name, module in sorted(sys.modules.items()):
    if name.startswith("prima"):
        for cls in vars(module).values():
            if (isinstance(cls, type) and dataclasses.is_dataclass(cls)
                    and cls.__module__ == name and (cls.__dataclass_params__.repr
                                                    or cls.__repr__ is not Record.__repr__)):
                print(f"{name}.{cls.__qualname__}")
"""


def test_every_dataclass_a_cold_validate_loads_shares_the_repr() -> None:
    """Each generated ``__repr__`` costs about half a million instructions to compile,
    in every process that imports it."""
    document = "apps/fa/fa2-follow.pxml"
    done = subprocess.run([sys.executable, "-c", "from prima.record import Record\n" + CHECK,
                           document], capture_output=True, text=True, check=False,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 0, done.stderr
    assert "1 file checked" in done.stdout + done.stderr
    own = [line for line in done.stdout.splitlines() if "checked" not in line]
    assert own == [], "declare these @dataclass(..., repr=False), derived from Record"


WRITTEN_OUT = [TraceLine, Pose, UserAction, Call, Outcome, Event, Blame]
"""Frozen records whose ``__init__`` is written out (compiled, the one ``dataclass``
writes runs as Python): each must take what the generated one would."""


@pytest.mark.pure  # (compiled, a method's signature is not kept)
@pytest.mark.parametrize("cls", WRITTEN_OUT, ids=lambda c: c.__name__)
def test_a_written_out_init_takes_the_fields_in_order_with_their_defaults(
        cls: type[Any]) -> None:
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    assert [p.name for p in params] == [f.name for f in dataclasses.fields(cls) if f.init]
    blank = cls(*[object() for p in params if p.default is inspect.Parameter.empty])
    for f, p in zip(dataclasses.fields(cls), params, strict=True):
        if f.default is not dataclasses.MISSING:
            assert p.default == f.default and getattr(blank, f.name) == f.default, f.name
        elif f.default_factory is not dataclasses.MISSING:
            assert getattr(blank, f.name) == f.default_factory(), f.name
        else:
            assert p.default is inspect.Parameter.empty, f.name
    given = [object() for _ in params]
    assert [getattr(cls(*given), p.name) for p in params] == given
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(blank, params[0].name, None)
