"""pytest plugin: pin your own applications' behaviour with golden traces.

Installed with PRIMA (entry point ``pytest11``). In a test::

    def test_my_guide(prima_golden):
        prima_golden("scenarios/my-guide.xml")

fails with a readable diff when the run's trace differs from
``scenarios/my-guide.golden.txt``. Run ``pytest --prima-update-goldens`` to
rewrite the golden files after reviewing the change.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import pytest

from prima.golden import check


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--prima-update-goldens", action="store_true", default=False,
                     help="rewrite PRIMA golden traces instead of comparing with them")


@pytest.fixture
def prima_golden(request: pytest.FixtureRequest) -> Callable[[str | Path], None]:
    """Check a scenario's run against its golden trace (fails with a diff)."""
    update = bool(request.config.getoption("--prima-update-goldens"))

    def compare(scenario: str | Path) -> None:
        result = check(Path(scenario), update=update)
        if result.status == "missing":
            pytest.fail(f"{scenario}: no golden trace yet; review a run and create it with "
                        "pytest --prima-update-goldens", pytrace=False)
        if result.status == "different":
            pytest.fail(f"{scenario}: the trace differs from its golden trace\n{result.diff}",
                        pytrace=False)

    return compare
