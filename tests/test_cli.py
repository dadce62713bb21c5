"""The command line: exit codes, output formats, no tracebacks."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from prima import xmlio as _schema
from prima.cli import main

ROOT = Path(__file__).parents[1]
INVALID = ROOT / "tests" / "dsl" / "data" / "invalid"


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def test_shipped_apps_validate() -> None:
    code, out, err = run("validate", str(ROOT / "apps"))
    assert (code, out) == (0, "")
    assert "0 error(s)" in err


def test_errors_exit_1_with_one_line_per_problem() -> None:
    path = INVALID / "chain-unknown-argument.pxml"
    code, out, _ = run("validate", str(path))
    assert code == 1
    assert out.splitlines() == [
        f"{path}:5:14: error: Turn needs the argument 'angle'",
        f"{path}:5:19: error: Turn has no argument 'degrees' (arguments: angle)",
    ]


def test_warnings_alone_exit_0() -> None:
    code, out, _ = run("validate", str(ROOT / "tests/dsl/data/warnings"))
    assert code == 0 and out.count(": warning: ") == 5


def test_json_format() -> None:
    code, out, _ = run("validate", "--format", "json", str(INVALID / "no-initial-state.pxml"))
    report = json.loads(out)
    assert code == 1
    assert report["errors"] == 1 and report["warnings"] == 0
    assert report["problems"][0]["line"] == 2
    assert report["problems"][0]["severity"] == "error"


def test_robot_profile_files_validate_too() -> None:
    assert run("validate", str(ROOT / "robots" / "home-robot.xml"))[0] == 0


@pytest.mark.parametrize("argv, fragment", [
    (["validate"], "required"),
    (["validate", "no/such/path"], "no such file or folder"),
    (["validate", "--format", "xml", "apps"], "invalid choice"),
    (["frobnicate"], "invalid choice"),
])
def test_usage_errors_exit_2(argv: list[str], fragment: str,
                             capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(*argv)
    assert code == 2
    assert fragment in err + capsys.readouterr().err


def test_folder_without_documents_is_a_usage_error(tmp_path: Path) -> None:
    code, _, err = run("validate", str(tmp_path))
    assert code == 2 and "no PRIMA files" in err


def test_bad_robot_profile_is_reported(tmp_path: Path) -> None:
    bad = tmp_path / "r.xml"
    bad.write_text('<robot xmlns="urn:prima:robot:1" name="r"/>')
    code, _, err = run("validate", "--robot", str(bad), str(ROOT / "apps"))
    assert code == 1 and f"{bad}:1:1: error:" in err


@pytest.mark.parametrize("build", [_schema.schema, _schema.verdict_schema],
                         ids=["xmlschema", "libxml2"])
def test_schemas_are_built_once_per_process(build) -> None:  # type: ignore[no-untyped-def]
    folders = [str(ROOT / "apps"), str(INVALID)]
    run("validate", *folders)
    before = build.cache_info()
    run("validate", *folders)
    after = build.cache_info()
    assert after.misses == before.misses and after.hits > before.hits


def test_python_m_prima_never_prints_a_traceback() -> None:
    result = subprocess.run([sys.executable, "-m", "prima", "validate", str(INVALID)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 1
    assert "Traceback" not in result.stdout + result.stderr
    assert result.stdout.count(": error: ") >= 30


def test_scenario_files_validate_like_documents(tmp_path: Path) -> None:
    bad = tmp_path / "bad-scenario.xml"
    bad.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="10">\n'
                   '  <map href="nowhere.xml"/>\n  <robot x="0" y="0"/>\n</scenario>\n')
    code, out, _ = run("validate", str(bad))
    assert code == 1
    assert out.startswith(f"{bad}:2:") and ": error: " in out


def test_shipped_scenarios_and_maps_validate() -> None:
    code, out, err = run("validate", str(ROOT / "scenarios"))
    assert (code, out) == (0, "")
    assert "0 error(s)" in err


def test_unknown_xml_in_a_folder_is_skipped_but_named_is_an_error(tmp_path: Path) -> None:
    other = tmp_path / "pom.xml"
    other.write_text("<project/>")
    (tmp_path / "app.pxml").write_bytes((ROOT / "apps/ea/ea3-navigate.pxml").read_bytes())
    code, _, err = run("validate", str(tmp_path))
    assert code == 0 and "1 file checked" in err
    code, out, _ = run("validate", str(other))
    assert code == 1 and "not a PXML document" in out
