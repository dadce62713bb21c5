"""How long each reaction waited, and how long the rules let it wait (docs/rules.md section 8).

A reaction is *late* when it starts later than the rules of docs/rules.md sections 5
and 7 allow. From its event on, a device its first atomic behavior needs may be
held, *rightly*, by:

- an AB that was running at the event and that the reaction may not cut (a Q&A's
  listening, a reply's words, a block's AB, a blended AB, one its request marked
  uninterruptible, a restart, one whose Commands the robot cannot cut), until it
  ends; one it may cut, until the end of the word under way (the interrupt policy
  cuts speech at a word boundary, anything else at once);
- an AB that goes first: a reply to another application's answer (7.4), the AB of
  a reaction that the rules put first (the latest (4.2), or one to the user's own
  action that has not yet said its first words (7.1)), an AB that keeps the
  Communication Channel over a reaction's that breaks it (rule 4.1), one in
  another application's begin/end block;
- the reaction's own application, in its own stream (what it chose to do first);
- a hold the mediator reports that the rules allow (a reaction's next AB that
  goes first keeps its devices; a block);
- anything, while the reacting application had lost its precedence (the wait
  share).

Everything else on its devices took them wrongly. The reaction's *residual* is
the time its devices were rightly held; it is late when it was *free* (no device
rightly held, and not started) for more than the slack, 0.2 s. Its first words
are judged the same way from its first start, the reaction's own atomic
behaviors before them excused (a filler, a turn to the user), with the slack
and a second more; they count once said whole (an utterance cut counts when said
again).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Iterable, Sequence
from typing import Final

from prima.judge._context import (
    EPS,
    FOLLOW_COMMANDS,
    TALK_DEVICES,
    Ab,
    Context,
    Hold,
    ReactionState,
    covered,
    span_at,
    spans_meeting,
)
from prima.judge._findings import Blame, Reaction, after
from prima.vocab import MAX_ANSWER_HOLD

__all__ = ["analyse"]

_TICK: Final = 0.02
"""A cut reaches its word boundary on the simulator's next step at the latest."""

Span = tuple[float, float]

Why = Blame | tuple[Ab, str, float | None]
"""What rightly held a reaction's devices for a while: a :class:`Blame`, or an AB with
the rule and the time until which it counted, whose Blame is made only if the finding
shows it (:meth:`_Analyst._top`: three a reaction at most, of the many its waits hold)."""


def _hold_t(h: Hold) -> float:
    return h.t


def _until(span: Span) -> float:
    return span[1]


def _gaps(spans: Iterable[Span], lo: float, hi: float) -> list[Span]:
    """The parts of [lo, hi] the spans leave uncovered."""
    out: list[Span] = []
    reach = lo
    for a, b in sorted((max(a, lo), min(b, hi)) for a, b in spans if b > lo and a < hi):
        if a > reach + EPS:
            out.append((reach, a))
        reach = max(reach, b)
    if hi > reach + EPS:
        out.append((reach, hi))
    return out


