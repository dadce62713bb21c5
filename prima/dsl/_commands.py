"""Binding Command arguments, from the element form and from the chain notation.

Both forms end in the same :class:`~prima.dsl.CommandCall`: arguments
are compiled according to the parameter's kind (text is a template, numbers
are literals or expressions, places and gestures are bare names or
``{expression}``), then checked against the Command's signature.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

from lxml import etree

from prima.catalog import EXTRAS_ACTED_ON, SYMBOLIC_KINDS, CommandSpec, Param, ParamKind, Range
from prima.dsl._binder import Spot
from prima.dsl._elements import children
from prima.dsl._expr import (
    MEMO_TEXT,
    ChainArg,
    ChainStep,
    Compiled,
    Scope,
    bare_name,
    compile_chain_arg,
    compile_expression,
    compile_template,
    constant,
    span,
    string_literal,
)
from prima.dsl._model import CommandCall
from prima.dsl._profile import RobotProfile
from prima.record import Record
from prima.vocab import MAX_NUMBER, AppKind
from prima.xmlio import local_name

if TYPE_CHECKING:
    from prima.dsl._binder import Binder as Builder

    Extra = tuple[str, Spot, Callable[[], Compiled | None]]
    """An additional argument as written: its name, where, and how to compile its value."""

_COMPUTED = re.compile(r"^\{(.*)\}$", re.S)
COMMANDS_HINT = "; see docs/pxml.md for the Commands"
"""Appended to an unknown Command's error."""

_DOCUMENT_NAMES = frozenset({ParamKind.GRAMMAR, ParamKind.VARIABLE})
"""Kinds of argument that name something the document declares (a Q&A's grammar
and variable): they are checked against the document, not passed to the robot."""


def element_name(command: str) -> str:
    """The element of a common Command: ``TopologicalMove`` -> ``topological-move``."""
    return re.sub(r"(?<=[a-z])(?=[A-Z])", "-", command).lower()


def compile_attribute(b: Builder, kind: ParamKind, el: etree._Element,
                      attr: str) -> Compiled | None:
    """Compile an argument written as an attribute value, by its parameter kind."""
    raw = el.get(attr, "")
    spot: Spot = (el, attr, 0)
    if kind is ParamKind.TEXT:
        return b.compile(spot, lambda: compile_template(raw, max_text=b.max_text))
    m = _COMPUTED.match(raw)
    if m:
        return b.compile((el, attr, 1),
                         lambda: compile_expression(m.group(1), max_text=b.max_text))
    if kind is ParamKind.NUMBER:
        return _number(b, spot, raw)
    return constant(raw, raw)


def _number(b: Builder, spot: Spot, raw: str) -> Compiled | None:
    """A number written as an attribute value; like a number in an expression, it must
    be finite and at most MAX_NUMBER in size (1 and 400 zeros is a decimal, but no number)."""
    shown = raw if len(raw) <= 20 else raw[:17] + "..."
    try:
        value = float(raw)
    except ValueError:
        b.error(spot, f"'{shown}' is not a number (write a number, or {{expression}})")
        return None
    if not abs(value) <= MAX_NUMBER:
        b.error(spot, f"'{shown}' is too large a number (the limit is {MAX_NUMBER:.0f})")
        return None
    return constant(int(value) if value.is_integer() and "." not in raw else value, raw)


def bind_element(b: Builder, el: etree._Element) -> CommandCall | None:
    """A Command written as an element (``<speak text="..."/>`` or ``<command name="...">``)."""
    tag = local_name(el)
    generic = tag == "command"
    name = el.get("name", "") if generic else b.element_commands.get(tag, "")
    spec = b.catalog.get(name)
    if spec is None:
        b.error((el, "name", 0), f"unknown Command '{name}'{_command_hint(b, name)}")
        return None
    args: dict[str, Compiled] = {}
    spots: dict[str, Spot] = {}
    if generic:
        _arg_elements(b, spec, el, args, spots)
    else:
        for param in spec.params:
            if el.get(param.name) is not None:
                spots[param.name] = (el, param.name, 0)
                _put(args, param.name, compile_attribute(b, param.kind, el, param.name))
                _note_place(b, spec, param, el.get(param.name, ""), spots[param.name])
    extras = [(x.get("name", ""), (x, "name", 0), partial(_extra_attr, b, spec, x))
              for x in children(el, "extra")]
    return _finish(b, spec, (el, None, 0), el.get("id"), (el, "id", 0), args, spots, extras)


