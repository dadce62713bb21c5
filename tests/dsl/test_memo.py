"""Short texts are compiled once per process, and every use is still located where it is."""

from __future__ import annotations

from prima.dsl import (
    Kept,
    Scope,
    check_document,
    compile_expression,
    compile_template,
    keeping,
    parse_chain,
)

SCOPE = Scope({"count": 2, "name": "Ann"})


def test_the_same_short_text_gives_the_same_compiled_expression() -> None:
    first = compile_expression("count + 1 == 3")
    again = compile_expression("count + 1 == 3")
    assert again is first
    assert again.evaluate(SCOPE) is True


def test_a_long_text_is_compiled_afresh_and_alike() -> None:
    text = "'" + "x" * 2_000 + "' == name"
    first, again = compile_expression(text), compile_expression(text)
    assert again is not first
    assert again == first and again.evaluate(SCOPE) is False


def test_each_setting_has_its_own_compiled_form() -> None:
    assert compile_template("Hi {name}", max_text=10) is not compile_template("Hi {name}")
    assert compile_template("Hi {name}", max_text=10).evaluate(SCOPE) == "Hi Ann"


def test_a_memoised_chain_is_a_new_list_each_time() -> None:
    first = parse_chain('Speak("Hello."), Turn(90)')
    again = parse_chain('Speak("Hello."), Turn(90)')
    assert again == first and again is not first
    again.pop()
    assert len(parse_chain('Speak("Hello."), Turn(90)')) == 2


DOC = """<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">
  <var name="count" expr="0"/>
  <state id="s" initial="true">
    <on event="human-found" cond="count > 1 and missing == 2"><goto state="s"/></on>
    <on event="human-lost" cond="count = 3"><goto state="s"/></on>
    <on event="touched"><chain>Speak("Hi."), Fly()</chain></on>
  </state>
  <state id="t">
      <on event="human-found"    cond="count > 1 and missing == 2"><goto state="s"/></on>
      <on event="human-lost"     cond="count = 3"><goto state="s"/></on>
      <on event="touched"><chain>Speak("Hi."), Fly()</chain></on>
  </state>
</pxml>"""


def _at(line: int, written: str) -> tuple[int, int]:
    """Line and column of ``written`` on a line of DOC."""
    return line, DOC.splitlines()[line - 1].index(written) + 1


def test_every_use_of_a_text_is_located_where_it_is_written() -> None:
    expected = [
        (*_at(4, "missing"), "undefined variable 'missing'"),
        (*_at(5, "= 3"), "expression: '=' assigns"),
        (*_at(6, "Fly"), "unknown Command 'Fly'"),
        (*_at(9, "missing"), "undefined variable 'missing'"),
        (*_at(10, "= 3"), "expression: '=' assigns"),
        (*_at(11, "Fly"), "unknown Command 'Fly'"),
    ]
    assert len({(line, col) for line, col, _ in expected}) == 6
    for _ in range(2):  # the second time, every text is already memoised
        _, problems = check_document(DOC.encode(), "t.pxml")
        found = [(p.line, p.col, p.message.split(";")[0].split(" (")[0]) for p in problems
                 if p.severity.value == "error"]
        assert found == expected


CHAINS = """<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">
  <grammar id="yn"><choice value="yes">yes</choice></grammar>
  <var name="said" expr="''"/>
  <state id="s" initial="true">
    <entry><chain>a: TopologicalMove(hall), q: QA("Go?", yn, said)</chain></entry>
    <on event="touched"><chain>Speak("{event.name}")</chain></on>
    <on event="held"><goto state="t"/></on>
  </state>
  <state id="t">
    <entry><chain>a: TopologicalMove(hall), q: QA("Go?", yn, said)</chain></entry>
    <on event="touched"><chain>Speak("{event.name}")</chain></on>
  </state>
  <state id="u"><entry><chain>Speak("{event.name}")</chain></entry></state>
</pxml>"""


def _messages(text: str, kept: Kept | None = None) -> list[tuple[int, int, str]]:
    with keeping(kept or Kept()):
        found = check_document(text.encode(), "t.pxml")[1]
    return [(p.line, p.col, p.message.split(" (")[0]) for p in found]


