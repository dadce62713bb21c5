"""Golden-trace testing: prima test and the prima_golden pytest fixture."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from prima.cli import main
from prima.golden import check, golden_path

ROOT = Path(__file__).parents[1]
pytest_plugins = ["pytester"]


def scenario(tmp_path: Path, message_at: int = 25) -> Path:
    text = (ROOT / "scenarios/examples/office-kidode.xml").read_text()
    text = text.replace("../../apps", str(ROOT / "apps"))
    text = text.replace("../maps", str(ROOT / "scenarios/maps"))
    text = text.replace('until="240"', 'until="40"').replace('at="25"', f'at="{message_at}"')
    path = tmp_path / "office.xml"
    path.write_text(text)
    return path


def test_check_is_missing_then_updated_then_same_then_different(tmp_path: Path) -> None:
    path = scenario(tmp_path)
    assert check(path).status == "missing" and not golden_path(path).exists()
    assert check(path, update=True).status == "updated"
    assert check(path).status == "same"
    scenario(tmp_path, message_at=27)
    result = check(path)
    assert result.status == "different"
    assert "\n-" in result.diff and "27.00" in result.diff and "25.00" in result.diff


def test_prima_test_cli(tmp_path: Path) -> None:
    path = scenario(tmp_path)

    def cli(*argv: str) -> tuple[int, str]:
        out, err = io.StringIO(), io.StringIO()
        return main(["test", *argv], out=out, err=err), out.getvalue()

    assert cli(str(tmp_path))[0] == 2  # a folder with no golden trace yet
    assert cli("--update", str(path)) == (0, f"updated   {path}\n")
    assert cli(str(tmp_path)) == (0, f"same      {path}\n")
    scenario(tmp_path, message_at=27)
    code, out = cli(str(tmp_path))
    assert code == 1 and out.startswith(f"different {path}\n---")


def test_a_golden_trace_that_is_a_pipe_or_not_text_is_one_located_line(
        tmp_path: Path) -> None:
    import os

    path = scenario(tmp_path)
    golden = golden_path(path)

    def cli(*argv: str) -> tuple[int, str, str]:
        out, err = io.StringIO(), io.StringIO()
        return main(["test", *argv], out=out, err=err), out.getvalue(), err.getvalue()

    golden.write_bytes(b"  No.\n \xff\xfe\n")
    assert cli(str(path)) == (1, "", f"{golden}:2:2: error: the golden trace is not UTF-8 "
                                     "text\n1 scenario(s): 1 failed\n")
    golden.unlink()
    golden.mkdir()
    assert cli(str(path))[2].startswith(f"{golden}:1:1: error: the golden trace is a folder")
    golden.rmdir()
    os.mkfifo(golden)  # (opened, it would wait for a writer: the test would hang)
    assert cli(str(path))[2].startswith(f"{golden}:1:1: error: the golden trace is not a "
                                        "regular file: PRIMA reads only regular files")
    golden.unlink()
    golden.write_bytes(b"\xff")
    assert cli("--update", str(path))[:2] == (0, f"updated   {path}\n")  # rewritten
    assert cli(str(path))[:2] == (0, f"same      {path}\n")


def test_a_long_golden_trace_is_never_held_whole_to_be_compared(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The run's own trace is in memory; of its golden trace, a piece at a time (a golden
    trace of 300 MB took 1.2 GB)."""
    import tracemalloc

    path = scenario(tmp_path)
    check(path, update=True)
    golden = golden_path(path)
    long = golden.read_text() * (32_000_000 // golden.stat().st_size)
    golden.write_text(long)

    def traced(*_args: object) -> str:  # (what is counted: from the run's trace on)
        tracemalloc.start()
        return long

    monkeypatch.setattr("prima.golden.format_text", traced)
    try:
        assert check(path).status == "same"
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < len(long) // 4, f"{peak:,} bytes for a golden trace of {len(long):,}"


def test_pytest_fixture(pytester: pytest.Pytester, tmp_path: Path) -> None:
    path = scenario(tmp_path)
    pytester.makepyfile(f"""
        def test_office(prima_golden):
            prima_golden({str(path)!r})
    """)
    pytester.runpytest().assert_outcomes(failed=1)  # no golden yet
    pytester.runpytest("--prima-update-goldens").assert_outcomes(passed=1)
    pytester.runpytest().assert_outcomes(passed=1)
    scenario(tmp_path, message_at=27)
    result = pytester.runpytest()
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*differs from its golden trace*",
                                 "*then pytest --prima-update-goldens*"])