def _arg_elements(b: Builder, spec: CommandSpec, el: etree._Element,
                  args: dict[str, Compiled], spots: dict[str, Spot]) -> None:
    """The ``<arg name value>`` children of a ``<command>``."""
    for arg in children(el, "arg"):
        name = arg.get("name", "")
        param = spec.param(name)
        if param is None:
            b.error((arg, "name", 0), f"{spec.name} has no argument '{name}'{_params_hint(spec)}")
        elif name in spots:
            b.error((arg, "name", 0), f"argument '{name}' is given twice")
        else:
            spots[name] = (arg, "value", 0)
            _put(args, name, compile_attribute(b, param.kind, arg, "value"))
            _note_place(b, spec, param, arg.get("value", ""), spots[name])


def _note_place(b: Builder, spec: CommandSpec, param: Param, raw: str, spot: Spot) -> None:
    """A place attribute written as a name, not ``{computed}``."""
    if param.kind is ParamKind.PLACE and not _COMPUTED.match(raw):
        b.literal_place(raw, spot, spec.name, param.name)


def _extra_attr(b: Builder, spec: CommandSpec, el: etree._Element) -> Compiled | None:
    param = b.profile.extras.get(spec.name, {}).get(el.get("name", ""))
    return compile_attribute(b, param.kind if param else ParamKind.TEXT, el, "value")


def bind_chain(b: Builder, el: etree._Element, text: str,
               steps: Sequence[ChainStep]) -> list[CommandCall | None]:
    """The Commands of a chain (:func:`bind_step` each). Where the builder keeps
    (:func:`~prima.dsl._kept.keeping`), a short chain bound without a problem is kept: the
    same text bound again, in the same setting (the robot profile, the kind of
    application, the variables declared, inside a handler or not), gives the same
    Commands, each located where this chain is written, and the same labels, places
    and names to check."""
    kept = b.kept
    if kept is None or len(text) > MEMO_TEXT:
        return [bind_step(b, el, text, step) for step in steps]
    key = (text, b.kind, b.max_text, b.in_handler, b.variable_key)
    found = kept.chains.get(key)
    if isinstance(found, KeptChain) and found.profile is b.profile:
        return found.replay(b, el)
    marks = (len(b.problems), len(b.refs.variables), len(b.refs.grammars), len(b.places))
    calls = [bind_step(b, el, text, step) for step in steps]
    if len(b.problems) == marks[0] and all(calls):
        kept.chains.put(key, KeptChain.record(b, steps, calls, marks))
    return calls


@dataclass(frozen=True, repr=False, eq=False)
class KeptChain(Record):
    """A chain's Commands as bound once, with what binding them asked the builder to
    check later, located in the chain's text (where, index) so that they can be
    replayed for another element that holds the same text."""

    profile: RobotProfile
    calls: tuple[tuple[CommandCall, int, int], ...]
    """Each Command, where its step and its label are written."""
    variables: tuple[tuple[str, str | None, int], ...]
    grammars: tuple[tuple[str, str | None, int], ...]
    places: tuple[tuple[str, str | None, int, str, str], ...]

    @classmethod
    def record(cls, b: Builder, steps: Sequence[ChainStep], calls: Sequence[CommandCall | None],
               marks: tuple[int, int, int, int]) -> KeptChain:
        _problems, variables, grammars, places = marks
        return cls(
            b.profile,
            tuple((call, step.index, step.label_index)
                  for call, step in zip(calls, steps, strict=True) if call is not None),
            tuple((name, where, index) for name, (_el, where, index)
                  in b.refs.variables[variables:]),
            tuple((name, where, index) for name, (_el, where, index)
                  in b.refs.grammars[grammars:]),
            tuple((name, where, index, command, param) for name, (_el, where, index), command,
                  param in b.places[places:]))

    def replay(self, b: Builder, el: etree._Element) -> list[CommandCall | None]:
        out: list[CommandCall | None] = []
        for call, index, label_index in self.calls:
            again = CommandCall(call.command, dict(call.args), dict(call.extra), call.label,
                                b.loc((el, "#text", index)), call.grammar, call.into)
            if again.label is not None:
                b.add_label(again.label, again, (el, "#text", label_index))
            out.append(again)
        b.refs.variables.extend((name, (el, where, index)) for name, where, index in self.variables)
        b.refs.grammars.extend((name, (el, where, index)) for name, where, index in self.grammars)
        b.places.extend((name, (el, where, index), command, param)
                        for name, where, index, command, param in self.places)
        return out


