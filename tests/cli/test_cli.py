"""The command line: exit codes, output formats, no tracebacks."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from prima import xmlio as _schema
from prima.cli import main
from tests.signalled import signalled_run

ROOT = Path(__file__).parents[2]
FIG_5_7 = ROOT / "scenarios" / "thesis" / "fig5-7.xml"
OFFICE = ROOT / "scenarios" / "examples" / "office-kidode.xml"
INVALID = ROOT / "tests" / "dsl" / "data" / "invalid"


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


GUIDE_APPS = [ROOT / "apps" / "fa" / "fa7-spotlight.pxml"]
"""Shipped applications written for the guide robot (robots/guide-robot.xml)."""


def test_shipped_apps_validate() -> None:
    home = [str(p) for p in sorted((ROOT / "apps").rglob("*.pxml")) if p not in GUIDE_APPS]
    code, out, err = run("validate", *home)
    assert (code, out) == (0, "")
    assert "0 error(s)" in err
    guide = str(ROOT / "robots" / "guide-robot.xml")
    code, out, err = run("validate", "--robot", guide, *map(str, GUIDE_APPS))
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
    (["run", str(FIG_5_7), "--seed", "-1"], "from 0 to 2^63 - 1"),
    (["run", str(FIG_5_7), "--seed", str(2**63)], "from 0 to 2^63 - 1"),
    (["debug", str(FIG_5_7), "--seed", "x"], "'x' is not a whole number"),
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


def test_documents_a_scenario_names_are_checked_against_its_robot_in_any_order() -> None:
    # fa7-spotlight is the guide robot's (guide-spotlight.xml names it with that robot)
    apps, scenarios = str(ROOT / "apps"), str(ROOT / "scenarios")
    assert run("validate", apps)[0] == 0  # alone too: FA7 names its robot (<pxml robot>)
    first, second = run("validate", apps, scenarios), run("validate", scenarios, apps)
    assert first[:2] == second[:2] == (0, "")
    assert " files checked: 0 error(s)" in first[2] and first[2] == second[2]


def test_a_document_is_checked_against_its_scenarios_robot_whatever_its_file_is_called(
        tmp_path: Path) -> None:
    # the guide robot's FA saved as .xml, named before the scenario that runs it there
    app = tmp_path / "spotlight.xml"
    app.write_bytes((ROOT / "apps/fa/fa7-spotlight.pxml").read_bytes())
    scenario = tmp_path / "scene.xml"
    text = (ROOT / "scenarios/examples/guide-spotlight.xml").read_text()
    text = text.replace('href="../maps/museum.xml"', f'href="{ROOT}/scenarios/maps/museum.xml"')
    text = text.replace('fa="../../apps/fa/fa7-spotlight.pxml"', 'fa="spotlight.xml"')
    text = text.replace('profile="../../robots/guide-robot.xml"',
                        f'profile="{ROOT}/robots/guide-robot.xml"')
    scenario.write_text(text)
    assert run("validate", str(app))[0] == 1  # alone: the robot it names is not beside it
    code, out, err = run("validate", str(app), str(scenario))
    assert (code, out) == (0, ""), out
    assert "4 files checked: 0 error(s)" in err  # the app, the scenario, its map, its robot


def test_unknown_xml_in_a_folder_is_skipped_but_named_is_an_error(tmp_path: Path) -> None:
    other = tmp_path / "pom.xml"
    other.write_text("<project/>")
    (tmp_path / "app.pxml").write_bytes((ROOT / "apps/ea/ea3-navigate.pxml").read_bytes())
    code, _, err = run("validate", str(tmp_path))
    assert code == 0 and "1 file checked" in err
    code, out, _ = run("validate", str(other))
    assert code == 1 and "not a PXML document" in out


@pytest.mark.parametrize("until", ["inf", "nan", "0", "-5", "1e999", "2000000"])
def test_run_refuses_an_until_that_is_not_a_sensible_time(until: str) -> None:
    code, out, err = run("run", str(OFFICE), "--until", until)
    assert code == 2 and "--until must be" in err and out == ""


def test_run_checks_its_output_path_before_running(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("")
    code, _, err = run("run", str(OFFICE), "--out", str(tmp_path / "file" / "trace.txt"))
    assert code == 2 and f"{tmp_path / 'file'} is not a folder" in err
    code, _, err = run("run", str(OFFICE), "--out", str(tmp_path))
    assert code == 2 and "is a folder" in err


HANG = 600.0
"""Seconds a test waits at most for a child process: a bound against a hang (a blocked
named pipe, a run that never stops), not a speed it must keep on a loaded machine."""


def interrupted_run(out: Path, form: str) -> str:
    """``prima run --format FORM --out OUT`` stopped with Ctrl-C once its trace has passed
    30 s of the run (tests/signalled.py); its standard error (it exits with 130)."""
    done = signalled_run("SIGINT", 30, "run", str(OFFICE), "--until", "900000", "--format",
                         form, "--out", str(out))
    assert done.returncode == 130, done.stderr
    return done.stderr


def test_ctrl_c_ends_a_run_with_130_and_keeps_the_trace_so_far(tmp_path: Path) -> None:
    out = tmp_path / "trace.jsonl"
    err = interrupted_run(out, "jsonl")
    assert "interrupted at t=" in err and "Traceback" not in err
    lines = out.read_text().splitlines()
    assert lines and all(json.loads(line)["seq"] == i for i, line in enumerate(lines[:-1]))


def test_prima_test_reports_every_scenario_even_after_a_broken_one(tmp_path: Path) -> None:
    broken = tmp_path / "a-broken.xml"
    broken.write_text('<scenario xmlns="urn:prima:scenario:1" name="x" until="5">'
                      '<map href="nowhere.xml"/><robot x="0" y="0"/></scenario>')
    (tmp_path / "a-broken.golden.txt").write_text("")
    good = tmp_path / "b-good.xml"
    text = (ROOT / "scenarios/examples/office-kidode.xml").read_text()
    text = text.replace("../../apps", str(ROOT / "apps"))
    text = text.replace("../maps", str(ROOT / "scenarios/maps"))
    good.write_text(text.replace('until="240"', 'until="5"'))
    assert run("test", str(good), "--update")[0] == 0
    code, out, err = run("test", str(tmp_path))
    assert code == 1
    assert "same      " + str(good) in out and "not found" in err
    assert "2 scenario(s): 1 failed" in err


# ---------------------------------------------------------------- hostile paths, named files

def _scenario(folder: Path, apps: str = "", robot: str = "", zones: str = "") -> Path:
    (folder / "map.xml").write_text(
        '<map xmlns="urn:prima:map:1" name="m"><place name="a" x="0" y="0"/></map>\n')
    path = folder / "s.xml"
    path.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="10">\n'
                    '  <map href="map.xml"/>\n'
                    f'  {apps}\n'
                    f'  <robot place="a"{robot}/>\n'
                    f'  {zones}\n'
                    '</scenario>\n')
    return path


def _pxml(folder: Path, name: str, kind: str, body: str = "") -> Path:
    path = folder / f"{name}.pxml"
    path.write_text(f'<pxml xmlns="urn:prima:pxml:1" kind="{kind}" name="{name}">\n'
                    f'  <state id="s" initial="true">{body}</state>\n</pxml>\n')
    return path


def test_a_named_pipe_is_a_located_error_not_a_hang(tmp_path: Path) -> None:
    fifo = tmp_path / "app.pxml"
    os.mkfifo(fifo)
    result = subprocess.run([sys.executable, "-m", "prima", "validate", str(fifo)],
                            capture_output=True, text=True, check=False, timeout=HANG)
    assert result.returncode == 1
    assert result.stdout == f"{fifo}:1:1: error: a named pipe: PRIMA reads only regular files\n"


def test_a_folder_given_as_the_robot_profile_is_a_located_error(tmp_path: Path) -> None:
    code, _, err = run("validate", "--robot", str(tmp_path), str(ROOT / "apps"))
    assert code == 1
    assert f"{tmp_path}:1:1: error: a directory: PRIMA reads only regular files" in err


FILES_ONLY = [
    ["run", "{thing}"], ["run", str(FIG_5_7), "--fa", "{thing}"],
    ["run", str(FIG_5_7), "--ea", "{thing}"], ["run", str(FIG_5_7), "--robot", "{thing}"],
    ["debug", "{thing}"], ["test", str(FIG_5_7), "--robot", "{thing}"],
    ["show", "{thing}.jsonl"], ["plot", "{thing}.jsonl", "-o", "x.svg"],
    ["plot", str(ROOT / "apps" / "fa" / "fa2-follow.pxml"), "--map", "{thing}", "-o", "x.svg"],
    ["sweep", "{thing}", "--runs", "2", "--jitter", "1"], ["check", "{thing}"],
    ["lsp", "--robot", "{thing}"],
]
"""Command lines with a place for a file and never a folder (``{thing}``)."""


@pytest.mark.parametrize(("kind", "argv"), [
    *(("folder", argv) for argv in FILES_ONLY), *(("pipe", argv) for argv in FILES_ONLY),
    ("pipe", ["judge", "{thing}.jsonl"]), ("pipe", ["test", "{thing}.xml"]),
])
def test_a_folder_or_a_named_pipe_given_as_a_file_is_said_as_what_it_is(
        kind: str, argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Not "no such file"; and the named pipe is never opened (that would wait for ever)."""
    monkeypatch.chdir(tmp_path)
    given = [word.replace("{thing}", "thing") for word in argv]
    thing = next(word for word in given if word.startswith("thing"))
    if kind == "folder":
        os.mkdir(thing)
    else:
        os.mkfifo(thing)
    code, out, err = run(*given)
    said = "is a folder, not a file" if kind == "folder" else \
        "is a named pipe, not a regular file"
    assert (code, out, err) == (2, "", f"prima {given[0]}: error: {thing}: {said}\n")


