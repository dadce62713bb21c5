"""``prima lsp`` driven through the protocol, as an editor drives it: a real server
process over stdio, pygls's client on this side."""

from __future__ import annotations

import asyncio
import io
import shutil
from collections.abc import Awaitable, Callable
from pathlib import Path

import pytest

pytest.importorskip("pygls")

from lsprotocol import types  # noqa: E402

from prima.cli import main  # noqa: E402
from tests.lsp.client import Session, uri, where  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SEVERITY = {types.DiagnosticSeverity.Error: "error", types.DiagnosticSeverity.Warning: "warning"}


def run(root: Path, test: Callable[[Session], Awaitable[None]], *args: str) -> None:
    async def session() -> None:
        async with Session(root, *args) as s:
            await test(s)

    asyncio.run(session())


def lines(diagnostics: list[types.Diagnostic], name: str) -> list[str]:
    """Diagnostics as prima validate prints problems: file:line:col: severity: message."""
    return [f"{name}:{d.range.start.line + 1}:{d.range.start.character + 1}: "
            f"{SEVERITY[d.severity or types.DiagnosticSeverity.Error]}: {d.message}"
            for d in diagnostics]


def validate(*paths: Path, name: Path) -> list[str]:
    """What prima validate PATHS prints about the file ``name``."""
    out = io.StringIO()
    main(["validate", *map(str, paths)], out=out, err=io.StringIO())
    return [line for line in out.getvalue().splitlines() if line.startswith(f"{name}:")]


SHIPPED = ROOT / "apps" / "ea" / "ea3-navigate.pxml"
FAULTS = (
    ('Speak("Come on, let\'s go.")', 'Speek("Come on, let\'s go.")'),  # did you mean 'Speak'
    ("cond=\"event.kind == 'corner' and goal != ''\"",
     "cond=\"event.kind == 'corner' and gaol != ''\""),  # did you mean 'goal'
    ('<goto state="arrived"/>', '<goto state="arived"/>'),
    ('cond="event.place == goal"', 'cond="event.place == goal &amp;&amp; 1"'),
)


def broken(text: str) -> str:
    for right, wrong in FAULTS:
        assert right in text
        text = text.replace(right, wrong, 1)
    return text


def test_a_shipped_app_and_a_broken_copy_get_prima_validates_diagnostics(tmp_path: Path) -> None:
    copy = tmp_path / "ea3-broken.pxml"
    copy.write_text(broken(SHIPPED.read_text(encoding="utf-8")), encoding="utf-8")
    expected = validate(copy, name=copy)
    assert len(expected) == len(FAULTS) + 1  # and a warning: 'arrived' is now unreachable
    assert any(": warning: state 'arrived' is unreachable" in line for line in expected)
    assert any("did you mean 'Speak'?" in line for line in expected)
    assert any("did you mean 'goal'?" in line for line in expected)
    shipped_expected = validate(SHIPPED, ROOT / "scenarios" / "examples" / "office-kidode.xml",
                                name=SHIPPED)

    async def test(s: Session) -> None:
        assert lines(await s.open(SHIPPED), str(SHIPPED)) == shipped_expected == []
        assert lines(await s.open(copy), str(copy)) == expected

    run(ROOT, test)
    run(tmp_path, test)


def test_diagnostics_follow_the_keystrokes(tmp_path: Path) -> None:
    """As you type: a fault appears when it is typed and goes when it is mended, in
    the buffer (the file on disk never changes)."""
    path = tmp_path / "ea3.pxml"
    text = SHIPPED.read_text(encoding="utf-8")
    path.write_text(text, encoding="utf-8")

    async def test(s: Session) -> None:
        assert await s.open(path) == []
        typo = text.replace("Speak(\"O.K.\")", "Speak(\"O.K.\"", 1)
        faults = await s.change(path, typo)
        assert [d.message for d in faults] == [
            line.split(": error: ")[1] for line in _validate_text(tmp_path, typo)]
        assert faults and faults[0].range.start.line == text[:text.index('Speak("O.K.")')] \
            .count("\n")
        assert await s.change(path, text) == []

    run(tmp_path, test)
    assert path.read_text(encoding="utf-8") == text


def _validate_text(folder: Path, text: str) -> list[str]:
    other = folder / "typed" / "ea3.pxml"
    other.parent.mkdir(exist_ok=True)
    other.write_text(text, encoding="utf-8")
    return validate(other, name=other)


