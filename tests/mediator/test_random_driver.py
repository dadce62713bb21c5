"""The random driver and its independent oracle (prima.mediator.oracle).

Thousands of seeded scenarios, each checked after every step by a model of the
rules written from docs/mediator.md over the public API only; and proof that
the oracle can fail: mediators broken on purpose are caught.

A failure names its seeds; replay one with
``python -m prima.mediator.random_driver SEED`` (or :func:`replay`), and run
the long version with ``python bench/random_driver.py --scenarios 1000000``.
"""

from __future__ import annotations

import ast
import dataclasses
from collections.abc import Iterator
from pathlib import Path

import pytest

import prima.mediator._holds as holds_module
import prima.mediator._log as log_module
import prima.mediator._memory as memory_module
import prima.mediator._ranking as ranking_module
from prima.mediator import DecisionKind, Rule
from prima.mediator.oracle import window_peak
from prima.mediator.random_driver import play, replay, scenario
from prima.mediator.testing import ScriptedDriver

SEEDS = range(1_000_000_000, 1_000_000_000 + 4_000)
"""Other seeds than the bench's default run (which starts at 0)."""


def failures(seeds: range, stop_at: int | None = None) -> Iterator[tuple[int, list[str]]]:
    found = 0
    for seed in seeds:
        r = play(seed)
        if r.violations:
            yield seed, r.violations
            found += 1
            if stop_at is not None and found >= stop_at:
                return


def test_thousands_of_random_scenarios_keep_every_invariant() -> None:
    bad = list(failures(SEEDS, stop_at=5))
    if bad:
        lines = [f"seed {seed}: {'; '.join(v[:2])}" for seed, v in bad]
        pytest.fail("the oracle found violations (replay: python -m "
                    "prima.mediator.random_driver SEED)\n" + "\n".join(lines))


FOUND = (77000003429, 77000001268, 77000007298, 77000008886, 77000012445, 78000011328,
         78000018342, 79000019769, 4242000039872, 4242000053838, 2000002071,
         4343000008614, 4343000034092, 4343000054841, 4343000154069, 4343000353473,
         4343000270844, 4343000600810, 4343000807527)
"""Seeds of the long run in which the oracle once found a violation (an AB held for ever
after a false interruption's pause, one kept from the wheels by an AB a reaction to the
user held, three streams waiting for each other; a reaction to the user whose app was
unloaded holding the others on; an AB kept for another app's next AB that its tree, now
replying to the user's answer, outranks; words turned for again and again, each turn
suspending the other app's return, which their wait let run; a wait another app's block
or stream hold made, charged by the oracle to the app answering the user meanwhile; an AB
started while its tree replied to the user's answer, whose reply's first words, taking no
time, were said later in the same operation; a restart waiting for the reaction it was
cut for, which stepped aside for the next AB of a reaction whose return the restart kept
from the wheels, and, the oracle, one that stepped aside so: no rival of what took the
wheels meanwhile; an AB that started while an app answering the user still held the
others, unloaded later in the same operation; a later reaction joining a reaction to the
user, which made it the latest, whom it held not looked at again): each stays clean."""


@pytest.mark.parametrize("seed", FOUND)
def test_the_seeds_that_once_failed_keep_every_invariant(seed: int) -> None:
    assert play(seed).violations == []


def test_a_seed_replays_exactly() -> None:
    seed = SEEDS[17]
    assert scenario(seed) == scenario(seed)
    a, b = play(seed), play(seed)
    assert (a.decisions, a.steps, a.violations) == (b.decisions, b.steps, b.violations)
    text = replay(seed)
    assert text.startswith(f"seed {seed}:") and "decisions:" in text and "no violation" in text