def test_a_folder_where_a_folder_may_be_is_searched_not_refused(tmp_path: Path) -> None:
    assert run("judge", str(tmp_path))[2] == f"prima judge: error: no scenario in {tmp_path}\n"


def test_a_scenario_is_checked_with_every_file_it_names(tmp_path: Path) -> None:
    _pxml(tmp_path, "fa", "fa", '<entry><goto state="nowhere"/></entry>')
    _pxml(tmp_path, "ea", "ea")
    _pxml(tmp_path, "zone", "ea", '<entry><raise event="x"/></entry>')
    path = _scenario(tmp_path, '<apps fa="fa.pxml" ea="ea.pxml"/>',
                     zones='<zone name="z" ea="zone.pxml" x1="0" y1="0" x2="1" y2="1"/>')
    code, out, err = run("validate", str(path))
    assert code == 1
    assert out.splitlines() == [
        f"{tmp_path / 'fa.pxml'}:2:52: error: no state has the id 'nowhere'",
        f"{tmp_path / 'zone.pxml'}:2:39: error: only an FA may raise its own events",
    ]
    assert "5 files checked: 2 error(s)" in err


def test_each_file_is_checked_once_however_it_is_named(tmp_path: Path) -> None:
    path = _scenario(tmp_path)
    (tmp_path / "map.xml").write_text(
        '<map xmlns="urn:prima:map:1" name="m"><place name="a" x="0" y="0" kind="x"/></map>\n')
    code, out, err = run("validate", str(tmp_path / "map.xml"), str(path), str(tmp_path))
    assert code == 1
    assert [line.split(": error:")[0] for line in out.splitlines()] == [
        f"{tmp_path / 'map.xml'}:1:73"]  # once, though loading the scenario loads the map
    assert "2 files checked" in err


