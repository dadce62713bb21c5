"""``prima show``: the page of a run, checked as text and in a real headless browser."""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from prima.cli import main

pytest.importorskip("plotly", reason="prima show needs the show extra (plotly)")

from prima.show import read_rows, render  # noqa: E402 - after the skip
from tests.browser import STEPPED_CLOCK, headless_chromium, until

ROOT = Path(__file__).parents[2]
SCENARIOS = sorted(p for folder in ("thesis", "policies", "examples")
                   for p in (ROOT / "scenarios" / folder).glob("*.xml"))
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"


def _cli(*argv: str) -> tuple[int, str]:
    err = io.StringIO()
    status = main(list(argv), out=io.StringIO(), err=err)
    return status, err.getvalue()


# ------------------------------------------------------------------ the page as text

def test_a_scenario_and_its_jsonl_trace_make_the_same_page(tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    assert main(["run", str(SAMPLE_03), "--format", "jsonl", "--out", str(trace)]) == 0
    from_scenario, from_trace = tmp_path / "a.html", tmp_path / "b.html"
    assert _cli("show", str(SAMPLE_03), "-o", str(from_scenario))[0] == 0
    status, said = _cli("show", str(trace), "--scenario", str(SAMPLE_03),
                        "--out", str(from_trace))
    assert status == 0, said
    assert "353 atomic behavior(s)" in said
    # the same but for the title (the input's name)
    assert (from_scenario.read_text().replace("sample-03", "run")
            == from_trace.read_text())


def test_the_page_is_deterministic_and_self_contained() -> None:
    rows = read_rows(SAMPLE_03)
    page = render(rows, scenario=SAMPLE_03, title="sample-03")
    assert page == render(read_rows(SAMPLE_03), scenario=SAMPLE_03, title="sample-03")
    assert "<script src=" not in page and 'src="http' not in page  # offline: nothing fetched
    assert "Plotly.newPlot" in page and 'id="timeline"' in page and 'id="map"' in page


def test_a_trace_without_its_scenario_has_no_map(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    trace = tmp_path / "run.jsonl"
    assert main(["run", str(SAMPLE_03), "--format", "jsonl", "--out", str(trace)]) == 0
    monkeypatch.chdir(tmp_path)
    status, said = _cli("show", str(trace))  # the default page: run.html, here
    assert status == 0 and "no map" in said
    assert (tmp_path / "run.html").is_file()


def test_the_timeline_draws_waits_as_spans_and_blends_on_half_rows() -> None:
    """The page draws :mod:`prima.timeline`'s digest, as ``prima plot`` does: a hold
    is a span (not an instant), a blended AB has half its device's row."""
    from prima.show._model import build
    from prima.show._page import timeline_figure

    rows = read_rows(ROOT / "scenarios" / "policies" / "blend-on.xml")
    model = build(rows)
    fig, traces = timeline_figure(model)
    hold = next(t for t in fig.data if t.meta == "hold")
    spans = [s for s in model.timeline.spans if s.kind == "hold"]
    # EA1's move kept for FA3's reaction's next AB, then held while FA3 talks, before the
    # dance; held while FA3 talks after it
    assert [(s.reason, s.holder) for s in spans] == [
        ("reserved", "fa3-dance"), ("keep-channel", ""), ("keep-channel", "")]
    assert spans[0].t1 == spans[1].t0  # (held anew: one wait ends where the next begins)
    bases = [span.t0 for span in spans for _d in span.devices]
    assert list(hold.base) == bases and min(hold.x) > 0.5
    assert [model.rows[i]["kind"] for i in hold.customdata] == ["hold"] * len(bases)
    assert not any(t.meta == "marks" and "held" in t.name for t in fig.data)
    widths = [w for i in traces["bars"] for w in fig.data[i].width]
    # each app's bars, unblended first: the legend's swatch is drawn like the first bar
    blended = [b.blended for app in model.timeline.apps
               for b in sorted(model.timeline.bars, key=lambda b: b.blended) if b.app == app]
    assert any(blended) and widths == [0.4 if b else 0.8 for b in blended]
    assert not any(fig.data[i].marker.pattern.shape[0] for i in traces["bars"])
    assert list(fig.layout.yaxis.categoryarray)[::-1] == model.timeline.devices


def test_a_feedback_commands_iterations_are_one_labelled_bar() -> None:
    """As ``prima plot`` draws them: a run of iterations (``TrackingHuman x195``) is one
    bar without seams, labelled once, over its iterations' bars, which keep their hover
    and click (the run's bar takes neither) and no label of their own. An iteration cut
    and restarted ends one run and begins the next (``x3``, then ``x195``)."""
    from prima.show._model import build
    from prima.show._page import timeline_figure

    model = build(read_rows(SAMPLE_03))
    fig, traces = timeline_figure(model)
    labelled = [t for t in fig.data if t.meta == "runs"]
    assert labelled and all(t.hoverinfo == "skip" for t in labelled)
    labels = [text for t in labelled for text in t.text]
    assert {"TrackingHuman x3", "TrackingHuman x195", "TopologicalMove x43"} <= set(labels)
    texts = {ab: text for i in traces["bars"]
             for ab, text in zip(fig.data[i].customdata, fig.data[i].text, strict=True)}
    tracking = [b.ab for b in model.timeline.bars if b.command == "TrackingHuman"]
    assert tracking and all(texts[ab] == "" for ab in tracking)
    assert any(text == "Speak" for text in texts.values())  # a lone AB keeps its label


def test_a_long_runs_page_is_written_a_piece_at_a_time() -> None:
    """The timeline of a long run is written a trace at a time and each long array of a
    trace in pieces, never as one JSON text (which, escaped for the page, took several
    times its size): what writing the page takes beyond a short run's hardly grows."""
    import os
    import tracemalloc

    from prima.show._model import build
    from prima.show._page import write_page

    def peak(abs_: int) -> int:
        model = build(line for ab in range(1, abs_ + 1) for line in (
            {"t": ab * 2.0, "seq": 2 * ab, "kind": "start", "app": "a", "ab": ab,
             "command": "Speak", "text": f"<words> & {ab}", "devices": ["speaker"]},
            {"t": ab * 2.0 + 1.0, "seq": 2 * ab + 1, "kind": "end", "app": "a", "ab": ab}))
        with open(os.devnull, "w", encoding="utf-8") as out:
            tracemalloc.start()
            try:
                write_page(model, None, "run", out)
                return tracemalloc.get_traced_memory()[1]
            finally:
                tracemalloc.stop()

    peak(100)  # (Plotly's modules imported and its JavaScript read once)
    short, long = peak(2_000), peak(30_000)
    # (as one text, 21 MiB more here, some 800 bytes an AB)
    assert long - short < 400 * 28_000, f"{(long - short) / 28_000:.0f} bytes more an AB"


@pytest.mark.parametrize("content, message", [
    ('{"t": 0, "seq": 0, "kind": "start"}\nnot json\n', "run.jsonl:2:1: error: not a JSON"),
    ('{"t": 0, "kind": "start"}\n', "run.jsonl:1:1: error: missing field 'seq'"),
    ("", "run.jsonl:1:1: error: the trace has no lines"),
])
def test_a_bad_trace_is_a_located_error(tmp_path: Path, content: str, message: str) -> None:
    trace = tmp_path / "run.jsonl"
    trace.write_text(content)
    status, said = _cli("show", str(trace), "-o", str(tmp_path / "x.html"))
    assert status == 1
    assert message in said.splitlines()[0], said
    assert "Traceback" not in said and not (tmp_path / "x.html").exists()


def test_without_plotly_it_says_which_extra_to_install(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import sys

    monkeypatch.delitem(sys.modules, "prima.show._page", raising=False)
    monkeypatch.setitem(sys.modules, "plotly", None)  # an import of it fails
    status, said = _cli("show", str(SAMPLE_03), "-o", str(tmp_path / "x.html"))
    assert status == 2  # checked before the scenario runs, as plot does
    assert said == ("prima show: error: Plotly is not installed; install the show extra: "
                    "pip install 'prima[show]' (in a checkout of PRIMA: pip install -e "
                    "'.[show]')\n")
    assert not (tmp_path / "x.html").exists()


@pytest.mark.parametrize("argv, message", [
    (["missing.jsonl"], "no such file: missing.jsonl"),
    (["README.md"], "give a trace (*.jsonl) or a scenario (*.xml)"),
    ([str(SAMPLE_03), "--scenario", str(SAMPLE_03)], "--scenario goes with a jsonl trace"),
    ([str(SAMPLE_03), "-o", "README.md/x.html"], "--out README.md/x.html: README.md is not "
                                                 "a folder"),
    ([str(SAMPLE_03), "-o", "."], "is a folder"),
])
def test_usage_errors(argv: list[str], message: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    status, said = _cli("show", *argv)
    assert status == 2 and message in said and len(said.splitlines()) == 1, said


# ------------------------------------------------------------ the page in a browser

@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    yield from headless_chromium()


def _open(browser: Any, scenario: Path, folder: Path) -> list[dict[str, Any]]:
    """Write the scenario's page, open it from file://; its trace rows."""
    rows = read_rows(scenario)
    page = folder / f"{scenario.stem}.html"
    page.write_text(render(rows, scenario=scenario, title=scenario.stem), encoding="utf-8")
    browser.get(page.as_uri())
    until(browser, "return !!window.primaShow")
    browser.execute_script(STEPPED_CLOCK)
    return rows


def _errors(browser: Any) -> list[str]:
    return [e["message"] for e in browser.get_log("browser") if e["level"] == "SEVERE"]


def test_the_table_says_why_a_command_got_nowhere(browser: Any, tmp_path: Path) -> None:
    """A move the user stands in the way of tries again and again (prima live's first
    example: nothing on the page said why the guide stood still); one that gives up
    says its error."""
    head = {"app": "ea1", "ab": 7, "tree": 1, "command": "TopologicalMove",
            "reason": "completed", "devices": ["locomotion"],
            "robot": {"x": 1.0, "y": 1.0, "heading": 0.0}}
    rows = [{"t": 0.0, "seq": 0, "kind": "start", **head, "reason": "free-devices",
             "detail": {"args": "to=panel-1"}},
            {"t": 1.5, "seq": 1, "kind": "end", **head,
             "detail": {"args": "to=panel-1", "result": "blocked=True, goal=panel-1"}},
            {"t": 9.0, "seq": 2, "kind": "end", **head,
             "detail": {"args": "to=panel-1", "error": "blocked on the way to 'panel-1'",
                        "result": "error=blocked on the way to 'panel-1'"}}]
    page = tmp_path / "blocked.html"
    page.write_text(render(rows, title="blocked"), encoding="utf-8")
    browser.get(page.as_uri())
    until(browser, "return !!window.primaShow")
    said = browser.execute_script(
        "return Array.from(document.querySelectorAll('#trace tbody tr'))"
        ".map(tr => tr.cells[5].textContent)")
    assert said == ["TopologicalMove to=panel-1",
                    "TopologicalMove to=panel-1 (blocked: something in the way; it tries again)",
                    "TopologicalMove to=panel-1 (failed: blocked on the way to 'panel-1')"]


_ROBOT_MARKER = """
const trace = document.querySelectorAll('#map .scatterlayer .trace')[PRIMA_SHOW.robotTrace];
return trace.querySelector('.point').getAttribute('transform');
"""

_BARS = """
const gd = document.getElementById('timeline');
const out = [];
gd.data.forEach(function (trace, i) {
  if (trace.meta === 'runs') return;  // a run's label bar: no AB of its own
  if (trace.meta === 'marks') {
    trace.customdata.forEach(function (row, j) {
      out.push([row, trace.y[j], trace.x[j], 0, i, j, null, trace.meta]);
    });
    return;
  }
  const drawn = document.querySelectorAll('#timeline .barlayer .trace')[i]
    .querySelectorAll('.point path');
  trace.customdata.forEach(function (ab, j) {
    out.push([ab, trace.y[j], trace.base[j], trace.x[j], i, j, drawn.length, trace.meta]);
  });
});
return out;
"""


def _first_move(rows: list[dict[str, Any]]) -> float | None:
    """When the robot first leaves its first pose (None: it never does)."""
    first = None
    for row in rows:
        pose = row.get("robot")
        if pose is None:
            continue
        here = (pose["x"], pose["y"])
        if first is None:
            first = here
        elif abs(here[0] - first[0]) + abs(here[1] - first[1]) > 0.05:
            return float(row["t"])
    return None


def _clickable(bars: list[list[Any]], spans: list[list[Any]]) -> list[Any]:
    """The widest bar no suspension span nor mark (drawn over the bars) covers."""
    free = [b for b in bars if not any(s[1] == b[1] and s[2] <= b[2] + b[3] and b[2] <= s[2] + s[3]
                                       for s in spans)]
    return max(free or bars, key=lambda b: b[3])


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_the_page_in_a_browser(browser: Any, scenario: Path, tmp_path: Path) -> None:
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    rows = _open(browser, scenario, tmp_path)
    assert _errors(browser) == []

    # every AB of the trace has its bar, drawn
    drawn = browser.execute_script(_BARS)
    bars = [b for b in drawn if b[7] == "bars"]
    starts = {r["ab"] for r in rows if r["kind"] == "start"}
    assert {b[0] for b in bars} == starts
    for trace in {b[4] for b in drawn if b[7] != "marks"}:
        assert sum(1 for b in drawn if b[4] == trace) == next(b[6] for b in drawn
                                                              if b[4] == trace)

    # playing moves the robot (from just before it first moves): 0.6 s of the page's
    # clock at 16x is 9.6 s of the run, stepped by the test (browser.STEPPED_CLOCK)
    moves = _first_move(rows)
    if moves is not None:
        start = max(0.0, moves - 1.0)
        browser.execute_script(f"window.primaShow.seek({start})")
        before = browser.execute_script(_ROBOT_MARKER)
        browser.execute_script("document.getElementById('speed').value = '16';")
        browser.find_element(By.ID, "play").click()
        browser.execute_script("window.stepClock(1000); window.stepClock(1600);")
        browser.find_element(By.ID, "play").click()  # pause
        played = browser.execute_script("return window.primaShow.time()")
        assert played == pytest.approx(min(start + 9.6, browser.execute_script(
            "return PRIMA_SHOW.end")))
        assert played > moves
        assert browser.execute_script(_ROBOT_MARKER) != before

    # the user's words read as said in their bubble (quotes, not &quot;)
    said = next((r for r in rows if r["kind"] == "user" and r.get("action") == "say"), None)
    if said is not None:
        browser.execute_script(f"window.primaShow.seek({said['t'] + 0.1})")
        shown = until(browser, "const want = arguments[0], shown = Array.from("
                      "document.querySelectorAll('#map .annotation-text'))"
                      ".map(function (e) { return e.textContent; });"
                      "return shown.some(function (t) { return t.includes(want); }) "
                      "? shown : null;", f'"{said["text"][:40]}')
        assert any(f'"{said["text"][:40]}' in text for text in shown), shown
        assert not any("&quot;" in text or "&amp;" in text for text in shown), shown

    # clicking a bar shows its decision's reason
    ab, _device, start, _width, trace, point, *_ = _clickable(
        bars, [b for b in drawn if b[7] != "bars"])
    element = browser.execute_script(
        "return document.querySelectorAll('#timeline .barlayer .trace')[arguments[0]]"
        ".querySelectorAll('.point')[arguments[1]];", trace, point)
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", element)
    ActionChains(browser).move_to_element(element).click().perform()
    details = browser.find_element(By.ID, "details").text
    reason = next(r["reason"] for r in rows if r["kind"] == "start" and r["ab"] == ab)
    assert f"AB {ab}:" in details and reason in details, details
    assert browser.execute_script("return window.primaShow.time()") == pytest.approx(start)

    # and clicking a trace line shows its own
    line = next(i for i, r in enumerate(r for r in rows if r["kind"] != "pose")
                if r.get("reason") and r["kind"] in ("hold", "suspend", "cancel", "start")
                and i > 3)
    table_rows = [r for r in rows if r["kind"] != "pose"]
    tr = browser.find_element(By.CSS_SELECTOR, f'#trace tr[data-i="{line}"]')
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", tr)
    tr.click()
    assert table_rows[line]["reason"] in browser.find_element(By.ID, "details").text
    assert _errors(browser) == []


def test_screenshot_of_sample_03_is_in_the_docs() -> None:
    shot = ROOT / "docs" / "show-sample-03.png"
    assert shot.is_file() and shot.stat().st_size > 10_000
    assert "show-sample-03.png" in (ROOT / "docs" / "show.md").read_text()




def test_only_the_show_command_imports_the_viewer() -> None:
    """The viewer stays apart from the core: ``prima show``'s handler imports it, lazily;
    so does the other viewer, ``prima live``'s page, which draws with it."""
    import ast

    importers = []
    for path in sorted((ROOT / "prima").rglob("*.py")):
        if "show" in path.relative_to(ROOT / "prima").parts[:1]:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n == "prima.show" or n.startswith(("prima.show.", "plotly")) for n in names):
                importers.append((path.relative_to(ROOT / "prima").parts[0],
                                  node.col_offset > 0))
    assert set(importers) == {("cli", True), ("live", True)}
