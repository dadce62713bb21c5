"""Whose each finding is: the application a finding blames, the rule it broke (in words
that are the same from run to run: the finding itself has the figures), the atomic
behavior it waited for, and where the culprit's document asks for what it did.

One function per kind of finding, each given to its measure's entry
(:data:`~._measures.MEASURES`, ``blame``): ``prima check`` attributes every failure
through it, so a new measure says whom its findings blame where it is registered.
"""

from __future__ import annotations

from collections.abc import Mapping

from prima.judge._findings import (
    BargeIn,
    Blame,
    Elsewhere,
    Ignored,
    Leaving,
    Reaction,
    Recovery,
    Silence,
    Split,
    Stuck,
    Unfaced,
)

__all__ = ["Whose", "Wheels", "barge_in", "elsewhere", "ignored", "leaving", "reaction",
           "recovery", "silence", "split", "stuck", "unfaced"]

Whose = tuple[str, str, str, str]
"""(culprit application, rule broken, atomic behavior waited for, where it is asked)."""

Wheels = Mapping[int, Blame]
"""For an utterance's start line (its seq), another application's AB that held the
wheels then."""


def _blame(b: Blame | None) -> str:
    return "" if b is None else str(b)


def reaction(f: Reaction, wheels: Wheels) -> Whose:
    waited = _blame(f.waits[0]) if f.waits else ""
    what = "late" if f.late else "never heard whole"
    if f.took is not None:  # another application's AB held its devices meanwhile
        return f.took.app, f"its {f.took.command} held the devices of {f.app}'s " \
                           f"reaction to {f.event} ({what})", waited, f.took.at
    held = f.waits[0] if f.waits else None
    if not f.late and held is not None and held.app != f.app:
        # never heard for what the rules let hold its devices: that application's doing
        return held.app, f"its {held.command} held the devices of {f.app}'s reaction " \
                         f"to {f.event} ({what})", waited, held.at
    return f.app, f"its reaction to {f.event} is {what}", waited, f.at


def unfaced(f: Unfaced, wheels: Wheels) -> Whose:
    held = wheels.get(f.seq) if f.during is None else f.turned_by
    if held is not None:  # the robot could not be turned to the user first
        return held.app, f"its {held.command} moved the robot: {f.app}'s {f.command} " \
                         "was said with the user off to the side", "", held.at
    return f.app, f"{f.command} \"{f.text}\" said with the user off to the side", "", f.at


def leaving(f: Leaving, wheels: Wheels) -> Whose:
    if f.moved_by is not None:
        return f.moved_by.app, f"its {f.moved_by.command} took the robot away from the " \
                               f"user while {f.app} spoke", "", f.moved_by.at
    return f.app, "moved away from the user while speaking", "", f.at


def stuck(f: Stuck, wheels: Wheels) -> Whose:
    if f.kind == "end" and f.behind is not None and f.behind.app != f.app:
        return f.behind.app, f"its {f.behind.command} held the devices {f.app} waited " \
                             "for until the end", _blame(f.behind), f.behind.at
    return f.app, f"stuck ({f.kind})", _blame(f.behind), f.at


def elsewhere(f: Elsewhere, wheels: Wheels) -> Whose:
    return f.app, "resumed speaking away from where its stream was suspended", "", f.at


def split(f: Split, wheels: Wheels) -> Whose:
    return f.by, f"\"{f.text}\" split {f.app}'s exchange ({f.kind})", "", f.at


def silence(f: Silence, wheels: Wheels) -> Whose:
    return f.app, "said nothing after the user's answer", "", f.at


def barge_in(f: BargeIn, wheels: Wheels) -> Whose:
    return f.app, f"its {f.command} talked on over the user", "", f.at


def ignored(f: Ignored, wheels: Wheels) -> Whose:
    what = "never answered them" if f.answered is None else "answered them late"
    return f.app, f"took the user's words and {what}", "", f.at


def recovery(f: Recovery, wheels: Wheels) -> Whose:
    return f.app, f"its {f.command} did not go on after a false interruption", "", f.at