def test_a_chain_bound_again_is_checked_again_where_it_is() -> None:
    """A chain bound without a problem is kept, and its copies replayed: their Commands
    located where each is written, their labels checked for duplicates, their names
    checked; the setting it was bound in (a handler or not, the variables declared)
    is part of what it is."""
    kept = Kept()
    first = _messages(CHAINS, kept)
    assert len(kept.chains) == 2  # the entries' chain and the handlers' (line 10: a replay)
    assert _messages(CHAINS, kept) == first
    assert _messages(CHAINS) == first == _messages_afresh(CHAINS)
    column = CHAINS.splitlines()[9].index("a:") + 1
    assert (10, column, "duplicate Command id 'a'") in first
    assert (10, CHAINS.splitlines()[9].index("q:") + 1, "duplicate Command id 'q'") in first
    event = CHAINS.splitlines()[12].index("event.name") + 1
    assert [m for m in first if "'event'" in m[2]] == [
        (13, event, "'event' is only available inside an event handler")]
    declared = CHAINS.replace('<var name="said"', '<var name="hall" expr="\'x\'"/><var name="said"')
    warned = [m for m in _messages(declared, kept) if "taken as a place name" in m[2]]
    assert [line for line, _col, _m in warned] == [5, 10]


def _messages_afresh(text: str) -> list[tuple[int, int, str]]:
    return [(p.line, p.col, p.message.split(" (")[0])
            for p in check_document(text.encode(), "t.pxml")[1]]


def test_a_document_built_again_is_the_same_document() -> None:
    from pathlib import Path

    for path in sorted((Path(__file__).resolve().parents[2] / "apps").rglob("*.pxml")):
        data = path.read_bytes()
        fresh = check_document(data, str(path))
        with keeping(Kept()) as kept:
            assert check_document(data, str(path)) == fresh, path.name
            assert check_document(data, str(path)) == fresh, path.name  # replayed
        assert len(kept.states) + len(kept.chains) > 0, path.name


def test_a_state_kept_is_the_state_built_afresh_after_any_edit() -> None:
    """States built without a problem are kept and replayed where the same text is written
    at the same place: after edits anywhere (in a state, between states, adding lines,
    breaking the document), the problems and the document are what a fresh build gives."""
    import random
    from pathlib import Path

    rng = random.Random(11)
    typed = ["a", " ", "x", '"', "<", ">", "\n", "{", "}", "(", ",", "", "", "&amp;",
             "goto", "Speak", "event.", '<timer name="t" after="1" reactive="true"/>',
             '<chain>a: Speak("x")</chain>']
    apps = sorted((Path(__file__).resolve().parents[2] / "apps").rglob("*.pxml"))
    replayed = 0
    for path in apps:
        source = path.read_text(encoding="utf-8")
        for _ in range(25):  # each an edit of the file as shipped, its states kept
            with keeping(Kept()) as kept:
                check_document(source.encode(), path.name)
                replayed += len(kept.states)
                at = rng.randrange(len(source) + 1)
                cut = min(len(source), at + rng.choice([0, 1, 3]))
                text = source[:at] + rng.choice(typed) + source[cut:]
                warm = check_document(text.encode(), path.name)
            fresh = check_document(text.encode(), path.name)
            assert warm == fresh, (path.name, text[at - 40:at + 40])
    assert replayed > 1000


def test_states_kept_check_command_ids_and_timers_across_states_again() -> None:
    doc = """<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">
  <state id="s" initial="true">
    <entry><chain>a: Speak("x")</chain><timer name="t" after="1"/></entry>
    <on event="touched"><goto state="u"/></on>
  </state>
  <state id="u"><entry><chain>b: Speak("y")</chain><timer name="t" after="2"/></entry></state>
</pxml>"""
    kept = Kept()
    assert _messages(doc, kept) == []
    assert len(kept.states) == 2
    # state u is replayed; state s, changed, now holds the same id and a reactive timer
    clash = doc.replace('a: Speak("x")', 'b: Speak("x")').replace(
        '<timer name="t" after="1"/>', '<timer name="t" after="1" reactive="true"/>')
    found = {m for _line, _col, m in _messages(clash, kept)}
    assert found == {m for _line, _col, m in _messages_afresh(clash)}
    assert "duplicate Command id 'b'" in found
    assert "timer 't' is started elsewhere with a different reactive flag" in found
