"""Records (prima.record): one shared ``__repr__``, ``__eq__`` and ``__hash__``, the same as
the ones a dataclass compiles; and every dataclass a cold ``prima validate`` loads uses
them (the last two where it is frozen)."""

from __future__ import annotations

import dataclasses
import inspect
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from prima.interpreter._interpreter import _Handling, _Timer
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


@dataclass(frozen=True)
class GeneratedKeys:
    name: str
    size: float = 1.5
    note: str = field(default="", compare=False)
    seen: int = field(default=0, hash=False)
    forced: int = field(default=0, compare=False, hash=True)


@dataclass(frozen=True, repr=False, eq=False)
class SharedKeys(Record):
    name: str
    size: float = 1.5
    note: str = field(default="", compare=False)
    seen: int = field(default=0, hash=False)
    forced: int = field(default=0, compare=False, hash=True)


@dataclass(frozen=True, repr=False, eq=False)
class SharedOne(Record):
    name: str


@dataclass(frozen=True, repr=False, eq=False)
class SharedNone(Record):
    pass


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


NAN = float("nan")
KEYED = [("a", 1.5, "", 0, 0), ("a", 1.5, "other note", 0, 0), ("b", 1.5, "", 0, 0),
         ("a", 2.0, "", 0, 0), ("a", 1.5, "", 7, 0), ("a", 1.5, "", 0, 7), ("a", NAN, "", 0, 0)]
"""Fields of records to compare two by two: equal but for a field not compared, unequal in
one compared field, a hashed field not compared, a compared field not hashed, a NaN."""


def test_a_frozen_record_compares_and_hashes_as_its_generated_methods_would() -> None:
    for one in KEYED:
        for other in KEYED:
            generated = GeneratedKeys(*one) == GeneratedKeys(*other)
            assert (SharedKeys(*one) == SharedKeys(*other)) is generated, (one, other)
            assert (SharedKeys(*one) != SharedKeys(*other)) is not generated, (one, other)
        assert hash(SharedKeys(*one)) == hash(GeneratedKeys(*one)), one
        record = SharedKeys(*one)
        assert record == record  # (itself, even with a NaN: as tuples compare)
    assert SharedKeys("a") != GeneratedKeys("a")  # another class: never equal
    assert SharedKeys("a").__eq__(SharedOne("a")) is NotImplemented
    assert SharedOne("a") == SharedOne("a") != SharedOne("b")
    assert hash(SharedOne("a")) == hash(("a",))
    assert SharedNone() == SharedNone() and hash(SharedNone()) == hash(())
    assert len({SharedKeys("a"), SharedKeys("a", note="x"), SharedKeys("b")}) == 2


CHECK = """
import dataclasses, sys, types
from prima.cli import main
main(["validate", sys.argv[1]])
for name, module in sorted(sys.modules.items()):
    if name.startswith("prima"):
        for cls in vars(module).values():
            if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)
                    and cls.__module__ == name):
                continue
            params = cls.__dataclass_params__
            if params.repr or cls.__repr__ is not Record.__repr__:
                print(f"{name}.{cls.__qualname__} repr")
            # (an ``__eq__`` of its own written in Python; compiled, a class shows one
            # of mypyc's slot wrappers, which calls the ``__eq__`` it inherits)
            if params.frozen and not params.order and (
                    params.eq or isinstance(vars(cls).get("__eq__"), types.FunctionType)):
                print(f"{name}.{cls.__qualname__} eq")
"""


def test_every_dataclass_a_cold_validate_loads_shares_its_methods() -> None:
    """Each generated ``__repr__`` costs about half a million instructions to compile,
    in every process that imports it, and so do a frozen one's ``__eq__`` and ``__hash__``
    (one ordered keeps them: ``order`` needs ``eq``)."""
    document = "apps/fa/fa2-follow.pxml"
    done = subprocess.run([sys.executable, "-c", "from prima.record import Record\n" + CHECK,
                           document], capture_output=True, text=True, check=False,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 0, done.stderr
    assert "1 file checked" in done.stdout + done.stderr
    own = [line for line in done.stdout.splitlines() if "checked" not in line]
    assert own == [], ("declare these @dataclass(..., repr=False), derived from Record, "
                       "and eq=False too where frozen")


WRITTEN_OUT = [TraceLine, Pose, UserAction, Call, Outcome, Event, Blame, _Handling, _Timer]
"""Records whose ``__init__`` is written out (compiled, the one ``dataclass`` writes runs
as Python): each must take what the generated one would (the last two are not frozen)."""


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
    if cls.__dataclass_params__.frozen:
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(blank, params[0].name, None)