def bind_step(b: Builder, el: etree._Element, text: str, step: ChainStep) -> CommandCall | None:
    """A Command written in the chain notation: ``label: Name(args)[extras]``."""
    where: Spot = (el, "#text", step.index)
    spec = b.catalog.get(step.command)
    if spec is None:
        b.error(where, f"unknown Command '{step.command}'{_command_hint(b, step.command)}")
        return None
    args: dict[str, Compiled] = {}
    spots: dict[str, Spot] = {}
    after_named = False
    for pos, arg in enumerate(step.args):
        arg_spot: Spot = (el, "#text", _written_at(arg, text))
        name_spot: Spot = (el, "#text", arg.name_index) if arg.name else arg_spot
        param = _chain_param(b, spec, pos, arg, arg_spot, name_spot, after_named)
        after_named = after_named or arg.name is not None
        if param is None:
            continue
        if param.name in spots:
            b.error(name_spot, f"argument '{param.name}' is given twice")
            continue
        spots[param.name] = arg_spot
        value = _chain_value(b, param, arg, text, arg_spot)
        _put(args, param.name, value)
        name = bare_name(arg)
        if param.kind is ParamKind.PLACE and name in b.variable_names:
            b.warning(arg_spot, f"'{name}' is taken as a place name; write {{{name}}} "
                                "to use the variable")
        if param.kind is ParamKind.PLACE and not arg.computed and value is not None:
            b.literal_place(str(value.evaluate(_NO_SCOPE)), arg_spot, spec.name, param.name)
    extras = [(x.name or "", (el, "#text", x.name_index),
               partial(_extra_chain, b, spec, x, text, el)) for x in step.extras]
    label_spot: Spot = (el, "#text", step.label_index)
    return _finish(b, spec, where, step.label, label_spot, args, spots, extras)


def _command_hint(b: Builder, name: str) -> str:
    """What follows an unknown Command's name: the Command it may be a misspelling of, or
    where the Commands are listed. An EA is not offered the robot's own Commands."""
    close = b.similar(name, (c.name for c in b.catalog
                             if not (c.robot_specific and b.kind is AppKind.EA)))
    return f"; did you mean '{close}'?" if close is not None else COMMANDS_HINT


def _chain_param(b: Builder, spec: CommandSpec, pos: int, arg: ChainArg, arg_spot: Spot,
                 name_spot: Spot, after_named: bool) -> Param | None:
    """The parameter a chain argument is for, by its name or position; None after an error."""
    if arg.name is not None:
        param = spec.param(arg.name)
        if param is None:
            b.error(name_spot, f"{spec.name} has no argument '{arg.name}'{_params_hint(spec)}")
        return param
    if after_named:
        b.error(arg_spot, "a positional argument cannot follow a named one")
        return None
    if pos >= len(spec.params):
        b.error(arg_spot, f"{spec.name} takes at most {len(spec.params)} argument(s)"
                          f"{_params_hint(spec)}")
        return None
    return spec.params[pos]


