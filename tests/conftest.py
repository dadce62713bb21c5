"""Shared by every test: tests marked ``pure`` run only against the pure Python build,
and are skipped against the compiled one (``prima.compiled()``). They change PRIMA's
classes or modules at run time (to plant a fault, to count calls, to subclass), which
compiled classes and modules do not allow, or copy its source as a build of its own."""

from __future__ import annotations

import pytest

import prima


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if not prima.compiled():
        return
    skip = pytest.mark.skip(reason="the pure build only (changes PRIMA at run time, or copies it)")
    for item in items:
        if item.get_closest_marker("pure") is not None:
            item.add_marker(skip)
