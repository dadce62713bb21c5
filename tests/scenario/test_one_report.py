"""One validation reports a bad scenario's problems (:func:`prima.scenario.make_validation`):
``prima validate``, ``prima run`` (and ``prima sweep``) and the language server name the
same problems at the same places, as ``file:line:col: severity: message`` lines, with a
non-zero exit and never a traceback."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path

import pytest

from prima.cli import main
from prima.lsp._workspace import Workspace

ROOT = Path(__file__).resolve().parents[2]
FA = ROOT / "apps" / "fa" / "fa1-emotions.pxml"
EA = ROOT / "apps" / "ea" / "ea1-museum.pxml"
MUSEUM = ROOT / "scenarios" / "maps" / "museum.xml"
OFFICE = ROOT / "scenarios" / "maps" / "office.xml"


def scenario(*, fa: Path | str = FA, ea: Path | str = EA, map_: Path = MUSEUM,
             robot: str = 'place="museum-door" heading="0"', more: str = "",
             end: str = "</scenario>\n") -> str:
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<scenario xmlns="urn:prima:scenario:1" name="bad" until="60" seed="1">\n'
            f'  <map href="{map_}"/>\n'
            f'  <apps fa="{fa}" ea="{ea}"/>\n'
            f'  <robot {robot}/>\n'
            f'{more}'
            '  <user x="3.2" y="4" heading="0"/>\n'
            f'{end}')


BAD: dict[str, Callable[[Path], str]] = {
    "a missing document": lambda folder: scenario(fa=folder / "nowhere.pxml"),
    "a bad policy value": lambda _folder: scenario(
        more='  <policy name="interrupt" state="maybe"/>\n'),
    "an unknown place": lambda _folder: scenario(robot='place="nowhere" heading="0"'),
    "malformed XML": lambda _folder: scenario(end=""),
    "an application in the wrong slot": lambda _folder: scenario(fa=EA, ea=FA),
    "places its application names that the map lacks": lambda _folder: scenario(
        map_=OFFICE, robot='x="1" y="1" heading="0"'),
}
"""Bad scenarios, each made in a folder: the last two were reported otherwise by
``prima run`` (its own checks: the application's file at 1:1, or its first problem only)."""


def command(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def problem_lines(text: str) -> list[str]:
    """The ``file:line:col: severity: message`` lines of a command's output."""
    return [line for line in text.splitlines() if ": error: " in line or ": warning: " in line]


@pytest.mark.parametrize("case", BAD)
def test_validate_run_sweep_and_the_language_server_report_alike(tmp_path: Path,
                                                                  case: str) -> None:
    path = tmp_path / "bad.xml"
    path.write_text(BAD[case](tmp_path))

    code, out, err = command("validate", str(path))
    assert code == 1
    validated = problem_lines(out)
    assert validated and all(line.startswith(str(path)) or ".pxml:" in line
                             for line in validated)

    code, out, err = command("run", str(path))
    assert (code, out) == (1, "")
    assert "Traceback" not in err
    assert sorted(problem_lines(err)) == sorted(validated)
    assert err.splitlines() == problem_lines(err)  # (nothing but the problems)

    code, _out, err = command("sweep", str(path), "--runs", "1", "--jitter", "1", "--jobs", "1",
                              "--worst", "0")
    assert code == 1
    assert sorted(problem_lines(err)) == sorted(validated)

    workspace = Workspace([tmp_path])
    files = {line.split(":", 1)[0] for line in validated}
    served = [str(p) for file in sorted(files) for p in workspace.problems(Path(file))]
    assert sorted(served) == sorted(validated)


def test_run_with_a_swapped_application_checks_what_runs(tmp_path: Path) -> None:
    """``--fa`` or ``--ea`` swaps an application the scenario names: the scenario's own is
    not checked (it does not run); the one given is, as the run loads it."""
    path = tmp_path / "s.xml"
    path.write_text(scenario(fa=EA, ea=FA))
    assert command("validate", str(path))[0] == 1
    assert command("run", str(path), "--fa", str(FA), "--ea", str(EA), "--until", "1")[0] == 0
    code, out, err = command("run", str(path), "--fa", str(FA), "--until", "1")
    assert (code, out) == (1, "")
    assert err == f'{FA}:1:1: error: this is an FA (kind="fa"); it cannot run as the EA\n'