def _chain_value(b: Builder, param: Param, arg: ChainArg, text: str, spot: Spot) -> Compiled | None:
    if param.kind in SYMBOLIC_KINDS and not arg.computed:
        name = bare_name(arg)
        if name is None:
            name = string_literal(arg)
        if name is not None:
            return constant(name, name)
        written = _source(arg, text)
        if _HYPHENATED.match(written):
            b.error(spot, f"write \"{written}\" in quotes: in a chain, '-' between names "
                          "reads as a subtraction")
        elif param.kind in _DOCUMENT_NAMES:
            b.error(spot, f"'{param.name}' must be a bare name")
        else:
            b.error(spot, f"'{param.name}' is a {param.kind.value}: write a bare name, "
                          "or {expression} to compute it")
        return None
    return b.compile((spot[0], "#text", 0),
                     lambda: compile_chain_arg(arg, text, max_text=b.max_text))


_HYPHENATED = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\s*-\s*[A-Za-z0-9_]+)+$")


def _written_at(arg: ChainArg, text: str) -> int:
    """Where a chain argument's value is written from: its first token, or the sign or
    word before it (``-3`` from its ``-``)."""
    return span(arg.tree, text)[0]


def _source(arg: ChainArg, text: str) -> str:
    start, end = span(arg.tree, text)
    return text[start:end]


def _extra_chain(b: Builder, spec: CommandSpec, x: ChainArg, text: str,
                 el: etree._Element) -> Compiled | None:
    param = b.profile.extras.get(spec.name, {}).get(x.name or "")
    name = bare_name(x)
    if param is not None and param.kind in SYMBOLIC_KINDS and name is not None:
        return constant(name, name)
    return b.compile((el, "#text", 0), lambda: compile_chain_arg(x, text, max_text=b.max_text))


_NO_SCOPE = Scope({})


def _put(args: dict[str, Compiled], name: str, compiled: Compiled | None) -> None:
    if compiled is not None:
        args[name] = compiled


def _params_hint(spec: CommandSpec) -> str:
    if not spec.params:
        return f" ({spec.name} takes no arguments)"
    return f" (arguments: {', '.join(p.name for p in spec.params)})"


def _finish(b: Builder, spec: CommandSpec, where: Spot, label: str | None, label_spot: Spot,
            args: dict[str, Compiled], spots: dict[str, Spot],
            extras: Sequence[Extra]) -> CommandCall:
    """Checks shared by both forms, then the :class:`CommandCall`."""
    _check_signature(b, spec, where, spots)
    _check_numbers(b, spec, args, spots)
    extra = _extras(b, spec, extras)
    grammar, into = _names(b, spec, args, spots)
    call = CommandCall(spec.name, args, extra, label, b.loc(where), grammar, into)
    if label is not None:
        b.add_label(label, call, label_spot)
    return call


def _check_signature(b: Builder, spec: CommandSpec, where: Spot, spots: dict[str, Spot]) -> None:
    """Who may use the Command, and whether the arguments it needs are given."""
    if spec.robot_specific and b.kind is AppKind.EA:
        b.error(where, f"only an FA may use the robot-specific Command '{spec.name}'")
    for param in spec.params:
        if param.required and param.name not in spots:
            b.error(where, f"{spec.name} needs the argument '{param.name}'")
    for group in spec.one_of:
        present = sorted(name for name in group if name in spots)
        if len(present) != 1:
            got = f" (got {', '.join(present)})" if present else ""
            b.error(where, f"{spec.name} needs exactly one of {' or '.join(sorted(group))}{got}")


def _check_numbers(b: Builder, spec: CommandSpec, args: dict[str, Compiled],
                   spots: dict[str, Spot]) -> None:
    """Each number argument of the Command: :func:`check_number`, against its ranges. An
    argument that is no number is dropped."""
    for param in spec.params:
        compiled = args.get(param.name)
        if param.kind is ParamKind.NUMBER and compiled is not None and not check_number(
                b, compiled, spots[param.name], param.name, spec):
            del args[param.name]


