"""One place per extension point, proven: a measure or a policy registered in a scratch
entry flows through everything that reads measures or policies (``judge``, ``sweep``,
``check``'s attribution, the command line's options) with nothing else touched."""

from __future__ import annotations

import dataclasses
import io
from collections.abc import Sequence
from pathlib import Path

import pytest

from prima.check import attribute
from prima.cli import main
from prima.judge import Measure, Thresholds, judge, registered
from prima.judge._measures import Finder
from prima.run import Run
from prima.scenario import Setup
from prima.sweep import format_sweep, sweep
from prima.vocab import Policy, registered_policy

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "scenarios" / "thesis" / "sample-03.xml"


@dataclasses.dataclass(frozen=True)
class Said:
    """The scratch measure's finding: an utterance started."""

    seq: int
    t: float
    app: str
    at: str = ""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


class _Starts:
    """Finds every start of a Speak: a measure no run passes."""

    kinds = frozenset({"start"})

    def __init__(self) -> None:
        self.found: list[Said] = []

    def feed(self, row: dict[str, object], ctx: object) -> None:
        if str(row.get("command") or "").split("+")[-1] == "Speak":
            self.found.append(Said(int(str(row["seq"])), float(str(row["t"])),
                                   str(row.get("app") or "")))

    def finish(self, ctx: object, reactions: Sequence[object]) -> Sequence[Said]:
        return self.found


def _finder() -> Finder:
    return _Starts()  # type: ignore[return-value]  # (rows are dicts, as jsonl has them)


SCRATCH = Measure("scratch", "scratch utterances", "scratch utterances allowed",
                  "every utterance started (a test's measure)", _finder,
                  lambda f: f"seq {f.seq} t={f.t:g} {f.app} said",
                  lambda f, wheels: (f.app, "said something (scratch)", "", f.at))


def test_a_registered_measure_is_judged_thresholded_and_reported() -> None:
    trace = [line.to_dict() for line in Run(SAMPLE).run()]
    with registered(SCRATCH):
        report = judge(trace)
        assert report.of("scratch") and not report.ok
        assert any(b.startswith("scratch utterances:") for b in report.breaches())
        assert "scratch" in report.to_dict() and report.counts()["scratch"] > 0
        assert judge(trace, thresholds=Thresholds(max_scratch=10_000)).of("scratch")
        spared = judge(trace, thresholds=Thresholds(max_scratch=10_000))
        assert not any(b.startswith("scratch") for b in spared.breaches())
        # check: whose each failure is, from the measure's own entry
        failures = attribute(report, {"fa": "fa"})
        assert {f["rule"] for f in failures if f["measure"] == "scratch"} == \
            {"said something (scratch)"}
    assert "scratch" not in judge(trace).to_dict()  # gone once the block is left
    with pytest.raises(ValueError, match="no threshold"):
        Thresholds(max_scratch=1)


def test_a_registered_measure_is_a_row_of_the_sweep_and_an_option(tmp_path: Path) -> None:
    with registered(SCRATCH):
        result = sweep(SAMPLE, runs=2, jitter=0.5, jobs=1, keep=0)
        assert "scratch utterances" in format_sweep(result)
        assert result.breached == 2
        err = io.StringIO()
        trace = tmp_path / "run.jsonl"
        assert main(["run", str(SAMPLE), "-o", str(trace)], out=io.StringIO(), err=err) == 0
        out = io.StringIO()
        assert main(["judge", str(trace), "--max-scratch", "10000"], out=out, err=err) in (0, 1)
        assert "--max-scratch" not in err.getvalue()
    assert main(["judge", str(trace), "--max-scratch", "1"], out=io.StringIO(),
                err=io.StringIO()) == 2  # (no such option once the block is left)


def test_a_measure_is_registered_once() -> None:
    with registered(SCRATCH), pytest.raises(ValueError), registered(SCRATCH):
        pass
    with pytest.raises(ValueError):
        registered(dataclasses.replace(SCRATCH, key="late")).__enter__()


SWITCH = Policy("scratch", True, "a test's policy: it switches the exchange rule's field "
                "of the mediator's configuration and the simulator's hearing",
                config="exchange", sim="hears_always")


def test_a_registered_policy_is_switched_by_the_command_line_and_mapped_once() -> None:
    with registered_policy(SWITCH):
        on = Setup.load(SAMPLE, policies={"barge-in": False})
        assert on.policies["scratch"] is True and on.config.exchange is True
        off = Setup.load(SAMPLE, policies={"scratch": False})
        assert off.policies["scratch"] is False and off.config.exchange is False
        assert Run(Setup.load(SAMPLE, policies={"barge-in": False})).sim.hears_always is True
        err = io.StringIO()
        assert main(["run", str(SAMPLE), "--policy", "scratch=off"], out=io.StringIO(),
                    err=err) == 0, err.getvalue()
        assert main(["run", str(SAMPLE), "--policy", "all=off"], out=io.StringIO(),
                    err=io.StringIO()) == 0
    err = io.StringIO()
    assert main(["run", str(SAMPLE), "--policy", "scratch=off"], out=io.StringIO(),
                err=err) == 2
    assert "no policy 'scratch'" in err.getvalue()
    with pytest.raises(ValueError):
        registered_policy(dataclasses.replace(SWITCH, name="interrupt")).__enter__()
