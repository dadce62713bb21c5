"""The judge's tests' hand-written traces (:class:`Trace`): each method appends one line,
as a run's trace has it, so that a test writes the few lines a fault needs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from prima.judge import Report, Thresholds, judge

ROOT = Path(__file__).parents[2]
THESIS = ROOT / "scenarios" / "thesis"

FACING = {"x": 0.0, "y": 0.0, "heading": 0.0}
"""The robot at the origin, facing east."""
USER = {"x": 1.0, "y": 0.0, "heading": 180.0, "detectable": True}
"""The user a metre east of it, facing it."""
TALK = ("speaker", "speech-recognition")
"""A Q&A's devices."""


class Trace:
    """A hand-written trace: each method appends one line, seq counted."""

    def __init__(self) -> None:
        self.rows: list[dict[str, Any]] = []
        self.robot = dict(FACING)
        self.user: dict[str, Any] = dict(USER)

    def line(self, t: float, kind: str, **fields: Any) -> dict[str, Any]:
        row = {"t": t, "seq": len(self.rows), "kind": kind}
        row.update({k: v for k, v in fields.items() if v is not None})
        if kind in ("start", "end", "user", "event", "pose"):
            row.setdefault("robot", dict(self.robot))
            row.setdefault("user", dict(self.user))
        self.rows.append(row)
        return row

    def sort(self) -> None:
        """Put lines written out of order where they belong in time (in the order
        they were written within an instant), and count their seqs again."""
        self.rows.sort(key=lambda r: r["t"])
        for seq, row in enumerate(self.rows):
            row["seq"] = seq

    def event(self, t: float, name: str) -> None:
        self.line(t, "event", text=name)

    def touch(self, t: float) -> None:
        """The user touches the robot: the user's line, then the event it posts."""
        self.line(t, "user", action="touch")
        self.event(t, "touched")

    def say(self, t: float, words: str, heard: bool = True) -> None:
        self.line(t, "user", action="say", text=words, detail={"heard": heard})

    def request(self, t: float, app: str, ab: int, cid: int | list[int], *, tree: int = 0,
                command: str = "Speak", text: str | None = None, reactive: bool = False,
                reason: str = "new-tree", devices: tuple[str, ...] = ("speaker",),
                before: int | None = None, at: str | None = None,
                precedes: int | None = None) -> None:
        ids = cid if isinstance(cid, list) else [cid]
        detail: dict[str, Any] = {"command_id": ids[0]}
        if at is not None:
            detail["at"] = at
        if precedes is not None:
            detail["precedes"] = precedes
        self.line(t, "request", app=app, ab=ab, tree=tree, command=command, text=text,
                  reactive=reactive, reason=reason, devices=list(devices),
                  command_ids=ids if len(ids) > 1 else None, before=before, detail=detail)

    def start(self, t: float, app: str, ab: int, cid: int, *, tree: int = 0,
              command: str = "Speak", text: str | None = None,
              devices: tuple[str, ...] = ("speaker",), iteration: int = 0,
              reason: str = "free-devices", cuttable: bool = False,
              words: tuple[float, float] | None = None) -> None:
        """``words``: when its words begin and end, if they begin as it starts."""
        detail: dict[str, Any] = {"command_id": cid}
        if iteration:
            detail["iteration"] = iteration
        if cuttable:
            detail["cuttable"] = True
        if words is not None:
            detail["words_start"], detail["words_end"] = words
        self.line(t, "start", app=app, ab=ab, tree=tree, command=command, text=text,
                  reason=reason, devices=list(devices), detail=detail)

    def end(self, t: float, app: str, ab: int, cid: int, *, tree: int = 0,
            command: str = "Speak", devices: tuple[str, ...] = ("speaker",),
            result: str = "duration=1.0", iteration: int = 0, reason: str = "completed",
            words: tuple[float, float] | None = None, text: str | None = None) -> None:
        """``words``: when its words began and ended, as said."""
        detail: dict[str, Any] = {"command_id": cid, "result": result}
        if iteration:
            detail["iteration"] = iteration
        if words is not None:
            detail["words_start"], detail["words_end"] = words
        self.line(t, "end", app=app, ab=ab, tree=tree, command=command, text=text,
                  reason=reason, devices=list(devices), detail=detail)

    def interrupt(self, t: float, app: str, ab: int, cid: int, *, by: str, by_ab: int,
                  tree: int = 0) -> None:
        """The interrupt policy asks to cut ``app``'s Speak ``ab`` for ``by``'s reaction."""
        self.line(t, "interrupt", app=app, ab=ab, tree=tree, command="Speak",
                  text=f"for {by}'s reaction (AB{by_ab})", reason="interrupt",
                  devices=["speaker"], detail={"command_id": cid})

    def speak(self, t: float, app: str, ab: int, cid: int, words: str, *, lasts: float = 1.0,
              tree: int = 0, request: bool = True, reactive: bool = False,
              cuttable: bool = False, at: str | None = None) -> None:
        """A Speak requested and started at ``t`` that ends ``lasts`` seconds later."""
        if request:
            self.request(t, app, ab, cid, tree=tree, text=words, reactive=reactive, at=at)
        said = (t, t + lasts)
        self.start(t, app, ab, cid, tree=tree, text=words, cuttable=cuttable, words=said)
        self.end(t + lasts, app, ab, cid, tree=tree, words=said, text=words)

    def ask(self, t: float, app: str, ab: int, cid: int, prompt: str, answer: str | None,
            at: float, *, tree: int = 0, request: bool = True, reactive: bool = False,
            cuttable: bool = False, prompt_lasts: float = 1.0) -> None:
        """A Q&A started at ``t`` (and requested then, unless ``request`` is False),
        saying its prompt for ``prompt_lasts`` seconds, answered with ``answer`` at
        ``at`` (None: it times out then)."""
        said = (t, t + min(prompt_lasts, at - t))
        if request:
            self.request(t, app, ab, cid, tree=tree, command="QA", text=prompt,
                         reactive=reactive, devices=TALK)
        self.start(t, app, ab, cid, tree=tree, command="QA", text=prompt, devices=TALK,
                   cuttable=cuttable, words=said)
        if answer is None:
            self.end(at, app, ab, cid, tree=tree, command="QA", devices=TALK,
                     result="status=timeout", words=said)
            return
        self.say(at, answer)
        self.end(at, app, ab, cid, tree=tree, command="QA", devices=TALK,
                 result=f"status=answered, utterance={answer}", words=said)

    def pose(self, t: float) -> None:
        self.line(t, "pose")

    def drives_then_speaks(self, t: float, words: str) -> tuple[str, ...]:
        """ea asks for a SetPosition+Speak at ``t`` and it starts (its words' times known
        only from its end line); its devices."""
        devices = ("localization", "locomotion", "speaker")
        self.request(t, "ea", 1, [1, 2], command="SetPosition+Speak", text=words,
                     devices=devices)
        self.start(t, "ea", 1, 1, command="SetPosition+Speak", text=words, devices=devices)
        return devices

    def judge(self, **thresholds: Any) -> Report:
        return judge(self.rows, thresholds=Thresholds(**thresholds), name="hand-written")


