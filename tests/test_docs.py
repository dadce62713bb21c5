"""The docs describe every element, Command and CLI option that exists."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from lxml import etree

from prima.cli import build_parser
from prima.dsl import element_name
from prima.catalog import STANDARD_COMMANDS

ROOT = Path(__file__).parents[1]
XS = {"xs": "http://www.w3.org/2001/XMLSchema"}


def _elements(xsd: str) -> set[str]:
    tree = etree.parse(str(ROOT / "schemas" / xsd))
    return {e.get("name") for e in tree.iterfind(".//xs:element[@name]", XS)}


@pytest.mark.parametrize("xsd, doc", [("pxml.xsd", "pxml.md"), ("robot.xsd", "robot-profile.md")])
def test_every_schema_element_is_documented(xsd: str, doc: str) -> None:
    text = (ROOT / "docs" / doc).read_text()
    forms = ("<{}>", "<{} ", "`{}`")  # Command elements are listed in a table
    missing = {e for e in _elements(xsd) if not any(f.format(e) in text for f in forms)}
    assert missing == set()


def test_every_command_is_documented_in_both_forms() -> None:
    text = (ROOT / "docs" / "pxml.md").read_text()
    for spec in STANDARD_COMMANDS:
        assert f"`{spec.name}`" in text and f"`{element_name(spec.name)}`" in text, spec.name
        for param in spec.params:
            assert f"`{param.name}`" in text, (spec.name, param.name)


@pytest.mark.parametrize("command, doc", [("validate", "pxml.md"), ("run", "running.md"),
                                          ("test", "running.md"), ("judge", "judging.md"),
                                          ("sweep", "judging.md"), ("debug", "running.md"),
                                          ("check", "checking.md"),
                                          ("plot", "running.md"), ("show", "show.md"),
                                          ("lsp", "editors.md"), ("completion", "cli.md"),
                                          ("live", "live.md")])
def test_every_cli_option_is_documented(command: str, doc: str) -> None:
    text = (ROOT / "docs" / doc).read_text()
    assert f"prima {command}" in text
    sub = build_parser()._subparsers._group_actions[0].choices[command]  # type: ignore[union-attr]
    for action in sub._actions:
        for option in action.option_strings:
            if option not in ("-h", "--help"):
                assert option in text, option


def test_readme_example_validates() -> None:
    import re

    from prima.dsl import check_document

    snippet = re.search(r"```xml\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    snippet = snippet.replace('<state id="guide">', '<state id="guide" initial="true">', 1)
    source = f'<pxml xmlns="urn:prima:pxml:1" kind="ea" name="readme">{snippet}</pxml>'
    document, problems = check_document(source.encode(), "README.md")
    assert document is not None and problems == [], [str(p) for p in problems]


def test_the_scenario_example_runs(tmp_path: Path) -> None:
    """docs/scenarios.md's example, saved where its links lead (a folder of scenarios/),
    validates and runs: the files it names exist."""
    from prima.cli import main

    text = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    example = re.search(r"```xml\n(<scenario .*?)```", text, re.S)
    assert example is not None
    for folder in ("apps", "scenarios/maps"):
        (tmp_path / folder).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / folder).symlink_to(ROOT / folder)
    scenario = tmp_path / "scenarios" / "docs" / "example.xml"
    scenario.parent.mkdir()
    scenario.write_text(example.group(1), encoding="utf-8")
    assert main(["validate", str(scenario)]) == 0
    assert main(["run", str(scenario), "--until", "30", "--out", str(tmp_path / "t.txt")]) == 0


@pytest.mark.parametrize("argv, status", [
    (["--policy", "all=off", "scenarios/thesis/sample-05.xml"], 1),
    (["scenarios/thesis/sample-05.xml"], 0),
])
def test_the_judging_example_is_a_real_run(argv: list[str], status: int,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/judging.md's `prima judge` examples are the commands' outputs, as they are."""
    import io

    from prima.cli import main

    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    assert main(["judge", *argv], out=out, err=io.StringIO()) == status
    shown = f"$ prima judge {' '.join(argv)}\n{out.getvalue()}```"
    assert shown in (ROOT / "docs" / "judging.md").read_text()


def test_the_judging_tables_are_the_judges() -> None:
    """docs/judging.md's table of measures and table of thresholds list every measure
    and parameter the judge has, with its key, title, option, field and default."""
    from prima.judge import LIMITS, PARAMETERS

    text = (ROOT / "docs" / "judging.md").read_text(encoding="utf-8")
    measures = re.findall(r"^\| `(\w+)` \| ([^|]+?) \| `(--max-[\w-]+)` \|", text, re.M)
    assert measures == [(m.key, m.title, m.option) for m in LIMITS]
    options = [(option, field, None if default == "none" else float(default))
               for option, field, default in re.findall(
                   r"^\| `(--[\w-]+) [A-Z]+` \| `(\w+)` \| ([\w.]+) \|", text, re.M)]
    expected = [(m.option, m.limit, 0.0) for m in LIMITS]
    expected += [(p.option, p.name, p.default) for p in PARAMETERS]
    assert options == expected


_LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
_PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _anchors(page: Path) -> set[str]:
    """The anchors of a page's headings, as GitHub makes them."""
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    headings = re.findall(r"^#+\s+(.*)$", text, re.M)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in headings}


@pytest.mark.parametrize("page", _PAGES, ids=lambda p: p.name)
def test_every_link_of_the_docs_leads_somewhere_in_the_repository(page: Path) -> None:
    """The README and docs/ stand alone: each link names a file of the repository (and,
    with a #fragment, one of its headings) or a web address."""
    broken = []
    for target in _LINK.findall(re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"),
                                       flags=re.S)):
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path, _, fragment = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if ROOT.resolve() not in file.parents or not file.exists():
            broken.append(f"{target}: no such file in the repository")
        elif fragment and file.suffix == ".md" and fragment not in _anchors(file):
            broken.append(f"{target}: no such heading")
    assert broken == []


def test_the_shipped_maps_table_lists_every_map_and_its_places() -> None:
    from prima.scenario import load_map

    text = (ROOT / "docs" / "scenarios.md").read_text()
    section = text.split("### Shipped maps and their places", 1)[1].split("\n#", 1)[0]
    rows = re.findall(r"^\| `([^`]+\.xml)` \| `([^`]+)` \| (.*) \|$", section, re.M)
    listed = {file: (name, re.findall(r"`([^`]+)`", places)) for file, name, places in rows}
    shipped = {}
    for path in sorted((ROOT / "scenarios" / "maps").glob("*.xml")):
        world = load_map(path)
        shipped[path.name] = (world.name, [p.name for p in world.places])
    assert listed == shipped


def _first_application() -> str:
    text = (ROOT / "docs" / "pxml.md").read_text()
    return re.search(r"## A first application\n\n```xml\n(.*?)```", text, re.S).group(1)


def test_the_first_application_runs_on_the_shipped_office_map(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The doc's first application, saved as the doc gives it, validates and runs as its
    commands say, printing what the doc shows: the robot reaches the place it names."""
    import io

    from prima.cli import main

    (tmp_path / "hello-guide.pxml").write_text(_first_application(), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "hello-guide.pxml"], out=io.StringIO(), err=io.StringIO()) == 0
    out = io.StringIO()
    scenario = str(ROOT / "scenarios" / "examples" / "office-kidode.xml")
    assert main(["run", scenario, "--ea", "hello-guide.pxml", "--until", "75"],
                out=out, err=io.StringIO()) == 0
    assert "place='kidode-room'" in out.getvalue()
    assert f"```\n{out.getvalue()}```" in (ROOT / "docs" / "pxml.md").read_text()


def test_the_judging_python_example_says_what_it_gives() -> None:
    """docs/judging.md's "From Python" comments are a real run's values."""
    from prima.judge import judge
    from prima.run import Run

    text = (ROOT / "docs" / "judging.md").read_text(encoding="utf-8")
    assert ('Run("scenarios/thesis/sample-05.xml", policies={"all": False}).run()'
            in text)
    report = judge(Run(ROOT / "scenarios" / "thesis" / "sample-05.xml",
                       policies={"all": False}).run(), name="sample-05")
    shown = ", ".join(f"'{k}': {v}" for k, v in list(report.counts().items())[:5])
    assert f"report.counts()         # {{{shown}, ...}}" in text
    assert f"report.breaches()       # {report.breaches()!r}" in text
    assert f'report.of("splits")[0].text   # {report.of("splits")[0].text!r}' in text
    plain = judge(Run(ROOT / "scenarios" / "thesis" / "sample-05.xml").run())
    assert f'judge_file("scenarios/thesis/sample-05.xml").of("splits")   # {plain.of("splits")!r}' \
        in text
    from prima.run import Loaded

    rows: list[dict[str, object]] = []
    Run(ROOT / "scenarios" / "thesis" / "sample-05.xml", policies={"all": False},
        files=Loaded(), rows=rows.append).run()
    assert "judge(rows).counts() == report.counts()   # True" in text
    assert judge(rows).counts() == report.counts()


def test_the_readme_demo_output_is_a_real_runs() -> None:
    """The quickstart's pasted output is the first lines of the command it shows, as is."""
    from prima.run import Run
    from prima.trace import format_text

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"```\n(  No\.     time.*?)\n\.\.\.\n```", readme, re.S)
    assert block is not None
    real = format_text(Run(ROOT / "scenarios" / "thesis" / "sample-03.xml").run())
    shown = block.group(1).splitlines()
    assert shown == real.splitlines()[:len(shown)]


def test_the_readme_names_the_system_tools_the_tests_need_beside_the_test_command() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    command = readme.index("python -m pip install -e '.[test]' && python -m pytest")
    beside = readme[command: command + 800]
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    packages = {p for group in re.findall(r"apt-get install -y -q ([\w -]+)", ci)
                for p in group.split()}
    assert packages >= {"libxml2-utils", "chromium", "chromium-driver"}, packages
    for package in packages:
        assert package in beside, package