def check_number(b: Builder, compiled: Compiled, spot: Spot, name: str,
                 spec: CommandSpec | None = None, extra: Range | None = None) -> bool:
    """Whether the number argument ``name`` (or a ``<timer>``'s ``after``) may have its
    value, as far as it is known when the document loads; False after an error at
    ``spot`` when it is no number.

    A constant one (a literal, or an expression of constants) must be a number:
    ``Turn(angle="ninety")``, ``Turn(true)`` and ``angle="{'ninety'}"`` would fail when
    requested. A constant argument of ``spec`` must also lie within the ranges the robot
    takes (:meth:`~prima.catalog.CommandSpec.refusal`: the rule the robot applies when it
    performs the Command, said in its words), or the Command would fail when performed:
    ``QA(..., timeout=-3)``; an ``extra``, an additional argument the robot acts on, within
    its own range instead (``Gesture(dance)[tempo=0]``). A value computed from variables
    is checked when the application runs.
    """
    if not compiled.constant:
        return True
    value = compiled.evaluate(_NO_SCOPE)
    el, where, _index = spot
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        written = el.get(where, "") if where not in (None, "#text") else compiled.source
        shown = written if len(written) <= 20 else written[:17] + "..."
        form = "argument " + name if where == "#text" else f"attribute {where}"
        b.error(spot, f"{form}={shown}: expected a number, or an expression giving one")
        return False
    if extra is not None:  # (an additional argument the robot acts on: its own range)
        refusal = extra.refusal(value)
    else:
        refusal = None if spec is None else spec.refusal(name, value)
    if spec is not None and refusal is not None:
        b.error(spot, f"{spec.name}: {refusal}")
    return True


def _extras(b: Builder, spec: CommandSpec, extras: Sequence[Extra]) -> dict[str, Compiled]:
    """The additional arguments this robot's profile declares for the Command (FA only)."""
    extra: dict[str, Compiled] = {}
    declared = b.profile.extras.get(spec.name, {})
    for name, spot, make in extras:
        if b.kind is AppKind.EA:
            b.error(spot, "only an FA may pass additional arguments")
        elif name not in declared:
            known = ", ".join(sorted(declared)) or "none"
            b.error(spot, f"{spec.name} has no additional argument '{name}' on this robot "
                          f"(declared: {known})")
        else:
            compiled = make()
            limits = EXTRAS_ACTED_ON.get((spec.name, name))
            if compiled is not None and limits is not None \
                    and declared[name].kind is ParamKind.NUMBER \
                    and not check_number(b, compiled, spot, name, spec, limits):
                continue
            _put(extra, name, compiled)
    return extra


def _names(b: Builder, spec: CommandSpec, args: dict[str, Compiled],
           spots: dict[str, Spot]) -> tuple[str | None, str | None]:
    """Check the names written as arguments; take out the grammar and the variable.

    A gesture must be one the robot knows; a grammar and a variable must be
    declared in the document. Those two leave ``args``: they become the call's
    :attr:`~CommandCall.grammar` and :attr:`~CommandCall.into`.
    """
    named: dict[ParamKind, str] = {}
    for param in spec.params:
        if param.kind in _DOCUMENT_NAMES:
            compiled = args.pop(param.name, None)
            if compiled is not None and not compiled.constant:
                b.error(spots[param.name], f"'{param.name}' must be a bare name")
        else:
            compiled = args.get(param.name)
        if compiled is None or not compiled.constant or param.kind not in SYMBOLIC_KINDS:
            continue
        value = named[param.kind] = str(compiled.evaluate(_NO_SCOPE))
        spot = spots[param.name]
        if param.kind is ParamKind.GESTURE:
            b.check_gesture(value, spot)
        elif param.kind is ParamKind.GRAMMAR:
            b.need_grammar(value, spot)
        elif value and param.kind is ParamKind.VARIABLE:  # an empty one receives nothing
            b.need_variable(value, spot)
    return named.get(ParamKind.GRAMMAR), named.get(ParamKind.VARIABLE)