def _visit(folder: Path, ea_text: str) -> tuple[Path, Path]:
    """A workspace with a scenario that runs an EA (written ``ea_text``) on the office map."""
    (folder / "maps").mkdir()
    shutil.copy(ROOT / "scenarios" / "maps" / "office.xml", folder / "maps" / "office.xml")
    shutil.copy(ROOT / "apps" / "fa" / "fa2-follow.pxml", folder / "fa.pxml")
    ea = folder / "guide.pxml"
    ea.write_text(ea_text, encoding="utf-8")
    scenario = folder / "visit.xml"
    scenario.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<scenario xmlns="urn:prima:scenario:1" name="visit" until="60">\n'
        '  <map href="maps/office.xml"/>\n'
        '  <apps fa="fa.pxml" ea="guide.pxml"/>\n'
        '  <robot place="entrance"/>\n'
        '</scenario>\n', encoding="utf-8")
    return ea, scenario


def test_a_document_is_checked_with_the_scenario_that_runs_it(tmp_path: Path) -> None:
    """The scenario's map is in force: a place it lacks is an error, with the map's
    closest place, exactly as prima validate of the scenario says it."""
    text = SHIPPED.read_text(encoding="utf-8").replace(
        "TopologicalMove({goal})</chain>\n    </entry>",
        'TopologicalMove("kidode_room")</chain>\n    </entry>', 1)
    ea, scenario = _visit(tmp_path, text)
    expected = validate(scenario, ea, name=ea)
    assert len(expected) == 1 and "did you mean 'kidode-room'?" in expected[0]
    assert validate(ea, name=ea) == []  # alone, a document knows no map

    async def test(s: Session) -> None:
        assert lines(await s.open(ea), str(ea)) == expected

    run(tmp_path, test)


def _chain_start(text: str, needle: str) -> tuple[int, int]:
    """Where the chain holding ``needle`` starts (just after its ``<chain...>``)."""
    at = text.index(needle)
    tag = text.rindex("<chain", 0, at)
    return where(text, text[tag:at + 1], text.index(">", tag) + 1 - tag)


def test_completion_in_a_chain_offers_the_robots_commands_with_their_arguments() -> None:
    from prima.catalog import Catalog

    fa = ROOT / "apps" / "fa" / "fa2-follow.pxml"
    ea = SHIPPED
    spotlight = ROOT / "apps" / "fa" / "fa7-spotlight.pxml"
    fa_text, ea_text = fa.read_text(encoding="utf-8"), ea.read_text(encoding="utf-8")
    speak = Catalog.standard()["Speak"]

    async def test(s: Session) -> None:
        await s.open(fa)
        items = {i.label: i for i in await s.complete(fa, *_chain_start(fa_text, "Speak("))}
        assert {c.name for c in Catalog.standard()} | {"TakePicture"} <= set(items)
        assert items["Speak"].detail == "Speak(text)"
        assert items["Speak"].insert_text_format is types.InsertTextFormat.Snippet
        assert items["Speak"].text_edit.new_text == "Speak(${1:text})"  # type: ignore[union-attr]
        assert items["QA"].detail == "QA(prompt, grammar, into?, timeout=8)"
        doc = items["Speak"].documentation
        assert isinstance(doc, types.MarkupContent) and doc.value == speak.describe()
        await s.open(ea)  # an EA: the common Commands only
        labels = {i.label for i in await s.complete(ea, *_chain_start(ea_text, "StopMoving()"))}
        assert "Speak" in labels and "TakePicture" not in labels
        # the guide robot's own Command, for its FA (the scenario that runs it names the robot)
        await s.open(spotlight)
        text = spotlight.read_text(encoding="utf-8")
        labels = {i.label for i in await s.complete(spotlight, *_chain_start(text, "Spotlight("))}
        assert "Spotlight" in labels and "TakePicture" not in labels
        # inside a Command's parentheses: its arguments, and the places of the scenario's map
        line, col = where(ea_text, "TopologicalMove({goal})", len("TopologicalMove("))
        items = {i.label: i for i in await s.complete(ea, line, col)}
        assert {"kidode-room", "hall", "to="} <= set(items)
        assert items["kidode-room"].text_edit.new_text == '"kidode-room"'  # type: ignore[union-attr]
        assert items["to="].detail == "place"

    run(ROOT, test)


def test_completion_of_states_events_and_fields() -> None:
    text = SHIPPED.read_text(encoding="utf-8")

    async def test(s: Session) -> None:
        await s.open(SHIPPED)
        states = {i.label for i in await s.complete(
            SHIPPED, *where(text, '<goto state="arrived"', len('<goto state="')))}
        assert states == {"ask-goal", "guide", "tell-message", "navigating", "arrived"}
        events = {i.label for i in await s.complete(
            SHIPPED, *where(text, '<on event="message"', len('<on event="')))}
        assert {"message", "human-found", "place-reached", "interrupted"} <= events
        assert "touched" not in events  # the robot's own events are an FA's
        fields = {i.label for i in await s.complete(
            SHIPPED, *where(text, "event.sender", len("event.")))}
        assert fields == {"sender", "text"}
        ids = {i.label for i in await s.complete(
            SHIPPED, *where(text, '<on-answer of="where"', len('<on-answer of="')))}
        assert ids == {"where", "reply"}  # the Q&As' ids

    run(ROOT, test)