@pytest.mark.parametrize("apps, zones, col, message", [
    ('<apps fa="ea.pxml"/>', "", 13, "'ea.pxml' is an EA (kind=\"ea\"); it cannot run as the FA"),
    ('<apps ea="fa.pxml"/>', "", 13, "'fa.pxml' is an FA (kind=\"fa\"); it cannot run as the EA"),
    ('<apps fa="fa.pxml" ea="twin.pxml"/>', "", 26,
     "the FA and the EA are both named 'fa'; each application needs a name of its own"),
    ('<apps fa="fa.pxml"/>', '<zone name="z" ea="twin.pxml" x1="0" y1="0" x2="1" y2="1"/>', 22,
     "the FA and this zone's EA are both named 'fa'"),
    ('<apps fa="map.xml"/>', "", 13,
     "'map.xml' is not a PXML document (its root is in 'urn:prima:map:1')"),
    ('<apps fa="fa.pxml" ea="ea.pxml"><ea href="ea-twin.pxml"/></apps>', "", 45,
     "the EAs 'ea.pxml' and 'ea-twin.pxml' are both named 'ea'"),
    # one file named twice: said once (not also as two EAs of one name)
    ('<apps fa="fa.pxml" ea="ea.pxml"><ea href="ea.pxml"/></apps>', "", 45,
     "the EA 'ea.pxml' is already running from the start"),
])
def test_applications_must_fit_their_slots(tmp_path: Path, apps: str, zones: str, col: int,
                                           message: str) -> None:
    _pxml(tmp_path, "fa", "fa")
    _pxml(tmp_path, "ea", "ea")
    (tmp_path / "twin.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="fa"><state id="s" initial="true"/>'
        "</pxml>\n")
    (tmp_path / "ea-twin.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="ea"><state id="s" initial="true"/>'
        "</pxml>\n")
    path = _scenario(tmp_path, apps, zones=zones)
    code, out, _ = run("validate", str(path))
    line = 3 if not zones else 5
    [found] = out.splitlines()
    assert code == 1 and found.startswith(f"{path}:{line}:{col}: error: {message}")