def test_the_scenarios_cover_what_they_should() -> None:
    """Over a few hundred seeds: every kind of action, tiny budgets, zero-length ABs."""
    kinds, tiny, immediate, raising, endless = set(), 0, 0, 0, 0
    for seed in SEEDS[:300]:
        sc = scenario(seed)
        kinds |= {a.kind for a in sc.acts}
        kinds |= {"asap" for a in sc.acts if a.asap} | {"group" for a in sc.acts if a.group}
        kinds |= {"reactive" for a in sc.acts if a.reactive}
        kinds |= {"follows" for a in sc.acts if a.follows}
        tiny += any(b.wait_share < 5 for b in sc.config.budgets.values())
        immediate += sc.immediate and 0.0 in sc.durations
        raising += any(s.raise_on for s in sc.scripts)
        endless += any(s.endless for s in sc.scripts)
    assert kinds == {"submit", "event", "speech", "regard", "stream", "block", "swap", "asap",
                     "group", "reactive", "follows"}
    assert min(tiny, immediate, raising, endless) > 10


def test_the_driver_exercises_the_connect_channel_policy() -> None:
    """A third of the seeds run with a robot that faces its user at every few
    questions: the mediator puts turns of its own before utterances."""
    seeds = [seed for seed in SEEDS[:300] if scenario(seed).facing]
    assert 80 < len(seeds) < 120
    turns = sum(replay(seed).count("[connect-channel]") for seed in seeds[:40])
    assert turns > 20


def test_the_driver_exercises_barge_in() -> None:
    """Three seeds in ten run a robot that hears at any time (docs/rules.md 7.5): the user
    speaks outside Q&As, words some apps take, a cough nobody takes, a backchannel; the
    oracle checks every cut for the user's words and every false interruption's pause."""
    seeds = [seed for seed in SEEDS[:300] if scenario(seed).hearing]
    assert 60 < len(seeds) < 120
    replays = [replay(seed) for seed in seeds[:80]]
    for what in ("[barge-in]", "[nomatch]", "[backchannel]", "[stream-runs]", "[grammar]",
                 "(no application took the user's words)"):
        assert sum(r.count(what) for r in replays) > 3, what


def test_the_driver_exercises_keeping_the_user_faced_and_answering_first() -> None:
    """The user goes off to the side while the robot talks in some seeds: the mediator
    turns the robot back beside the words (7.6 (3)); reactions to the user's own action
    hold the streams they interrupted (7.6 (1)), which the oracle checks."""
    replays = [replay(seed) for seed in SEEDS[:600]]
    assert sum(r.count("keeps facing the user") for r in replays) > 5
    assert sum(r.count("[answering]") for r in replays) > 20


def test_the_driver_runs_three_apps_in_a_third_of_the_seeds() -> None:
    """An EA beside the FA and the first EA all along: the three apps' streams
    suspend each other (the oracle checks, at every step, that suspended streams
    resume most recent first)."""
    seeds = [seed for seed in SEEDS[:300] if scenario(seed).beside is not None]
    assert 80 < len(seeds) < 130
    suspended = {line.split()[2] for seed in seeds[:60] for line in replay(seed).splitlines()
                 if " suspend " in line}
    assert {"fa", "ea", "eb"} <= suspended


