"""A document says which robot it is written for (``<pxml robot="...">``): validating it
uses that robot's profile without a flag, so ``prima validate apps/`` passes on the guide
robot's FA7 (it reported its Command Spotlight as unknown)."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from prima.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _validate(*argv: str) -> tuple[int, str]:
    out = io.StringIO()
    return main(["validate", *argv], out=out, err=io.StringIO()), out.getvalue()


@pytest.mark.parametrize("folder", ["apps", "scenarios", "robots"])
def test_the_shipped_files_validate(folder: str) -> None:
    assert _validate(str(ROOT / folder)) == (0, "")


def test_a_flag_still_checks_against_another_robot() -> None:
    status, said = _validate(str(ROOT / "apps" / "fa" / "fa7-spotlight.pxml"), "--robot",
                             str(ROOT / "robots" / "home-robot.xml"))
    assert status == 1 and "unknown Command 'Spotlight'" in said


def test_a_declared_robot_that_is_missing_is_located(tmp_path: Path) -> None:
    doc = tmp_path / "t.pxml"
    doc.write_text('<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t"\n'
                   '      robot="nowhere.xml"><state id="s" initial="true"/></pxml>\n')
    status, said = _validate(str(doc))
    assert status == 1
    assert said.startswith(f"{doc}:2:14: error: robot profile '{tmp_path / 'nowhere.xml'}' "
                           "not found"), said