def counts(report: Report) -> dict[str, int]:
    return {k: v for k, v in report.counts().items() if v}


def clean() -> Trace:
    """A short exchange with nothing wrong: a touch answered at once, a Q&A replied to."""
    tr = Trace()
    tr.line(0.0, "load", app="fa")
    tr.line(0.0, "load", app="ea")
    tr.speak(0.0, "ea", 1, 1, "Hello.")
    tr.touch(3.0)
    tr.request(3.0, "fa", 2, 2, tree=1, command="QA", text="Yes?", reactive=True, devices=TALK)
    tr.ask(3.0, "fa", 2, 2, "Yes?", "Nothing.", at=5.0, tree=1, request=False)
    tr.request(5.0, "fa", 3, 3, tree=1, text="O.K.", reason="end-event", before=2)
    tr.speak(5.0, "fa", 3, 3, "O.K.", tree=1, request=False)
    tr.pose(7.0)
    return tr


def reaction_behind(speech_ends: float, reacts_at: float) -> Trace:
    """ea speaks from 8 s to ``speech_ends``; fa reacts to a touch at 10 s, starting at
    ``reacts_at``."""
    tr = Trace()
    tr.speak(8.0, "ea", 1, 1, "A long sentence.", lasts=speech_ends - 8.0, at="ea.pxml:3:5")
    tr.touch(10.0)
    tr.request(10.0, "fa", 2, 2, tree=1, text="Yes?", reactive=True, at="fa.pxml:12:5")
    tr.sort()  # (the end of ea's sentence where it belongs)
    tr.speak(reacts_at, "fa", 2, 2, "Yes?", tree=1, request=False)
    return tr