def test_hover_shows_the_documentation_of_commands_elements_and_attributes() -> None:
    from prima.catalog import Catalog

    text = SHIPPED.read_text(encoding="utf-8")

    async def test(s: Session) -> None:
        await s.open(SHIPPED)
        found = await s.hover(SHIPPED, *where(text, 'Speak("Come on', 2))
        assert found is not None and isinstance(found.contents, types.MarkupContent)
        assert Catalog.standard()["Speak"].describe() in found.contents.value
        goto = await s.hover(SHIPPED, *where(text, "<goto state", 2))
        assert goto is not None and "Leaves the current state" in str(goto.contents)
        order = await s.hover(SHIPPED, *where(text, 'order="asap"', 1))
        assert order is not None and "after-latest" in str(order.contents)

    run(ROOT, test)


def test_hover_shows_a_variables_source_in_a_fence_it_cannot_close(tmp_path: Path) -> None:
    ea = tmp_path / "fenced.pxml"
    declared = ('<var name="v" expr="\'x\n```\n# not code\n![seen](https://example.org/p.png)'
                '\n````\'"/>')
    text = (f'<pxml xmlns="urn:prima:pxml:1" kind="ea" name="fenced">\n{declared}\n'
            '<state id="s" initial="true"><entry><log text="{v}"/></entry></state></pxml>\n')
    ea.write_text(text, encoding="utf-8")

    async def test(s: Session) -> None:
        assert await s.open(ea) == []
        found = await s.hover(ea, *where(text, "{v}", 1))
        assert found is not None and isinstance(found.contents, types.MarkupContent)
        assert found.contents.value == f"**variable v**\n\n`````xml\n{declared}\n`````"

    run(tmp_path, test)


def test_go_to_definition_finds_a_state_a_label_and_a_variable() -> None:
    text = SHIPPED.read_text(encoding="utf-8")

    async def test(s: Session) -> None:
        await s.open(SHIPPED)
        for use, definition in (('<goto state="guide"', '<state id="guide"'),
                                ('<on-answer of="where"', "where: QA"),
                                ("goal != ''", '<var name="goal"')):
            shift = len(use) - 2 if use.startswith("<") else 1
            found = await s.definition(SHIPPED, *where(text, use, shift))
            assert [f.uri for f in found] == [uri(SHIPPED)], use
            name = definition.rsplit('"', 2)[1] if definition.endswith('"') \
                else definition.split(":")[0]
            start = text.index(definition) + definition.index(name)
            assert (found[0].range.start.line, found[0].range.start.character) == \
                where(text, definition, definition.index(name)), use
            assert text[start:start + len(name)] == name

    run(ROOT, test)


def test_positions_are_counted_as_the_editor_counts_them(tmp_path: Path) -> None:
    """The protocol counts UTF-16 code units: a character outside the BMP before a
    fault shifts its column by two, not one."""
    path = tmp_path / "emoji.pxml"
    text = ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="e">\n'
            '  <var name="count" expr="0"/>\n'
            '  <state id="s" initial="true"><entry>'
            '<log text="\U0001F600 {cuont}"/></entry></state>\n'
            '</pxml>\n')
    path.write_text(text, encoding="utf-8")
    [problem] = validate(path, name=path)
    col = int(problem.split(":")[2])

    async def test(s: Session) -> None:
        [found] = await s.open(path)
        assert found.message == "undefined variable 'cuont'; did you mean 'count'?"
        assert (found.range.start.line, found.range.start.character) == (3, col)  # col-1+1

    run(tmp_path, test)