def test_the_fixtures_fail_a_bad_input_with_its_message_not_a_traceback(
        pytester: pytest.Pytester, tmp_path: Path) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_text('<scenario xmlns="urn:prima:scenario:1" name="x" until="10">\n'
                   '  <map href="nowhere.xml"/>\n  <robot x="0" y="0"/>\n</scenario>\n')
    pytester.makepyfile(f"""
        def test_golden(prima_golden):
            prima_golden({str(tmp_path / "missing.xml")!r})

        def test_judged(prima_judge):
            prima_judge({str(bad)!r})

        def test_misspelt(prima_judge):
            prima_judge({str(bad)!r}, max_unfacd=1)
    """)
    result = pytester.runpytest()
    result.assert_outcomes(failed=3)
    result.stdout.fnmatch_lines([f"*{bad}:2:*map file 'nowhere.xml' not found*",
                                 "*prima_judge: no threshold 'max_unfacd'*"])
    assert "Traceback" not in result.stdout.str() and "prima/xmlio.py" not in result.stdout.str()


def test_the_fixtures_fail_bad_values_and_forged_traces_with_a_message(
        pytester: pytest.Pytester, tmp_path: Path) -> None:
    forged = tmp_path / "forged.jsonl"
    forged.write_text('{"t": 0, "seq": 0, "kind": "start", "detail": {"command_id": "x"}}\n')
    sample = Path(__file__).parents[1] / "scenarios" / "thesis" / "sample-03.xml"
    pytester.makepyfile(f"""
        def test_threshold_value(prima_judge):
            prima_judge({str(sample)!r}, max_late=-1)

        def test_threshold_type(prima_judge):
            prima_judge({str(sample)!r}, silence="long")

        def test_forged(prima_judge):
            prima_judge({str(forged)!r})

        def test_folder(prima_golden):
            prima_golden({str(tmp_path)!r})
    """)
    result = pytester.runpytest()
    result.assert_outcomes(failed=4)
    out = result.stdout.str()
    assert "Traceback" not in out and "prima/judge.py" not in out, out
    result.stdout.fnmatch_lines([f"*prima_judge('{sample}'): *max_late*",
                                 f"*{forged}:1:1: error: detail 'command_id' has the wrong type*"])


def _talker(folder: Path, words: str, fault: bool = False) -> Path:
    """A scenario whose EA says ``words``, then three more things (each later as the
    first takes longer), and, with ``fault``, divides by zero at run time."""
    (folder / "map.xml").write_text('<map xmlns="urn:prima:map:1" name="m">'
                                    '<place name="a" x="0" y="0"/></map>\n')
    more = "".join(f'<speak text="and then {k}"/>' for k in range(3))
    crash = '<assign name="x" expr="1 / 0"/>' if fault else ""
    (folder / "ea.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t"><var name="x" expr="0"/>'
        f'<state id="s" initial="true"><entry><request><speak text="{words}"/>{more}'
        f"</request>{crash}</entry></state></pxml>\n")
    path = folder / "talk.xml"
    path.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="30">'
                    '<map href="map.xml"/><apps ea="ea.pxml"/><robot place="a"/></scenario>\n')
    return path


def test_a_longer_utterance_is_one_change_and_one_shift_in_the_diff(tmp_path: Path) -> None:
    path = _talker(tmp_path, "Hello.")
    check(path, update=True)
    _talker(tmp_path, "Hello, and welcome to the museum of many things.")
    diff = check(path).diff
    changed = [x for x in diff.splitlines() if x.startswith(("-", "+"))
               and not x.startswith(("---", "+++"))]
    assert len(changed) == 4, diff  # the utterance, and the first of the rows it delays
    assert "every time" in diff and "s later, otherwise the same" in diff


def test_a_golden_pinning_a_runtime_error_names_no_absolute_path(tmp_path: Path) -> None:
    path = _talker(tmp_path, "Hello.", fault=True)
    check(path, update=True)
    golden = golden_path(path).read_text()
    assert "ERROR: ea.pxml:" in golden and str(tmp_path) not in golden, golden


def test_a_golden_made_in_a_folder_with_spaces_names_no_absolute_path(tmp_path: Path) -> None:
    """Error lines name the document relative to the scenario's folder from the start (a
    path with a space slipped past the rewriting of absolute paths)."""
    folder = tmp_path / "my apps"
    folder.mkdir()
    path = _talker(folder, "Hello.", fault=True)
    check(path, update=True)
    golden = golden_path(path).read_text()
    assert "ERROR: ea.pxml:" in golden and str(tmp_path) not in golden, golden