def _robot_with_gesture(folder: Path, gesture: str = "flip", broken: bool = False) -> Path:
    xml = (ROOT / "robots" / "home-robot.xml").read_text().replace(
        '<gesture name="sleep" duration="1.5"/>',
        f'<gesture name="{gesture}" duration="{0 if broken else 1}"/>')
    path = folder / "robot.xml"
    path.write_text(xml)
    return path


def test_the_documents_are_checked_against_the_profile_the_scenario_names(tmp_path: Path) -> None:
    _pxml(tmp_path, "fa", "fa", '<entry><chain>Gesture(flip)</chain></entry>')
    _robot_with_gesture(tmp_path)
    with_profile = _scenario(tmp_path, '<apps fa="fa.pxml"/>', robot=' profile="robot.xml"')
    assert run("validate", str(with_profile))[:2] == (0, "")
    # --robot wins over the scenario's profile, as in prima run
    code, out, _ = run("validate", "--robot", str(ROOT / "robots" / "home-robot.xml"),
                       str(with_profile))
    assert code == 1 and "unknown gesture 'flip'" in out


def test_a_broken_named_profile_is_reported_and_its_documents_wait(tmp_path: Path) -> None:
    _pxml(tmp_path, "fa", "fa", '<entry><chain>Gesture(flip)</chain></entry>')
    robot = _robot_with_gesture(tmp_path, broken=True)
    path = _scenario(tmp_path, '<apps fa="fa.pxml"/>', robot=' profile="robot.xml"')
    code, out, _ = run("validate", str(path))
    assert code == 1
    assert [line.split(": error:")[0].rsplit(":", 2)[0] for line in out.splitlines()] == [
        str(robot)]


def test_ctrl_c_closes_a_chrome_trace_where_the_run_stopped(tmp_path: Path) -> None:
    out = tmp_path / "trace.json"
    assert "Traceback" not in interrupted_run(out, "chrome-trace")
    events = json.loads(out.read_text())  # a whole, closed array
    begins = sum(e["ph"] == "b" for e in events)
    assert begins and begins == sum(e["ph"] == "e" for e in events)


def test_a_reader_that_stops_early_ends_the_command_quietly_with_141() -> None:
    """``prima run ... | head -1``: exit 141, as a shell reports a closed pipe (not 1, which
    says the scenario has errors), and no traceback."""
    import subprocess
    import sys

    # (a trace far longer than a pipe's buffer: the run is still writing when it closes)
    long = ROOT / "scenarios" / "thesis" / "sample-07.xml"
    proc = subprocess.Popen([sys.executable, "-m", "prima", "run", str(long), "--format",
                             "jsonl"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    assert proc.stdout.readline().startswith(b'{"t": 0')
    proc.stdout.close()
    said = proc.stderr.read()
    assert proc.wait(timeout=HANG) == 141 and b"Traceback" not in said, said