class _Analyst:
    """Works out every reaction's waits once the pass is over."""

    def __init__(self, ctx: Context, end: float) -> None:
        self.ctx = ctx
        self.end = end
        self.th = ctx.th
        self.cmd_abs: dict[int, list[Ab]] = {}
        for ab in ctx.abs.values():
            for cid in ab.ids:
                self.cmd_abs.setdefault(cid, []).append(ab)
        self.policy_for: dict[int, list[int]] = {}
        for cid, target in ctx.precedes.items():
            self.policy_for.setdefault(target, []).append(cid)
        self.starts = {d: [ab.start for ab in abs_] for d, abs_ in ctx.on_device.items()}
        self.longest = max((ab.until(end) - ab.start for ab in ctx.abs.values()), default=0.0)
        replies: set[int] = set()
        for ex in ctx.exchanges:
            if ex.kind == "words":
                replies.update(ex.reply)
                for cid in ex.reply:
                    replies.update(self.policy_for.get(cid, ()))
        self.replies = replies
        self.restarts = {again: cut for cut, again in ctx.restarted.items()}
        """An AB that starts a cut one again -> the cut one."""
        self._user_until: dict[int, float] = {}
        self._by_tree: dict[int, list[ReactionState]] | None = None
        self._ready: dict[int, float] = {}
        self._went: dict[tuple[int, int, bool], str] = {}
        """(AB, reaction, low) -> :meth:`goes_first` of an AB that started while the
        reaction waited (:meth:`went_first`)."""
        self._requested_by: dict[int, tuple[int, ...]] | None = None
        self._following: dict[str, tuple[list[Span], list[float]]] = {}
        """App -> when other applications followed the user (:meth:`_followed`)."""
        self._tree_gone: dict[int, float] = {}
        """Tree -> when its last AB ended (inf while one ran at the end; 0.0: it has
        none), for :meth:`_gone`."""

    # ------------------------------------------------------------ precedence
    def user_until(self, r: ReactionState) -> float:
        """Until when a reaction to the user's own action goes first (7.1): the end of
        the first of its own utterances said whole (not the words of an earlier reaction
        that its tree says first: another handling's, 7.1)."""
        key = id(r)
        found = self._user_until.get(key)
        if found is None:
            found = math.inf
            own = set(r.commands)
            for tree in r.trees:
                for ab in self.ctx.tree_abs.get(tree, ()):
                    if (ab.text and ab.end is not None and ab.end_reason == "completed"
                            and ab.start >= r.t - EPS and not own.isdisjoint(ab.ids)):
                        found = min(found, ab.end)
            self._user_until[key] = found
        return found

    def answered(self, app: str, t: float) -> float:
        """Until when ``app``'s reaction to the user's own action that kept something
        waiting at ``t`` kept the streams it interrupted waiting (7.6 (1)): until its first
        words were said whole (or, with none, it was over), at most its bound after it
        came."""
        found, latest = math.inf, -1
        for r in self.ctx.reactions:
            if r.app == app and r.user and r.t <= t + EPS:
                until = min(self.user_until(r), r.t + MAX_ANSWER_HOLD, self._gone(r))
                if until > t - EPS and r.order > latest:  # (the latest holds: 7.6 (1))
                    found, latest = until, r.order
        return found

    def _gone(self, r: ReactionState) -> float:
        """When the last AB of ``r``'s trees ended (inf while one ran at the end)."""
        last = 0.0
        for tree in r.trees:
            last = max(last, self._tree_end(tree))
        return last if last else math.inf

    def _tree_end(self, tree: int) -> float:
        """When ``tree``'s last AB ended (inf while one ran at the end; 0.0: it has none),
        worked out once: every reaction of its application to the user's own action asks
        it for each answering hold (a feedback loop's tree has hundreds of ABs)."""
        found = self._tree_gone.get(tree)
        if found is None:
            found = 0.0
            for ab in self.ctx.tree_abs.get(tree, ()):
                if ab.end is None:
                    found = math.inf
                    break
                found = max(found, ab.end)
            self._tree_gone[tree] = found
        return found

    def reaction_key(self, r: ReactionState, t: float) -> tuple[int, float]:
        if r.answer:  # (the reply to an answer goes on in its Q&A's tree, with its rank)
            return self.tree_key(r.trees[0], t) if r.trees else (1, math.inf)
        user = r.user and self.user_until(r) > t + EPS
        return (0 if user else 1, -r.order)

    def tree_key(self, tree: int, t: float) -> tuple[int, float]:
        """How a tree ranks at ``t`` as the reactions that took it over say: as the latest
        one, and first as the user's own action while a reaction to it whose first words
        are still ahead is one of them (a later reaction to a perception that joins it
        leaves it so, 7.1)."""
        taken = [r for r in self.ctx.tree_reactions.get(tree, ()) if r.t <= t + EPS]
        if not taken:
            return (1, math.inf)
        latest = self.reaction_key(max(taken, key=lambda r: r.order), t)
        if latest[0] and any(r.user and not r.answer and self.user_until(r) > t + EPS
                             for r in taken):
            return (0, latest[1])
        return latest

    def replies_to_answer(self, ab: Ab) -> bool:
        """``ab`` says (or turns or returns before) the words that reply to an answer
        (7.4); not once the user cut them with words an application took: said again,
        they are words like any (7.6 (5))."""
        if self.replies.isdisjoint(ab.ids):
            return False
        cut = self.restarts.get(ab.id)
        seen = {ab.id}
        while cut is not None and cut not in seen:  # (back through its restarts)
            if self.ctx.user_cuts.get(cut):
                return False
            seen.add(cut)
            cut = self.restarts.get(cut)
        return True

    def is_reply(self, r: ReactionState, t: float = -math.inf) -> bool:
        """``r`` answers a heard answer with words (7.4): the exchange's reply, which
        goes first, until ``t`` if the user cut it with words an application took by then
        (7.6 (5): what those words start goes first)."""
        return r.answer and not self.replies.isdisjoint(r.commands) \
            and not self.user_cut(r) <= t + EPS

    def user_cut(self, r: ReactionState) -> float:
        """When the user's words, which an application took, cut ``r``'s words (inf:
        they did not)."""
        cuts = self.ctx.user_cuts
        return min((ab.until(self.end) for cid in r.commands for ab in self.cmd_abs.get(cid, ())
                    if ab.end_reason == "barge-in" and cuts.get(ab.id)), default=math.inf)

    def demoted(self, app: str, tree: int, t: float, seq: int | None = None) -> bool:
        """``app`` had lost its precedence at ``t`` (as of the line ``seq``, if given), as
        far as ``tree``'s ABs go: not for a reaction to the user's own action before its
        first words (7.6 (4)), nor for the reply to the user's answer to its Q&A (its
        words, or its next question) before its first words."""
        if not self.ctx.demoted_at(app, t, seq):
            return False
        taken = [r for r in self.ctx.tree_reactions.get(tree, ()) if r.t <= t + EPS]
        latest = max(taken, key=lambda r: r.order) if taken else None
        if latest is not None and latest.user and self.user_until(latest) > t + EPS:
            return False
        return not any(r.t <= t + EPS and self.user_until(r) > t + EPS
                       for r in self._answers().get(tree, ()))

    def _answers(self) -> dict[int, list[ReactionState]]:
        """Tree -> the reactions to heard answers that go on in it (its replies)."""
        if self._by_tree is None:
            self._by_tree = {}
            for r in self.ctx.reactions:
                if r.answer and r.user:
                    for tree in r.trees:
                        self._by_tree.setdefault(tree, []).append(r)
        return self._by_tree

    def goes_first(self, y: Ab, r: ReactionState, low: bool, t: float) -> str:
        """Why ``y``, of another application, went first over the reaction ``r`` (whose
        first AB breaks the channel if ``low``), starting at ``t``; empty if it did
        not go first."""
        ctx = self.ctx
        if self.replies_to_answer(y):
            return "a reply to its answer (7.4)"
        # (one that started in the instant its app lost its precedence, before the line
        # that says so, started with it)
        if self.demoted(y.app, y.tree, t, y.seq if abs(t - y.start) <= EPS else None):
            return ""
        if y.low and not low:
            return ""
        if low and not y.low:
            return "keeps the channel (rule 4.1)"
        if ctx.block_open(y.app, t):
            return "its begin/end block (rule 3)"
        if self.is_reply(r, t):
            return ""  # (no other reaction goes before the words that reply to an answer)
        theirs, mine = self.tree_key(y.tree, t), self.reaction_key(r, t)
        if theirs < mine:
            return ("the user's own action first (7.1)" if theirs[0] < mine[0]
                    else "the latest reaction first (4.2)")
        return ""

    def went_first(self, y: Ab, r: ReactionState, low: bool) -> str:
        """:meth:`goes_first` as ``y`` started, worked out once: each of a reaction's waits
        that spans ``y`` asks it (its first start's, its words', its words' AB's from its
        request), one long wait another application's whole feedback loop (some 140 ABs
        three times over in a sample-7 run)."""
        key = (y.id, id(r), low)
        found = self._went.get(key)
        if found is None:
            found = self._went[key] = self.goes_first(y, r, low, y.start)
        return found

    def may_cut(self, y: Ab, r: ReactionState, low: bool, t: float, turn: bool = False) -> str:
        """Empty if the reaction may cut ``y`` (running at ``t``); else why not. ``turn``:
        for the turn to the user put before its words, which may cut its own
        application's other stream too, for a reaction to the user's own action
        (docs/rules.md 7.6 (1) and (3))."""
        ctx = self.ctx
        if y.app == r.app and not (turn and r.user and y.tree not in r.trees
                                   and self.user_until(r) > t + EPS):
            return "its own application's"
        if not y.cuttable:
            return "uncut: not interruptible"
        if y.reason == "restart":
            return "uncut: a restart (cut at most once)"
        if y.reason == "blend" or y.blended_over:
            return "uncut: blended"
        if self.replies_to_answer(y):
            return "uncut: a reply to its answer (7.4)"
        if ctx.block_open(y.app, t):
            return "uncut: in a begin/end block"
        said = y.planned or y.words
        if y.listens and (said is None or t >= said[1] - EPS):
            return "uncut: a Q&A listening"
        if ctx.demoted_at(r.app, t) and not (r.user and self.user_until(r) > t + EPS):
            return "uncut: the reacting application lost its precedence"
        if low and not y.low:
            return "uncut: it keeps the channel"
        if y.low and not low:
            return ""
        if self.demoted(y.app, y.tree, t):
            return ""
        if self.reaction_key(r, t) < self.tree_key(y.tree, t):
            return ""
        return "uncut: a reaction that goes first"

    @staticmethod
    def boundary(y: Ab, t: float) -> float:
        """Where a cut asked for at ``t`` ends ``y``: the end of the word under way, or
        at once (a step later at most). The words spread as planned when they started
        (a cut AB's end line says only what was said)."""
        words = y.planned or y.words
        if words is not None and words[0] - EPS <= t < words[1] - EPS and y.text:
            ws, we = words
            n = max(1, len([w for w in y.text.split() if w != "/"]))
            per = (we - ws) / n
            k = math.floor((t - ws) / per + 1e-9) + 1
            return min(we, ws + k * per) + _TICK
        return t + _TICK

    # ------------------------------------------------------------ waits
    def near(self, devices: Iterable[str], lo: float, hi: float) -> list[Ab]:
        """The ABs on these devices that ran at some time within [lo, hi]."""
        found: dict[int, Ab] = {}
        for d in devices:
            abs_ = self.ctx.on_device.get(d)
            if not abs_:
                continue
            starts = self.starts[d]
            i = bisect.bisect_left(starts, lo - self.longest - EPS)
            j = bisect.bisect_right(starts, hi + EPS)
            for ab in abs_[i:j]:
                end = ab.end  # (one still running at the end runs past lo)
                if end is None or end > lo - EPS:
                    found[ab.id] = ab
        return sorted(found.values(), key=lambda ab: ab.seq)

    def waits(self, r: ReactionState, own: set[int], devices: frozenset[str], low: bool,
              t0: float, seq0: int, t1: float, ready: float | None = None,
              turn: bool = False
              ) -> tuple[list[tuple[float, float, Why]], list[tuple[float, float, Ab]]]:
        """What rightly held ``devices`` within [t0, t1], and what took them wrongly.
        ``own``: the reaction's Commands (its own ABs never count against it);
        ``ready``: when it could first ask for a cut (after its own AB before it);
        ``turn``: the devices of a turn to the user put before it (:meth:`may_cut`)."""
        ready = t0 if ready is None else max(t0, ready)
        ctx = self.ctx
        allowed: list[tuple[float, float, Why]] = []
        took: list[tuple[float, float, Ab]] = []
        for y in self.near(devices, t0, t1):
            y_end = y.until(self.end)
            if y_end < t0 - EPS or y.start > t1 + EPS:
                continue
            if not own.isdisjoint(y.ids) or y.tree in r.trees:
                allowed.append((y.start, y_end, (y, "its own", None)))
                continue
            running = y.start < t0 - EPS or (abs(y.start - t0) <= EPS and y.seq < seq0)
            # (one that started while the reacting application had lost its precedence
            # started rightly: at its regaining, it is as one running at the event)
            regained = None if running else self._regained(r, y.start)
            if regained is not None and y_end <= regained + EPS:
                continue  # (over before it regained its precedence: that wait covers it)
            if running or regained is not None:
                when = ready if regained is None else max(ready, regained)
                why = self.may_cut(y, r, low, when, turn)
                stop = self.boundary(y, when)
                said = y.planned or y.words
                if not why and y.listens and said is not None and stop >= said[1] - EPS:
                    why = "uncut: a Q&A on the last word of its prompt, then listening"
                if why:
                    allowed.append((y.start, y_end, (y, why, y_end)))
                else:
                    stop = min(y_end, stop)
                    allowed.append((y.start, stop, (y, "cut at a word boundary", stop)))
                    if y_end > stop + EPS:
                        took.append((stop, y_end, y))
                continue
            why = self.went_first(y, r, low)
            if why:
                # it kept its devices from when it was ready (waiting, or next in a
                # reaction's tree, docs/rules.md 7.1): when the AB before it in its tree
                # ended, or when it was asked for if later
                allowed.append((self.ready(y), y_end, (y, why, y_end)))
            else:
                took.append((y.start, y_end, y))
        allowed += self._holds(r, own, low, t0, t1)
        if ctx.demoted_within(r.app, t0, t1):
            # (a reaction to the user's own action is not rationed before its first words:
            # docs/rules.md 7.6 (4))
            since = self.user_until(r) if r.user else -math.inf
            for lo, hi in spans_meeting(ctx.demoted.get(r.app, ()), t0, t1):
                if hi > since:
                    allowed.append((max(lo, since), hi, Blame(
                        r.app, None, "", "", "it had lost its precedence (its wait share)",
                        hi)))
        return allowed, took

    def _regained(self, r: ReactionState, t: float) -> float | None:
        """When ``r``'s application regained its precedence, if it had lost it at ``t``
        (None if it had not, or ``r`` was not rationed then: 7.6 (4))."""
        spans = self.ctx.demoted.get(r.app)
        if not spans:  # (most applications never lose it: asked of every AB a wait meets)
            return None
        if r.user and self.user_until(r) > t + EPS:
            return None
        span = span_at(spans, t)
        return span[1] if span is not None and t < span[1] - EPS else None

    def ready(self, y: Ab) -> float:
        """When ``y`` was ready to start, as far as the trace tells: when the AB before it
        in its tree ended (or when it was asked for, if that was later), else its
        start."""
        found = self._ready.get(y.id)
        if found is None:
            found = y.start
            tree = self.ctx.tree_abs.get(y.tree, ())
            i = y.place - 1
            precedes = self.ctx.precedes
            # (a policy's AB put before it, a turn or a return, was part of its wait)
            while i >= 0 and any(precedes.get(cid) in y.ids for cid in tree[i].ids):
                i -= 1
            if i >= 0:
                found = min(y.start, tree[i].until(self.end))
            asked = self.ctx.requested_at.get(y.id)
            if asked is not None:
                found = max(found, min(asked[0], y.start))
            self._ready[y.id] = found
        return found

    def _holds(self, r: ReactionState, own: set[int], low: bool, t0: float,
               t1: float) -> list[tuple[float, float, Why]]:
        """The holds the mediator reports on the reaction's ABs that the rules allow."""
        out: list[tuple[float, float, Why]] = []
        holds = self.ctx.holds  # (in trace order: their times never go back)
        for k in range(bisect.bisect_left(holds, t0 - EPS, key=_hold_t), len(holds)):
            h = holds[k]
            if h.t > t1 + EPS:
                break
            held = self.ctx.abs.get(h.ab)
            ids = held.ids if held is not None else self._requested_ids(h.ab)
            if own.isdisjoint(ids):
                continue
            if h.reason == "reserved" and h.before is not None:
                nxt = self.ctx.abs.get(h.before)
                if nxt is None:
                    out += self._kept_for_gone(r, h, t1)
                    continue
                if not self.goes_first(nxt, r, low, h.t):
                    continue
                until = min(nxt.start, t1)
                out.append((h.t, until, (nxt, "kept for a reaction's next AB (7.1)", until)))
            elif h.reason == "block":
                span = span_at(self.ctx.blocks.get(h.holder, ()), h.t)
                until = t1 if span is None else span[1]
                out.append((h.t, min(until, t1), Blame(h.holder, None, "", "",
                                                       "its begin/end block (rule 3)",
                                                       until)))
            elif h.reason == "answering":
                until = min(self.answered(h.holder, h.t), t1)
                out.append((h.t, until, Blame(h.holder, None, "", "",
                                              "the user's own action answered first "
                                              "(7.6 (1))", until)))
            elif h.reason == "keep-channel" and low:
                out.append((h.t, t1, Blame(h.holder, None, "", "",
                                           "keeps the channel (rule 4.1)", t1)))
        return out

    def _kept_for_gone(self, r: ReactionState, h: Hold, t1: float
                       ) -> list[tuple[float, float, Why]]:
        """A hold that kept ``r``'s devices for another reaction's next AB that never
        started: rightly, while that reaction's stream goes before ``r``, until its
        application cancelled the AB (a newer request of its own replaced it)."""
        gone = self.ctx.cancelled_ab.get(h.before or -1)
        if gone is None or gone[1] is None or \
                not self.tree_key(gone[1], h.t) < self.reaction_key(r, h.t):
            return []
        until = min(gone[0], t1)
        return [(h.t, until, Blame(h.holder, h.before, "", "",
                                   "kept for a reaction's next AB (7.1)", until))]

    def _requested_ids(self, ab: int) -> tuple[int, ...]:
        """The Commands requested as ``ab`` (indexed once, the first time it is asked)."""
        if self._requested_by is None:
            by: dict[int, list[int]] = {}
            for cid, found in self.ctx.cmd_ab.items():
                by.setdefault(found, []).append(cid)
            self._requested_by = {found: tuple(cids) for found, cids in by.items()}
        return self._requested_by.get(ab, ())

    def _blame(self, y: Ab, rule: str, until: float | None = None) -> Blame:
        return Blame(y.app, y.id, y.command, self.ctx.at(y), rule,
                     None if until is None else round(until, 3))

    # ------------------------------------------------------------ one reaction
    def reaction(self, r: ReactionState) -> Reaction:
        own = set(r.commands)
        for cid in r.commands:
            own.update(self.policy_for.get(cid, ()))
        # (each once: an AB of several Commands is each one's, and the wait of its words,
        # worked out for each, went through another application's whole loop three times)
        mine = sorted({ab.id: ab for cid in own for ab in self.cmd_abs.get(cid, ())}.values(),
                      key=lambda ab: ab.seq)
        first = mine[0] if mine else None
        devices = set(r.devices)
        put: list[tuple[frozenset[str], float, int, bool]] = []
        """A policy's AB put before the first Command: its devices, from its request, and
        whether it turns the robot to the user."""
        for cid in self.policy_for.get(r.commands[0], ()) if r.commands else ():
            for ab in self.cmd_abs.get(cid, ()):
                asked = self.ctx.requested_at.get(ab.id, (r.t, r.seq))
                put.append((ab.devices - devices, *asked, ab.reason == "connect-channel"))
                devices |= ab.devices
        low = any(ab.low for ab in mine[:1]) if first is not None else False
        t1 = first.start if first is not None else self._over(r)
        ready = r.t
        behind = self.ctx.abs.get(r.before) if r.before is not None else None
        waiting = self.ctx.requested.get(r.before) if r.before is not None else None
        if behind is not None and behind.app == r.app:  # after its own AB, still to end
            last = self._last_of(behind)  # (said again if cut: 7.3 (2))
            # (a restart still to start when the trace ends: it waited all along)
            ready = self.end if last.id in self.ctx.restarted else last.until(self.end)
        elif behind is None and r.before is not None and waiting is not None \
                and waiting[0] == r.app:
            # (after its own AB that never started, a cut AB's restart say: it waited for
            # it all along, or until the application cancelled it)
            gone = self.ctx.cancelled_ab.get(r.before)
            ready = self.end if gone is None else gone[0]
        allowed, took = self.waits(r, own, frozenset(r.devices), low, r.t, r.seq, t1, ready)
        for extra, t_put, seq_put, turn in put:
            if extra:  # (the turn's wheels count from when the turn was put in line)
                more, taken = self.waits(r, own, extra, low, t_put, seq_put, t1,
                                         max(ready, t_put), turn)
                allowed += [(max(a, t_put), b, blame) for a, b, blame in more]
                took += [(max(a, t_put), b, y) for a, b, y in taken]
        if behind is not None and ready > r.t:
            allowed.append((r.t, ready, (behind, "after its own AB", ready)))
        elif waiting is not None and ready > r.t:
            allowed.append((r.t, ready, Blame(r.app, r.before, waiting[1], waiting[2],
                                              "after its own AB, never started",
                                              round(ready, 3))))
        residual = covered(((a, b) for a, b, _ in allowed), r.t, t1)
        free = max(0.0, (t1 - r.t) - residual)
        spoken = [ab for ab in mine if ab.text and not set(ab.ids).isdisjoint(r.commands)]
        heard = next((ab for ab in spoken if ab.end_reason == "completed"), None)
        words = r.words or bool(spoken)
        words_free = 0.0
        words_waits: tuple[tuple[Blame, ...], Blame | None] = ((), None)
        cut_by_user = heard is None and any(ab.end_reason == "barge-in" for ab in spoken)
        if first is not None and words and not cut_by_user:  # (the user's own cut: 7.5)
            words_free, words_waits = self._words_free(r, own, mine, spoken, first, heard)
        first_start = None if first is None else first.start
        first_utterance = None if heard is None else heard.start
        residual, free = round(residual, 3), round(free, 3)
        words_free = round(words_free, 3)
        why, by_words = self._why(r.t, residual, free, first_start, first_utterance,
                                  words_free)
        waits, by = self._top(allowed), self._culprit(took, allowed, r.t, t1)
        if by_words:  # (late for its words: what they waited for, not its first AB)
            waits, by = words_waits
        return Reaction(
            r.event, r.t, r.seq, r.app, r.order, tuple(r.commands), tuple(r.trees),
            tuple(sorted(devices)), user=r.user, at=r.at, residual=residual, free=free,
            first_start=first_start,
            first_start_seq=None if first is None else first.seq,
            first_utterance=first_utterance,
            first_utterance_seq=None if heard is None else heard.seq,
            words=words, words_free=words_free,
            unheard=words and heard is None and self._unheard(r, spoken),
            late=bool(why), why=why, text=r.text, waits=waits, took=by)

    def _words_free(self, r: ReactionState, own: set[int], mine: Sequence[Ab],
                    spoken: Sequence[Ab], first: Ab, heard: Ab | None
                    ) -> tuple[float, tuple[tuple[Blame, ...], Blame | None]]:
        """How long, after its first start, the reaction's first words were free to
        start but did not, and what they waited for and what took their devices (as
        for a first start). They are rightly kept while their devices are rightly held
        (as a first start is), while one of the reaction's own ABs runs (a filler, a
        turn to the user), and while one of its own ABs that was requested and waits
        (a return put before the words, a restart) has its devices rightly held."""
        t0 = first.start
        t1 = heard.start if heard is not None else self.end
        if heard is None:  # (what it had still to say, its own app cancelled: from then)
            gone = [self.ctx.cancelled.get(cid) for cid in r.commands
                    if cid not in self.ctx.cmd_ab]
            if gone and all(g is not None for g in gone):
                t1 = min(t1, max(g for g in gone if g is not None))
        if t1 <= t0 + EPS:
            return 0.0, ((), None)
        target = heard or (spoken[0] if spoken else None)
        devices = (target.devices if target is not None else self._unsaid(r)) | TALK_DEVICES
        # (the words could ask for a cut only once the reaction's AB before them ended:
        # a Q&A then on the last word of its prompt was no longer to be cut)
        ready = self.ready(target) if target is not None else None
        allowed, took = self.waits(r, own, devices, False, t0, first.seq, t1, ready)
        waits = (self._top(allowed), self._culprit(took, allowed, t0, t1))
        spans = [(a, b) for a, b, _ in allowed]
        for ab in mine:
            spans.append((ab.start, ab.until(self.end)))
            asked = self.ctx.requested_at.get(ab.id)
            if asked is not None and asked[0] < ab.start - EPS and ab.start > t0 + EPS:
                lo = max(asked[0], t0)
                waiting, _ = self.waits(r, own, ab.devices, ab.low, lo, asked[1], ab.start)
                spans += [(a, b) for a, b, _ in waiting]
        return max(0.0, (t1 - t0) - covered(spans, t0, t1)), waits

    def _unsaid(self, r: ReactionState) -> frozenset[str]:
        """The devices of the AB that was to say the reaction's words and never started,
        as a line that named it while it waited says (a hold, a suspension): its own
        devices, not only the talk devices, are what kept it (the wheels a
        FaceHumanAndSpeak needs while another application follows the user). Empty
        when no line named it."""
        for cid in r.commands:
            if cid in self.ctx.cmd_ab:
                continue  # (it started)
            devices = self.ctx.waiting_devices.get(cid)
            if devices is not None and not TALK_DEVICES.isdisjoint(devices):
                return devices
        return frozenset()

    def _last_of(self, ab: Ab) -> Ab:
        """The AB that last starts ``ab`` again (a cut AB's restart, and its restart's),
        or ``ab`` itself; one whose own restart never started is still cut and waiting
        (``ctx.restarted`` names it)."""
        seen = {ab.id}
        while (again := self.ctx.abs.get(self.ctx.restarted.get(ab.id, -1))) is not None \
                and again.id not in seen:
            seen.add(again.id)
            ab = again
        return ab

    def _over(self, r: ReactionState) -> float:
        """When a reaction that never started was over: when its own application
        cancelled the last of its Commands (a newer request replaced it), or the
        trace's end."""
        cancelled = self.ctx.cancelled
        if r.commands and all(cid in cancelled for cid in r.commands):
            return max(cancelled[cid] for cid in r.commands)
        return self.end

    def _unheard(self, r: ReactionState, spoken: Sequence[Ab]) -> bool:
        """Its words were never heard whole: cut and said again but not whole, cut and
        not said again long after (still waiting for their turn when the trace ended
        is not unheard yet), or never said long after the event; not if its own
        application cancelled them, nor if they were cut and its request said to drop
        them then (docs/rules.md 7.6 (5): words the user cut still count if they were to
        be said again)."""
        cancelled = self.ctx.cancelled
        if spoken:
            if {cid for ab in spoken for cid in ab.ids} <= cancelled.keys():
                return False
        else:  # (none said: what never started is what would have said them)
            never = [cid for cid in r.commands if cid not in self.ctx.cmd_ab]
            if never and all(cid in cancelled for cid in never):
                return False
        cut = [ab for ab in spoken if ab.end_reason in ("interrupt", "barge-in")]
        if cut and any(ab.dropped for ab in cut):
            return False  # (cut, and their request said to drop them then)
        again = [self.ctx.abs[self.ctx.restarted[ab.id]] for ab in cut
                 if ab.end_reason == "interrupt" and self.ctx.restarted.get(ab.id) in self.ctx.abs]
        if any(a.end is not None for a in again):
            return True  # (cut for another reaction, and said again but not whole)
        if again:
            return False  # (being said again when the trace ends: not unheard yet)
        # never said again yet: unheard once they waited longer than anything may (the
        # time another application followed the user meanwhile aside, as for stuck: the
        # user leads the robot, as they asked, and that reaction goes on, 7.1)
        since = max((ab.until(self.end) for ab in cut), default=r.t)
        return self.end - since - self._followed(r.app, since) > self.th.stuck_after + EPS

    def _followed(self, app: str, since: float) -> float:
        """How long from ``since`` to the trace's end another application's AB followed
        the user (a Tracking Human). The ABs are gathered once for each ``app``, into
        stretches apart in time with the time each and those after it sum to, so that a
        long trace's many reactions ask at no more cost."""
        found = self._following.get(app)
        if found is None:
            union: list[Span] = []
            for a, b in sorted((ab.start, ab.until(self.end)) for ab in self.ctx.abs.values()
                               if ab.app != app
                               and not FOLLOW_COMMANDS.isdisjoint(ab.command.split("+"))):
                if union and a <= union[-1][1]:
                    union[-1] = (union[-1][0], max(b, union[-1][1]))
                else:
                    union.append((a, b))
            onward = [0.0] * (len(union) + 1)
            for i in range(len(union) - 1, -1, -1):
                onward[i] = onward[i + 1] + union[i][1] - union[i][0]
            found = self._following[app] = (union, onward)
        union, onward = found
        i = bisect.bisect_right(union, since, key=_until)  # (the first that ends after it)
        if i == len(union):
            return 0.0
        return onward[i] - max(0.0, since - union[i][0])

    def _top(self, allowed: list[tuple[float, float, Why]]) -> tuple[Blame, ...]:
        """What it waited for, longest first (three at most), other than its own (the
        Blames of these alone made: :data:`Why`)."""
        longest: dict[object, tuple[float, Why]] = {}
        for a, b, why in allowed:
            if isinstance(why, Blame):
                key: tuple[str, int | None, str] = (why.app, why.ab, why.rule)
            else:
                y, rule, _until = why
                if rule == "its own":
                    continue
                key = (y.app, y.id, rule)
            if key not in longest or b - a > longest[key][0]:
                longest[key] = (b - a, why)
        ranked = sorted(longest.values(), key=lambda item: -item[0])
        return tuple(why if isinstance(why, Blame) else self._blame(why[0], why[1], why[2])
                     for _, why in ranked[:3])

    def _culprit(self, took: list[tuple[float, float, Ab]],
                 allowed: list[tuple[float, float, Why]], lo: float,
                 hi: float) -> Blame | None:
        """The AB that held its devices longest while it was free to start."""
        free = _gaps(((a, b) for a, b, _ in allowed), lo, hi)
        best: tuple[float, Ab] | None = None
        for a, b, ab in took:
            overlap = sum(max(0.0, min(b, fb) - max(a, fa)) for fa, fb in free)
            if overlap > EPS and (best is None or overlap > best[0]):
                best = (overlap, ab)
        if best is None:
            return None
        return self._blame(best[1], "took its devices", best[1].until(self.end))

    def _why(self, t0: float, residual: float, free: float, first_start: float | None,
             first_utterance: float | None, words_free: float) -> tuple[str, bool]:
        """Why a reaction to an event at ``t0`` is late (empty: it is not), and whether its
        words made it so (its first start was in time): of its :class:`Reaction`'s
        figures, worked out before it is made (it is made once, late or not)."""
        t = self.th
        latency = after(t0, first_start)
        if t.react_within is not None:
            if latency is None:
                return "never started", False
            if latency > t.react_within + EPS:
                return f"started after {latency:g} s (allowed {t.react_within:g} s)", False
            bound = t.react_within + t.utterance_slack
            heard = after(t0, first_utterance)
            if heard is not None and heard > bound + EPS:
                return f"spoke after {heard:g} s (allowed {bound:g} s)", False
            return "", False
        if free > t.reaction_slack + EPS:
            what = "never started" if latency is None else f"started after {latency:g} s"
            return (f"{what}: free to start for {free:g} s (the rules let it wait "
                    f"{residual:g} s, and {t.reaction_slack:g} s more)"), False
        if words_free > t.reaction_slack + t.utterance_slack + EPS:
            said = ("its words never said whole" if first_utterance is None
                    else f"spoke after {after(t0, first_utterance):g} s")
            return (f"{said}: its words were free to start for {words_free:g} s "
                    f"(allowed {t.reaction_slack + t.utterance_slack:g} s)"), True
        return "", False


def analyse(ctx: Context, end: float) -> list[Reaction]:
    """Every reaction of the trace, judged (in the order their events came)."""
    analyst = _Analyst(ctx, end)
    return [analyst.reaction(r) for r in ctx.reactions]
