"""The kernel's agenda: skipping the wakes of a process that would do nothing
(``Kernel.skip_idle``) leaves every other piece of work where it was, in its order."""

from __future__ import annotations

import itertools

from prima.sim._kernel import Kernel, ProcGen, finish, idle, sleep

END = 40


def _run(skip: bool) -> tuple[list[tuple[int, str]], int, int]:
    """A poller on a 3-tick grid that acts once something has moved, beside work that
    moves it at tick 10 and work at tick 12 scheduled before and after the poller's
    wake there: what happened, in order, the poller's wakes and the wakes skipped."""
    k = Kernel(10)
    log: list[tuple[int, str]] = []
    moved = [False]
    woken = [0]

    def poller() -> ProcGen:
        while True:
            woken[0] += 1
            if moved[0]:
                moved[0] = False
                log.append((k.tick, "acts"))
                yield sleep(3)
            else:  # nothing to do: woken while nothing moves, it would do nothing again
                yield idle(3, lambda: not moved[0])

    def move() -> None:
        moved[0] = True
        log.append((k.tick, "moves"))
        k.at(12, lambda: log.append((k.tick, "late")))  # after the poller's wake at 12

    k.spawn(poller())
    k.at(10, move)
    k.at(12, lambda: log.append((k.tick, "early")))  # before the poller's wake at 12
    k.at(25, lambda: moved.__setitem__(0, True))
    skipped = 0
    while True:
        if skip:
            skipped += k.skip_idle(END)
        nxt = k.next_tick()
        if nxt is None or nxt > END:
            break
        k.tick = nxt
        k.run_due()
    return log, woken[0], skipped


def test_skipped_wakes_leave_every_other_work_in_its_place() -> None:
    log, woken, skipped = _run(skip=True)
    assert (log, woken + skipped) == _run(skip=False)[:2]
    assert log == [(10, "moves"), (12, "early"), (12, "acts"), (12, "late"), (27, "acts")]
    assert skipped >= 8 and woken <= 6, (woken, skipped)


def test_a_wake_where_the_process_would_end_is_not_skipped() -> None:
    k = Kernel(10)
    ended: list[int] = []

    def iteration() -> ProcGen:
        end = 10
        while k.tick < end:
            yield idle(min(4, end - k.tick), lambda: True, end)
        ended.append(k.tick)

    k.spawn(iteration())
    k.run_due()  # (its start: now idle until 4)
    assert k.skip_idle(100) == 2  # 4 and 8; the wake at 10 (not 12) is its end
    assert k.next_tick() == 10
    k.tick = 10
    k.run_due()
    assert ended == [10]


def test_a_process_first_again_and_again_is_asked_once_and_keeps_its_place() -> None:
    # its wakes up to the agenda's next other work are skipped at once (nothing comes
    # between them to change its answer); work due at the tick it reaches goes first
    k = Kernel(10)
    asked = [0]
    log: list[int | str] = []
    moved = [False]

    def unchanged() -> bool:
        asked[0] += 1
        return not moved[0]

    def poller() -> ProcGen:
        while True:
            log.append(k.tick)
            yield idle(3, unchanged)

    def move() -> None:
        moved[0] = True
        log.append("moves")

    k.spawn(poller())
    k.at(21, move)
    k.run_due()  # (its start: idle until 3)
    assert k.skip_idle(100) == 6 and asked[0] == 1  # 3 to 18, and its wake at 21 waits
    assert k.next_tick() == 21
    k.tick = 21
    k.run_due()
    assert log == [0, "moves", 21]


def _skipped_one_by_one(tick: int, every: int, until: int, bound: int) -> tuple[int, int]:
    """How many wakes an idle sleep's skip passes, and the tick of the wake it keeps,
    skipped one at a time."""
    n = 0
    while True:
        tick += min(every, until - tick)
        n += 1
        if tick >= bound:
            return n, tick


def _skipped_at_once(every: int, until: int, other: int, limit: int) -> tuple[int, int, int]:
    """A process idle every ``every`` ticks up to ``until`` from tick 0, and work at
    ``other`` (scheduled after it): the wakes one skip up to ``limit`` passes, the tick
    of the wake it keeps, and how often it asked the process."""
    k = Kernel(10)
    asked = [0]

    def unchanged() -> bool:
        asked[0] += 1
        return True

    def poller() -> ProcGen:
        while k.tick < until:
            yield idle(every, unchanged, until)

    k.spawn(poller())
    k.run_due()  # (its start: idle until ``every``)
    k.at(other, lambda: None)
    n = k.skip_idle(limit)
    kept = [tick for tick, _seq, _what, wake in k._heap if wake is not None]
    assert len(kept) == 1
    return n, kept[0], asked[0]


def test_the_wakes_skipped_at_once_are_those_skipped_one_by_one() -> None:
    # The process first on the agenda: its wakes are skipped up to the other work (a
    # tie goes to the work) or ``limit``, at least one, the last cut at ``until``,
    # whether or not they fit in whole; it is asked once.
    cases = 0
    for every, until, other, limit in itertools.product(
            range(1, 5), range(3, 14), range(3, 15), range(3, 15)):
        if every >= until or every > limit or every > other:
            continue  # (nothing to skip: its end, past the limit, or not first)
        n, end = _skipped_one_by_one(every, every, until, min(limit + 1, until, other))
        assert _skipped_at_once(every, until, other, limit) == (n, end, 1), \
            (every, until, other, limit)
        cases += 1
    assert cases > 300


def test_a_process_that_yields_finish_ends_as_one_that_returns() -> None:
    # (the same exit, with the same value, at the same point among the tick's work; and
    # a finished process is never resumed again)
    def ends(by_finish: bool) -> tuple[list[tuple[int, str, object]], bool]:
        k = Kernel(10)
        log: list[tuple[int, str, object]] = []

        def process() -> ProcGen:
            yield sleep(3)
            log.append((k.tick, "result", None))
            if by_finish:
                yield finish({"done": k.tick})
                log.append((k.tick, "resumed after its finish", None))
            return {"done": k.tick}

        proc = k.spawn(process(), lambda value: log.append((k.tick, "exit", value)))
        k.at(3, lambda: log.append((k.tick, "before", None)))
        # (work at 3 after its wake there, which it asks for as it starts, at 0)
        k.at(0, lambda: k.at(3, lambda: log.append((k.tick, "after", None))))
        while (nxt := k.next_tick()) is not None:
            k.tick = nxt
            k.run_due()
        return log, proc.alive

    assert ends(by_finish=True) == ends(by_finish=False) == (
        [(3, "before", None), (3, "result", None), (3, "exit", {"done": 3}), (3, "after", None)],
        False)
