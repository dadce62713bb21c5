"""What ships with PRIMA (prima.shipped), named on a command line from outside a
checkout: as a checkout names it (``scenarios/thesis/sample-01.xml``), or an application
or a robot by its name (``--fa fa1-emotions``). The current folder's own files come
first; PRIMA's own golden traces are never rewritten from outside. (tests/test_wheel.py
runs the same from a wheel.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from importlib import resources

from prima.cli import main
from prima.shipped import FOLDERS, locate, packaged, shipped

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = {folder: Path(str(resources.files(package))) for folder, package in FOLDERS.items()}
"""Where the install keeps each shipped folder: in an editable install, the checkout's
own (a tree run from elsewhere, the compiled build's copy, borrows the install's)."""


@pytest.fixture
def elsewhere(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize(("package", "name"), [
    ("prima.schemas", "pxml.xsd"), ("prima.robots", "home-robot.xml"),
    ("prima.dsl", "pxml.lark"), ("prima.apps", "fa"), ("prima.show", "draw.js"),
    ("prima.live", "live.js"), ("prima.mcap", "foxglove-layout.json")])
def test_a_packaged_file_is_the_one_importlib_resources_names(package: str, name: str) -> None:
    """PRIMA finds its data files in its packages' folders, without importing
    importlib.resources (tests/test_architecture.py): the same files it would name."""
    assert packaged(package, name) == Path(str(resources.files(package).joinpath(name)))
    assert packaged(package, name).exists()
    with pytest.raises(ModuleNotFoundError):
        packaged("prima.no_such_package", name)


def test_the_shipped_folders_are_the_checkouts(elsewhere: Path) -> None:
    """What ships is the checkout's files, file for file (tests/test_wheel.py: and a
    wheel's), found where the install keeps them."""
    for folder in FOLDERS:
        found = shipped(folder)
        assert found == SHIPPED[folder]
        assert {p.name: p.read_bytes() for p in found.iterdir() if p.is_file()} == \
            {p.name: p.read_bytes() for p in (ROOT / folder).iterdir() if p.is_file()}
    assert shipped("apps", "fa") == SHIPPED["apps"] / "fa"
    assert shipped("scenarios/maps/office.xml") == SHIPPED["scenarios"] / "maps" / "office.xml"
    # nothing else, and nothing outside them
    for path in ("prima", "docs/running.md", "apps/../README.md", "apps/fa/nope.pxml", ""):
        assert shipped(path) is None, path


def test_inside_the_checkout_it_is_named_as_the_checkout_names_it(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(SHIPPED["apps"].parent)
    assert shipped("apps/fa") == Path("apps/fa")


def test_locate(elsewhere: Path) -> None:
    assert locate("scenarios/thesis/sample-01.xml") == \
        str(SHIPPED["scenarios"] / "thesis" / "sample-01.xml")
    assert locate("fa1-emotions", "fa") == str(SHIPPED["apps"] / "fa" / "fa1-emotions.pxml")
    assert locate("cafe", "ea") == str(SHIPPED["apps"] / "ea" / "cafe.pxml")
    assert locate("guide-robot", "robot") == str(SHIPPED["robots"] / "guide-robot.xml")
    assert locate("museum", "map") == str(SHIPPED["scenarios"] / "maps" / "museum.xml")
    # a bare name is an application or a robot only where one is asked for
    assert locate("fa1-emotions") == "fa1-emotions"
    assert locate("cafe", "fa") == "cafe"
    # what is not shipped is left for the command to say there is no such file
    for text in ("nope.xml", "scenarios/thesis/nope.xml", "/nope/sample-01.xml"):
        assert locate(text) == text


def test_the_current_folders_own_file_comes_first(elsewhere: Path) -> None:
    (elsewhere / "fa1-emotions").write_text("mine")
    assert locate("fa1-emotions", "fa") == "fa1-emotions"
    mine = elsewhere / "scenarios" / "thesis" / "sample-01.xml"
    mine.parent.mkdir(parents=True)
    mine.write_text("mine")
    assert locate("scenarios/thesis/sample-01.xml") == "scenarios/thesis/sample-01.xml"


def test_a_shipped_scenario_runs_from_anywhere(
        elsewhere: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "scenarios/thesis/sample-01.xml", "--until", "3",
                 "--fa", "fa1-emotions", "--robot", "home-robot"]) == 0
    out = capsys.readouterr().out
    assert "loads fa1-emotions.pxml (fa)" in out and "loads ea3-navigate.pxml (ea)" in out


def test_a_shipped_ea_is_checked_from_anywhere(
        elsewhere: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "cafe", "--runs", "1", "--jobs", "1", "--worst", "0"]) == 0
    out = capsys.readouterr().out
    assert "cafe beside 8 FA(s) on 2 robot(s)" in out
    assert f"{SHIPPED['apps'] / 'fa' / 'fa2-follow.pxml'}:45:94: error: unknown gesture" in out


def test_a_name_that_is_no_shipped_fa_is_no_such_file(
        elsewhere: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "scenarios/thesis/sample-01.xml", "--fa", "fa9-nope"]) == 2
    assert "prima run: error: no such file: fa9-nope" in capsys.readouterr().err


def test_shipped_golden_traces_are_not_rewritten_from_outside(
        elsewhere: Path, capsys: pytest.CaptureFixture[str]) -> None:
    golden = SHIPPED["scenarios"] / "thesis" / "sample-01.golden.txt"
    before = golden.stat().st_mtime_ns
    assert main(["test", "--update", "scenarios/thesis/sample-01.xml"]) == 2
    assert "no such file or folder" in capsys.readouterr().err
    assert golden.stat().st_mtime_ns == before
    # without --update it is compared, as in a checkout
    assert main(["test", "scenarios/thesis/sample-01.xml"]) == 0
