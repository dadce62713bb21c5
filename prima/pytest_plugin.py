"""pytest plugin: pin your own applications' behaviour with golden traces, and judge it.

Installed with PRIMA (entry point ``pytest11``). In a test::

    def test_my_guide(prima_golden):
        prima_golden("scenarios/my-guide.xml")

fails with a readable diff when the run's trace differs from
``scenarios/my-guide.golden.txt``. A relative path is taken from the folder of
the test file that asks, not from where pytest was started. Run
``pytest --prima-update-goldens`` to rewrite the golden files after reviewing
the change.

The ``prima_judge`` fixture measures a run's naturalness (``docs/judging.md``)
and fails with the report when a threshold is exceeded::

    def test_my_guide_is_natural(prima_judge):
        prima_judge("scenarios/my-guide.xml", max_unfaced=2)

The plugin is loaded by every pytest run in an environment where PRIMA is
installed, so it imports nothing of PRIMA until a test uses the fixture.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import pytest

if TYPE_CHECKING:  # the fixtures import PRIMA only when a test uses them
    from prima.judge import Report


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--prima-update-goldens", action="store_true", default=False,
                     help="rewrite PRIMA golden traces instead of comparing with them")


@pytest.fixture
def prima_golden(request: pytest.FixtureRequest) -> Callable[[str | Path], None]:
    """Check a scenario's run against its golden trace (fails with a diff)."""
    from prima.golden import Status, check  # only now: the whole stack comes with it

    update = bool(request.config.getoption("--prima-update-goldens"))
    here = Path(request.path).parent

    def compare(scenario: str | Path) -> None:
        path = here / scenario  # an absolute scenario path stays as it is
        result = _located(lambda: check(path, update=update), f"prima_golden({str(scenario)!r})")
        if result.status is Status.MISSING:
            pytest.fail(f"{scenario}: no golden trace yet; review a run and create it with "
                        "pytest --prima-update-goldens", pytrace=False)
        if result.status is Status.DIFFERENT:
            pytest.fail(f"{scenario}: the trace differs from its golden trace\n{result.diff}\n"
                        "(a change you meant: review it, then pytest --prima-update-goldens)",
                        pytrace=False)

    return compare


@pytest.fixture
def prima_judge(request: pytest.FixtureRequest) -> Callable[..., Report]:
    """Judge a scenario's run (or a jsonl trace); fails with the report past a threshold.

    Keyword arguments override :class:`prima.judge.Thresholds` (``max_splits=1``,
    ``react_within=0.2``, ...). Returns the :class:`prima.judge.Report`.
    """
    from prima.judge import Thresholds, format_table, judge_file  # only now

    here = Path(request.path).parent

    known = set(Thresholds().to_dict())

    def check(path: str | Path, **thresholds: Any) -> Report:
        unknown = sorted(set(thresholds) - known)
        if unknown:
            pytest.fail(f"prima_judge: no threshold {', '.join(map(repr, unknown))} (the "
                        f"thresholds: {', '.join(sorted(known))})", pytrace=False)
        report = _located(lambda: judge_file(here / path, thresholds=Thresholds(**thresholds),
                                             name=str(path)), f"prima_judge({str(path)!r})")
        if not report.ok:
            pytest.fail(f"{path}: {'; '.join(report.breaches())}\n\n{format_table([report])}",
                        pytrace=False)
        return report

    return check


_T = TypeVar("_T")


def _located(work: Callable[[], _T], what: str) -> _T:
    """``work()``; a bad scenario, document or trace fails the test with PRIMA's located
    messages (``file:line:col: error: ...``), a bad threshold or path with its message,
    never a traceback through PRIMA."""
    from prima.errors import LocatedError, PrimaError

    try:
        return work()
    except LocatedError as exc:
        pytest.fail("\n".join(str(p) for p in exc.problems), pytrace=False)
    except (PrimaError, OSError) as exc:
        pytest.fail(f"{what}: {exc}", pytrace=False)
    except Exception as exc:  # noqa: BLE001 - a bad threshold value, or a fault: said so
        pytest.fail(f"{what}: {type(exc).__name__}: {exc}", pytrace=False)