def test_a_scenario_completes_its_maps_places_and_leads_to_its_files() -> None:
    scenario = ROOT / "scenarios" / "examples" / "office-kidode.xml"
    office = ROOT / "scenarios" / "maps" / "office.xml"
    text = scenario.read_text(encoding="utf-8")
    map_text = office.read_text(encoding="utf-8")

    async def test(s: Session) -> None:
        assert await s.open(scenario) == []
        places = {i.label for i in await s.complete(
            scenario, *where(text, '<walk at="40" to="poster"', len('<walk at="40" to="')))}
        assert places == {"entrance", "hall", "poster", "corner", "kidode-door", "kidode-room"}
        walk = await s.hover(scenario, *where(text, '<walk at="40"', 2))
        assert walk is not None and "The user walks" in str(walk.contents)
        [place] = await s.definition(scenario, *where(text, 'to="poster"', 5))
        assert place.uri == uri(office)
        assert (place.range.start.line, place.range.start.character) == \
            where(map_text, 'name="poster"', len('name="'))
        [fa] = await s.definition(scenario, *where(text, 'fa="../../apps', 6))
        assert fa.uri == uri(ROOT / "apps" / "fa" / "fa2-follow.pxml")

    run(ROOT, test)


BREAKS = {
    "apps/ea/ea3-navigate.pxml": FAULTS,
    "scenarios/examples/office-kidode.xml": (('place="entrance"', 'place="entrence"'),
                                             ('at="40" to="poster"', 'at="40" to="postr"')),
    "scenarios/maps/library.xml": (('<wall x1="8" y1="1"', '<wall x1="8" y1="1e999"'),),
    "apps/fa/fa1-emotions.pxml": (("<state ", "<state  bogus=\"1\" "),),
    "robots/guide-robot.xml": (("<gesture ", "<gesture speed=\"fast\" "),),
    "apps/ea/ea2-library.pxml": (('<timer name="ask-later" after="30"/>',
                                  '<timer name="ask-later" after="{\'later\'}"/>'),
                                 ('{book}?", yesno)', '{book}?", yesno, timeout=-1)')),
}
"""Damage done to copies of shipped files (each text replaced once, where it is)."""


def _shipped_tree(folder: Path, broken: bool) -> list[Path]:
    """Copies of apps/, scenarios/ and robots/ (with the damage of BREAKS, if ``broken``):
    their documents, profiles, scenarios and maps."""
    for part in ("apps", "scenarios", "robots"):
        shutil.copytree(ROOT / part, folder / part,
                        ignore=shutil.ignore_patterns("*.golden.txt", "__pycache__", "*.py"))
    for name, faults in BREAKS.items() if broken else ():
        path = folder / name
        text = path.read_text(encoding="utf-8")
        for right, wrong in faults:
            assert right in text, (name, right)
            text = text.replace(right, wrong, 1)
        path.write_text(text, encoding="utf-8")
    return sorted(p for p in folder.rglob("*") if p.suffix in (".pxml", ".xml"))


@pytest.mark.parametrize("broken", [False, True], ids=["shipped", "broken"])
def test_every_file_gets_exactly_what_prima_validate_reports(tmp_path: Path,
                                                             broken: bool) -> None:
    """Every shipped document, profile, scenario and map (and copies with faults typed
    into six of them), open in the editor: the diagnostics are prima validate's lines
    for that file, as ``prima validate apps scenarios robots`` checks it (a document with
    the first scenario that runs it): the same problems, wording and positions."""
    files = _shipped_tree(tmp_path, broken)
    out = io.StringIO()
    main(["validate", *(str(tmp_path / p) for p in ("apps", "scenarios", "robots"))],
         out=out, err=io.StringIO())
    expected: dict[str, list[str]] = {}
    for line in out.getvalue().splitlines():
        if not line.startswith(" "):
            expected.setdefault(line.split(":", 1)[0], []).append(line)
    if broken:
        assert {str(tmp_path / name) for name in BREAKS} <= set(expected), expected
        assert sum(map(len, expected.values())) >= 8

    async def test(s: Session) -> None:
        for path in files:
            assert lines(await s.open(path), str(path)) == expected.get(str(path), []), path

    run(tmp_path, test)


def test_robot_option_overrides_the_robot_a_document_names(tmp_path: Path) -> None:
    """``prima lsp --robot`` checks as ``prima validate --robot`` does: against that
    profile, not the one the document's robot attribute names."""
    (tmp_path / "apps" / "fa").mkdir(parents=True)
    shutil.copytree(ROOT / "robots", tmp_path / "robots",
                    ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    fa = tmp_path / "apps" / "fa" / "fa7-spotlight.pxml"
    shutil.copy(ROOT / "apps" / "fa" / "fa7-spotlight.pxml", fa)
    home = tmp_path / "robots" / "home-robot.xml"
    out = io.StringIO()
    main(["validate", "--robot", str(home), str(fa)], out=out, err=io.StringIO())
    expected = [line for line in out.getvalue().splitlines() if line.startswith(str(fa))]
    assert any("unknown Command 'Spotlight'" in line for line in expected)

    async def test(s: Session) -> None:
        assert lines(await s.open(fa), str(fa)) == expected

    run(tmp_path, test, "--robot", str(home))
