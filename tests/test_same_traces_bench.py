"""``bench/same_traces.py``: two builds that make the same traces pass; a difference in
any run is named, with a non-zero exit."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import pytest

from tests.benches import load

ROOT = Path(__file__).resolve().parents[1]


def _bench() -> ModuleType:
    return load("same_traces")


def _other_build(tmp_path: Path, *, touch_at: str = "20") -> Path:
    """A tree with this build's code and documents, and its own copy of sample 1 (the
    user's touch at ``touch_at`` s)."""
    tree = tmp_path / "other"
    (tree / "scenarios" / "thesis").mkdir(parents=True)
    for name in ("prima", "apps", "robots", "schemas"):
        (tree / name).symlink_to(ROOT / name)
    (tree / "scenarios" / "maps").symlink_to(ROOT / "scenarios" / "maps")
    text = (ROOT / "scenarios" / "thesis" / "sample-01.xml").read_text(encoding="utf-8")
    (tree / "scenarios" / "thesis" / "sample-01.xml").write_text(
        text.replace('<touch at="20"/>', f'<touch at="{touch_at}"/>'), encoding="utf-8")
    return tree


@pytest.mark.pure
def test_the_same_build_makes_the_same_traces(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    scenario = str(ROOT / "scenarios" / "thesis" / "sample-01.xml")
    code = _bench().main(["--against", str(_other_build(tmp_path)), "--runs", "2", scenario])
    assert code == 0
    assert "2 runs of 1 scenario(s): every trace the same in both builds" in capsys.readouterr().out


@pytest.mark.pure
def test_a_run_that_differs_is_named(tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    scenario = str(ROOT / "scenarios" / "thesis" / "sample-01.xml")
    other = _other_build(tmp_path, touch_at="21")
    assert _bench().main(["--against", str(other), "--runs", "2", scenario]) == 1
    out = capsys.readouterr().out
    assert "scenarios/thesis/sample-01.xml run 0:" in out and "2 differ" in out


def test_the_compiled_builds_copy_has_the_checkouts_files_and_none_built(
        tmp_path: Path) -> None:
    """``--compiled`` builds in a copy of the checkout (bench/_measure.py): the sources
    and the build's files are there, no module built here or cache comes along."""
    _bench()
    import _measure

    built = ROOT / "prima" / "sim" / "_kernel.cpython-test.so"
    built.write_bytes(b"not a module")
    try:
        _measure.copy_checkout(tmp_path)
    finally:
        built.unlink()
    for name in ("setup.py", "pyproject.toml", "README.md", "prima/sim/_kernel.py",
                 "scenarios/thesis/sample-01.xml", "tests/conftest.py"):
        assert (tmp_path / name).is_file(), name
    assert not list(tmp_path.rglob("*.so")) and not list(tmp_path.rglob("__pycache__"))


def test_another_checkout_runs_wholly_on_its_own_files(tmp_path: Path) -> None:
    """``bench/_tree.py`` (``_measure.in_checkout``): another checkout's build imports its
    own ``prima`` and finds its own robots, schemas, applications and scenarios, not
    those an editable install of this checkout maps in (an earlier build ran with
    today's robot profiles, or crashed on them)."""
    import subprocess

    _bench()
    import _measure

    tree = _other_build(tmp_path)
    (tree / "pyproject.toml").write_text(
        (ROOT / "pyproject.toml").read_text(encoding="utf-8"), encoding="utf-8")
    code = ("import prima, json; from importlib import resources; print(json.dumps("
            "[prima.__file__] + [str(resources.files(f'prima.{n}').joinpath(f)) for n, f in "
            "(('robots', 'home-robot.xml'), ('schemas', 'pxml.xsd'), ('apps', 'fa'), "
            "('scenarios', 'thesis'))]))")
    done = subprocess.run(_measure.in_checkout(tree, ["-c", code]), capture_output=True,
                          text=True, check=True, cwd=tmp_path)
    found = [Path(p) for p in __import__("json").loads(done.stdout)]
    assert found == [tree / "prima" / "__init__.py", tree / "robots" / "home-robot.xml",
                     tree / "schemas" / "pxml.xsd", tree / "apps" / "fa",
                     tree / "scenarios" / "thesis"]


def test_another_checkouts_compiled_runtime_is_found_at_its_top(tmp_path: Path) -> None:
    """A compiled build made in place (``--compiled``) has mypyc's shared runtime, a
    top-level ``<hash>__mypyc`` module, beside ``prima/``: every compiled module imports
    it, so ``bench/_tree.py`` finds it there (it did not, and ``bench/sweep.py
    --compiled`` stopped with ``No module named '...__mypyc'``)."""
    import subprocess

    _bench()
    import _measure

    tree = _other_build(tmp_path)
    (tree / "0123abcd__mypyc.py").write_text("BUILT = 'here'\n", encoding="utf-8")
    code = "import importlib; print(importlib.import_module('0123abcd__mypyc').BUILT)"
    done = subprocess.run(_measure.in_checkout(tree, ["-c", code]), capture_output=True,
                          text=True, check=False, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "here"