def test_the_oracle_uses_the_public_api_only() -> None:
    root = Path(__file__).parents[2] / "prima" / "mediator"
    for module in ("oracle.py", "random_driver.py"):
        tree = ast.parse((root / module).read_text(encoding="utf-8"))
        imported = [n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
        imported += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
        assert not [m for m in imported if "._" in m], module
        private = [n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
                   and n.attr.startswith("_") and not n.attr.startswith("__")
                   and not (isinstance(n.value, ast.Name) and n.value.id == "self")]
        assert private == [], (module, private)


def test_window_peak() -> None:
    spans = [(0.0, 1.0), (2.0, 4.0), (10.0, 11.0)]
    assert window_peak(spans, 3.0) == (2.0, 0.0)     # [0, 3]: 1 s + 1 s
    assert window_peak(spans, 100.0)[0] == 4.0
    assert window_peak(spans, 3.0, exempt=lambda lo, hi: lo < 5)[0] == 1.0


# ---------------------------------------------------------------- the oracle can fail
WRONG_WINNER = ("could start but waits", "outranks it for")
"""What the oracle says when the mediator ranked wrong: a better AB left waiting, or a
worse one started on a device a better one wanted."""


def caught(seeds: range = SEEDS) -> list[str]:
    """The first violations the oracle reports over ``seeds``."""
    for _seed, violations in failures(seeds, stop_at=1):
        return violations
    return []


def test_the_oracle_catches_a_ranking_criterion_left_out(monkeypatch: pytest.MonkeyPatch,
                                                         ) -> None:
    """Without 'reactive first', an older AB reserves what a newer reactive one needs."""
    criteria = tuple(c for c in ranking_module.CRITERIA if c.rule is not Rule.REACTIVITY)
    monkeypatch.setattr(ranking_module, "CRITERIA", criteria)
    assert any(what in v for v in caught() for what in WRONG_WINNER)


@pytest.mark.pure
def test_the_oracle_catches_a_double_booking(monkeypatch: pytest.MonkeyPatch) -> None:
    """A mediator that forgets a device is busy (and a driver that does not check)."""
    def start(self: memory_module.WorkingMemory, node: memory_module.Node) -> None:
        node.state = memory_module.NodeState.RUNNING
        self._rank_out(node)
        self.waiting -= 1
        node.tree.running += 1

    def blind_start(self: ScriptedDriver, ab: object) -> None:
        self.started.append(ab)  # type: ignore[arg-type]
        self.running[ab.id] = ab  # type: ignore[attr-defined]
        if self.on_start is not None:
            self.on_start(ab)  # type: ignore[arg-type]

    monkeypatch.setattr(memory_module.WorkingMemory, "start", start)
    monkeypatch.setattr(ScriptedDriver, "start", blind_start)
    assert any(what in v for v in caught()
               for what in ("held by running AB", "both run on", "device occupancy"))


@pytest.mark.pure
def test_the_oracle_catches_an_ab_started_twice(monkeypatch: pytest.MonkeyPatch) -> None:
    """A mediator that reports (and so would perform) one start twice."""
    original = log_module.DecisionLog.ab  # (what records starts)

    def ab(self: log_module.DecisionLog, kind: DecisionKind, rule: Rule,
           node: log_module.Node, detail: str = "") -> None:
        original(self, kind, rule, node, detail)
        if kind is DecisionKind.START and node.id % 50 == 7:
            original(self, kind, rule, node, detail)

    monkeypatch.setattr(log_module.DecisionLog, "ab", ab)
    assert any("started twice" in v for v in caught())


@pytest.mark.pure
def test_the_oracle_catches_a_block_ignored(monkeypatch: pytest.MonkeyPatch) -> None:
    original = holds_module.Holds.holder

    def holder(self: holds_module.Holds, node: holds_module.Node
               ) -> tuple[Rule, holds_module.App] | None:
        found = original(self, node)
        return None if found is not None and found[0] is Rule.BLOCK else found

    monkeypatch.setattr(holds_module.Holds, "holder", holder)
    assert any("block held" in v for v in caught())


@pytest.mark.parametrize("seed", [2102, 11446, 127444, 49640, 161195, 14252, 20281, 28347,
                                  587142, 5151, 6858, 14284, 38491, 40689, 63038, 117762,
                                  127791, 170836, 130517, 168125, 25391, 47859, 72202,
                                  187334, 179257, 194091, 400414, 439133, 567432, 873008,
                                  386988, 939197, 1000000000111027, 2000000000132388,
                                  2000000000038255, 2000000000078627, 2000000000174220,
                                  3000000000010914, 3000000000030658, 3000000000025602,
                                  4000000000437850, 5000000000233759, 6000000000220037,
                                  8000000000085618, 8000000000803102, 8000000000367237,
                                  8000000000426130, 11000000000126716, 11000000000702366,
                                  14000000000418768])
def test_seeds_that_once_failed(seed: int) -> None:
    """2102: the waiting index compared two slots (TypeError); 11446: an AB held by a
    newly reserving block still reserved a free device; 127444: the same for a newly
    armed stream hold (all three fixed in the mediator). 49640, 161195: overruns of the
    literal wait-share bound that no mediator can avoid (the channel rule; a start that
    no rival was waiting for any more), now notes. 14252: a suspended stream whose
    waiting ABs an asap request cancelled was rejoined by that request as a stream
    under way, past the other app's stream hold; 20281: a stream that resumed through
    one AB kept its other ABs parked by a stream hold (both fixed in the mediator).
    28347: an utterance that a connect-channel turn was put before left the speaker
    it reserved unnoticed, so the other app's utterance waited for the next event.
    587142: when a block took force, only the best waiting AB on each of its devices
    stepped aside; another app's AB it held, ranked lower there, still reserved a free
    device against a turn to the user. With the interrupt policy in the driver: 5151,
    a wait share spent up to floating-point rounding set its next check on the very
    instant (a livelock of deadlines; a share spent within 1e-9 s is spent); 6858, an
    unloaded app's running AB was cut and restarted for nobody; 14284, two reactions'
    tracking loops cut each other as the wait share demoted one, then the other (an
    app that lost its precedence cuts nothing). 38491, 40689, 63038 (three apps): an AB
    kept by two apps' stream holds at once was charged to both by the oracle; only the
    hold that parks it keeps it waiting (the other would keep nothing more). 117762,
    127791: a waiting AB that restore-state put a return before was still counted as
    a rival of the starts in that operation, so a demoted app's start on idle devices
    was not excused (the return, a LOW move, was the rival). 170836: an AB another
    app's stream hold kept was counted as a rival of a start on the idle device, so
    that start was not excused when the hold ended (the holder is charged for it).
    With a reaction's next AB keeping its devices (docs/rules.md 7.1): 130517, an AB kept
    for it that no round looked at still reserved its other device, the speaker, so a
    later request there waited for nothing; 168125, the same when the reservation began
    on one device of an AB that was best on another (the devices waiting ABs need
    beside each are now known, and looked at); 47859, the return put before a reply
    ranked as the reply only in its first iteration, so the reply and another app's
    reaction each kept what the other needed (the run never ended). 25391: a reply that
    takes no time said a user reaction's first words within the operation that started
    the reaction's next AB (the oracle judged that start by what held after it);
    72202: an AB kept for two apps' reactions was charged by the oracle to the one the
    mediator did not park it for. 187334: a reply's own next iteration, after its words,
    still ranked as the reply. 179257, 194091: an AB kept for a reaction's next AB
    while one round ran, which the operation's later rounds let go (the next AB
    entered the waiting list), was judged a rival of that round's starts; 400414, the
    same for a next AB that started within the operation. 439133: when an app regained
    its precedence, the ABs its reaction's next AB now keeps were not looked at, and one
    still reserved a device it could not have. 567432: the oracle took a return put
    before a reply's later iteration for part of the reply. 873008: a move held back
    while another app said something that took no time was judged a rival. 386988:
    each iteration of a return put before a demoted app's reply goes first past the
    share, as the reply does. 939197: a restart's pause ends exactly when the
    mediator's clock says (1.1 + 0.6), not within a tolerance. 1000000000111027: a
    reaction's next AB kept the speaker from another app's AB, which stepped aside (it
    reserves nothing) so the reaction's own move took the wheels, and then the app was
    unloaded in the same operation, cancelling that next AB: the oracle judged the move
    by what held after the unload. 2000000000132388: a reaction's next AB (its words,
    behind a turn to the user) kept the speaker from the other app's reaction, which
    stepped aside; its own app's restart of the question that reaction had cut took
    the speaker before both (a restart comes after the reaction it was cut for, 7.3 (2),
    also while that reaction's AB steps aside).
    2000000000038255: a reaction's next AB behind an AB another app's block keeps kept
    that app's move waiting (they waited for each other; it keeps nothing from that app
    now), also while the channel rule holds that AB too; 2000000000078627: the same when
    the block took force after the AB was kept (what was kept is looked at again).
    2000000000174220: a stream suspended in a round whose later start blended its own
    next AB in stayed suspended while it ran (it is resumed at once now).
    3000000000010914: while a turn to the user put before a reaction's words ran (it
    took no time), the AB after the words stopped keeping the neck (it keeps it now);
    3000000000025602: the same for a tree that became a reaction while its words waited
    behind the turn. 3000000000030658: a reaction's next AB behind an AB the other app's
    block kept, that app unloaded within the operation (the oracle judged the start by
    what held after the unload). 4000000000437850: the same for a block that took
    force within the operation and ended with its app's unload. 5000000000233759: a
    restart waited for the reaction it was cut for, which was kept for the next AB
    after the restart in its own tree (they waited for each other: it waits only for
    another tree's next AB); 6000000000220037: the same when a next AB of another tree
    kept it too (any such keeper counts, as it is now, not the AB's parking).
    8000000000085618: an app's stream hold armed as it went idle, its AB started, and
    the app was unloaded, all within one operation: the oracle saw the hold in neither
    view and judged the other app's AB it held a rival (an app unloaded within the
    operation has its starts there left unjudged). 8000000000803102: a restart that
    waited for the reaction it was cut for while a block held it too stayed in the
    ranking (it is parked, reserving nothing, like any AB a hold keeps).
    8000000000367237, 8000000000426130: a return put before a reply (LOW) lost the
    wheels on priority to its own app's HIGH stream again and again while the reply
    kept the other app waiting past the share (it ranks as the reply does: 7.4).
    11000000000126716: a demoted app's reply waited first in line for the speaker while
    the wheels it also needs were busy; the oracle charged that wait to its share (a
    reply goes first past the share, 7.4, waiting as it runs). 11000000000702366: a
    restart waited for the reaction it was cut for while that reaction's AB was kept for
    a third tree's next AB; the reaction's app regained its precedence and it no longer
    was, but nothing looked at the restart again (a re-ranked tree now has every
    restart that may wait for its reaction looked at again). 14000000000418768: the user
    cut an app's question with words the same app took; while a turn to the user went
    before its answer, the question's restart took the speaker (the answer's
    reservation kept only other apps' ABs): now the taker's reaction keeps it from the
    restart too, and the oracle agrees (7.5)."""
    assert play(seed).violations == []


def test_the_oracle_catches_a_reaction_that_loses_its_precedence(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/rules.md 7.1 undone: only a reaction's first AB ranks as reactive (the rule
    before 7.1), so its later ABs wait behind the other app's."""
    def reactivity(node: ranking_module.Node, _pjf: object) -> tuple[int, int]:
        return (0, -node.seq) if node.reactive else (1, 0)

    criteria = tuple(dataclasses.replace(c, scope=ranking_module.Scope.NODE, key=reactivity)
                     if c.rule is Rule.REACTIVITY else c for c in ranking_module.CRITERIA)
    monkeypatch.setattr(ranking_module, "CRITERIA", criteria)
    assert any(what in v for v in caught() for what in WRONG_WINNER)


@pytest.mark.pure
def test_the_oracle_catches_a_stream_hold_that_splits_a_stream_under_way(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/rules.md 7.2 undone: a stream hold keeps every AB of the other apps but the
    reactive ones, even those of a stream under way."""
    original = holds_module.Holds.holder

    def holder(self: holds_module.Holds, node: holds_module.Node
               ) -> tuple[Rule, holds_module.App] | None:
        found = original(self, node)
        if found is None and not node.reactive:
            for other in self._apps.values():
                st = self._streams.get(other.name)
                if (other is not node.app and st is not None and st.armed
                        and not node.devices.isdisjoint(st.devices)):
                    return Rule.STREAM_HOLD, other
        return found

    monkeypatch.setattr(holds_module.Holds, "holder", holder)
    assert any("could start but waits" in v and "parked by" in v for v in caught())


@pytest.mark.pure
def test_the_oracle_catches_a_cut_ab_that_is_never_restarted(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The interrupt policy with its restart undone: the cut AB is neither restarted
    nor reported dropped."""
    from prima.mediator import _mediator as mediator_module

    seeds = [s for s in range(200) if scenario(s).interrupt]
    assert seeds
    caught: list[str] = []

    def no_restart(self: mediator_module.Mediator, node: holds_module.Node,
                   outcome: mediator_module.Outcome) -> None:
        wm = self._wm
        wm.end(node, self._clock.now())
        self._holds.ended(node)
        self._log.emit(mediator_module.DecisionKind.END, Rule.INTERRUPT, node,
                       detail="to restart")
        wm.leave(node)

    monkeypatch.setattr(mediator_module.Mediator, "_interrupted", no_restart)
    for s in seeds:
        caught += [v for v in play(s).violations if "no restart was requested" in v]
        if caught:
            break
    assert caught


def test_with_every_policy_on_the_properties_hold() -> None:
    """Seeds in which the connect-channel and restore-state channel, the interrupt
    policy, declared blends and a third app all play at once: no two ABs share a
    device but by a declared blend, every cut AB is restarted or dropped exactly once,
    and working memory drains (the oracle checks each)."""
    seeds = [s for s in range(3000) if (sc := scenario(s)).facing and sc.interrupt
             and sc.blends and sc.beside is not None]
    assert len(seeds) >= 20
    for s in seeds:
        assert play(s).violations == [], s


@pytest.mark.pure
def test_the_oracle_catches_a_reaction_that_keeps_no_devices(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/rules.md 7.1 undone: a reaction's next AB reserves nothing while it waits for
    the reaction's StopMoving or turn, so another app's AB slips in between."""
    from prima.mediator import _rounds as rounds_module

    monkeypatch.setattr(rounds_module.Selector, "_reserved", lambda self, x: None)
    assert any("kept for" in v or what in v for v in caught() for what in WRONG_WINNER)


def test_the_oracle_catches_a_later_perception_reaction_overtaking_the_users(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/rules.md 7.1 undone: of two reactions the latest wins, even over a reaction to
    the user's own action whose words are still to come."""
    criteria = tuple(c for c in ranking_module.CRITERIA if c.rule is not Rule.USER_FIRST)
    monkeypatch.setattr(ranking_module, "CRITERIA", criteria)
    assert any(what in v for v in caught() for what in WRONG_WINNER)


def test_the_oracle_catches_a_reply_that_loses_to_a_reaction(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/rules.md 7.4 undone: the words that reply to an answer rank like any AB."""
    criteria = tuple(c for c in ranking_module.CRITERIA if c.rule is not Rule.EXCHANGE)
    monkeypatch.setattr(ranking_module, "CRITERIA", criteria)
    assert any(what in v for v in caught() for what in WRONG_WINNER)


@pytest.mark.pure
@pytest.mark.parametrize("undone, said", [("protected", "it replies to an answer"),
                                           ("once", "cut again")])
def test_the_oracle_catches_a_reply_cut_or_an_ab_cut_twice(
        monkeypatch: pytest.MonkeyPatch, undone: str, said: str) -> None:
    """docs/rules.md 7.4 and 7.3 (2) undone: the interrupt policy cuts the words that reply
    to an answer, or cuts a restart again."""
    from prima.mediator import _policies as policies_module

    original = policies_module.Policies.cuttable
    blank = {"protected": False, "once": False}[undone]

    def cuttable(self: policies_module.Policies, y: policies_module.Node,
                 x: policies_module.Node) -> bool:
        kept = getattr(y, undone)
        setattr(y, undone, blank)
        try:
            return original(self, y, x)
        finally:
            setattr(y, undone, kept)

    monkeypatch.setattr(policies_module.Policies, "cuttable", cuttable)
    if undone == "protected":  # (the reply must rank below the reaction to be cut at all)
        monkeypatch.setattr(ranking_module, "CRITERIA", tuple(
            c for c in ranking_module.CRITERIA if c.rule is not Rule.EXCHANGE))
    assert any(said in v for _seed, found in failures(range(0, 20_000))
               for v in found), said


def test_the_oracle_catches_a_blended_ab_that_never_ends(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A blended AB the driver never ends stays started for the rest of the run (the
    old home robot's chained blended Turn): the oracle says it never ended."""
    original = ScriptedDriver.start

    def start(self: ScriptedDriver, ab: memory_module.AtomicBehavior) -> None:
        if ab.blended:
            self.started.append(ab)
            self.running[ab.id] = ab  # (no end is ever scheduled)
            return
        original(self, ab)

    monkeypatch.setattr(ScriptedDriver, "start", start)
    seeds = [s for s in range(3000) if scenario(s).blends][:300]
    found = [v for s in seeds for v in play(s).violations]
    assert any("never ended" in v for v in found)
