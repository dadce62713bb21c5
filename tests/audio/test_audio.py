"""A run you can hear: the utterances of a trace, synthesised by espeak-ng to last as
long as the run says them, and ``prima show --audio``'s page playing them in Chromium."""

from __future__ import annotations

import io
import wave
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from prima.audio import OUTPUT_RATE, available, clip, utterances, wav
from prima.cli import main
from prima.dsl import default_profile
from prima.run import Run, spec_from_profile
from tests.browser import STEPPED_CLOCK, headless_chromium, until

if available() is not None:
    pytest.skip(f"{available()} (.ci/run installs it)", allow_module_level=True)

ROOT = Path(__file__).parents[2]
SAMPLE_10 = ROOT / "scenarios" / "thesis" / "sample-10.xml"
INTERRUPT = ROOT / "scenarios" / "policies" / "interrupt-on.xml"
MODEL = spec_from_profile(default_profile()).speech_duration


def _rows(scenario: Path) -> list[dict[str, Any]]:
    return [line.to_dict() for line in Run(scenario).run()]


def test_the_utterances_are_when_the_words_are_said() -> None:
    rows = _rows(INTERRUPT)
    said = utterances(rows, MODEL)
    ends = {r["ab"]: r for r in rows if r["kind"] == "end"}
    starts = {r["ab"]: r for r in rows if r["kind"] == "start"}
    # a Speak: the whole atomic behavior; a Q&A: its prompt, then it listens
    speak = next(u for u in said if u.command == "Speak")
    assert (speak.start, speak.end) == (starts[speak.ab]["t"], ends[speak.ab]["t"])
    qa = next(u for u in said if u.command == "QA")
    assert qa.start == starts[qa.ab]["t"] and qa.duration == MODEL(qa.text) < \
        ends[qa.ab]["t"] - qa.start
    # a FaceHumanAndSpeak turns first: its words end with it
    face = next(u for u in said if u.command == "FaceHumanAndSpeak" and not u.cut)
    assert face.end == ends[face.ab]["t"] and face.duration == MODEL(face.text)
    # the cut one: the words said before the cut, ending at the cut
    [cut] = [u for u in said if u.cut]
    assert cut.text == "This panel shows" == ends[cut.ab]["detail"]["spoken"]
    assert cut.whole == "This panel shows research points of our laboratory."
    assert cut.end == ends[cut.ab]["t"]
    assert cut.duration == pytest.approx(MODEL(cut.whole) * 3 / 8, abs=0.03)


def test_an_utterance_the_user_spoke_over_is_its_spoken_words_at_their_pace() -> None:
    """Barge-in cuts too (reason ``barge-in``): the sound is the words spoken, at the pace
    the speech model says them, ending at the cut (it was the whole utterance squeezed
    into the time before the cut)."""
    rows = _rows(ROOT / "scenarios" / "examples" / "barge-in-question.xml")
    [end] = [r for r in rows if r["kind"] == "end" and r.get("reason") == "barge-in"]
    spoken, whole = end["detail"]["spoken"], end["text"]
    [cut] = [u for u in utterances(rows, MODEL) if u.ab == end["ab"]]
    assert cut.cut and cut.text == spoken and cut.whole == whole and cut.end == end["t"]
    k, n = len(spoken.split()), len(whole.split())
    assert cut.duration == pytest.approx(MODEL(whole) * k / n, abs=0.03)
    assert cut.start == pytest.approx(end["detail"]["words_start"], abs=0.03)
    assert len(clip(cut).samples) == round(cut.duration * OUTPUT_RATE)


def test_what_is_synthesised_is_bounded() -> None:
    """A forged utterance of 99,999 s, or of 100,000 words, makes a clip of at most
    MAX_SECONDS saying at most MAX_WORDS words, marked shortened."""
    from prima.audio import MAX_SECONDS, MAX_WORDS, Utterance

    long = Utterance(1, "a", "Speak", 0.0, 99_999.0, "hi there", "hi there")
    made = clip(long)
    assert made.shortened and made.duration == pytest.approx(MAX_SECONDS)
    many = " ".join(["word"] * 100_000)
    wordy = Utterance(1, "a", "Speak", 0.0, 40_000.0, many, many)
    made = clip(wordy)
    assert made.shortened and made.duration == pytest.approx(MAX_SECONDS)
    assert len(made.words) <= MAX_WORDS


def test_a_clip_lasts_exactly_its_utterance_and_is_the_same_every_time() -> None:
    said = utterances(_rows(INTERRUPT), MODEL)
    for u in said[:4] + [u for u in said if u.cut]:
        made = clip(u)
        assert len(made.samples) == round(u.duration * OUTPUT_RATE), u
        assert max(abs(s) for s in made.samples) > 1000  # words, not silence
        assert made.samples == clip(u).samples
        with wave.open(io.BytesIO(wav(made.samples))) as read:
            assert (read.getnchannels(), read.getsampwidth(), read.getframerate()) == \
                (1, 2, OUTPUT_RATE)
            assert read.getnframes() == len(made.samples)


# ------------------------------------------------------------ the page in a browser

@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    yield from headless_chromium("--disable-background-networking",
                                 "--autoplay-policy=no-user-gesture-required")


def _sounds(browser: Any, page: Path) -> list[dict[str, Any]]:
    """Open the page from file://; its sounds, once every one has loaded its metadata."""
    browser.get(page.as_uri())
    until(browser, "return !!window.primaShow && window.primaShow.sounds().length && "
                   "window.primaShow.sounds().every(function (s) { "
                   "return s.ready >= 1 || s.error; })")
    browser.execute_script(STEPPED_CLOCK)
    sounds: list[dict[str, Any]] = browser.execute_script("return window.primaShow.sounds()")
    return sounds


@pytest.mark.parametrize("scenario", [SAMPLE_10, INTERRUPT], ids=lambda p: p.stem)
def test_the_page_plays_each_utterance_offline_as_long_as_it_is_said(
        browser: Any, scenario: Path, tmp_path: Path) -> None:
    page = tmp_path / f"{scenario.stem}.html"
    err = io.StringIO()
    assert main(["show", str(scenario), "--audio", "-o", str(page)], err=err) == 0, err.getvalue()
    said = utterances(_rows(scenario), MODEL)
    sounds = _sounds(browser, page)
    assert len(sounds) == len(said) > 10
    for sound, u in zip(sounds, said, strict=True):
        assert sound["error"] == 0 and sound["ready"] >= 1  # loaded, from the page itself
        assert (sound["start"], sound["end"]) == pytest.approx((u.start, u.end))
        assert sound["duration"] == pytest.approx(u.duration, abs=1e-3)
        assert sound["expected"] == pytest.approx(u.duration, abs=1e-4)
    # played with the playhead: inside an utterance, its sound plays from there (one frame
    # of the page's clock, stepped by the test: the playhead then stays where it is while
    # the sound plays on, as long as the machine takes to get it past 0.4 s)
    u = said[len(said) // 2]
    index = said.index(u)
    browser.execute_script(f"window.primaShow.seek({u.start + 0.3}); window.primaShow.play();"
                           "window.stepClock(0);")
    until(browser, "const s = window.primaShow.sounds()[arguments[0]]; "
                   "return !s.paused && s.at > 0.4;", index)
    playing = browser.execute_script("return window.primaShow.sounds()")
    assert not playing[index]["paused"] and playing[index]["at"] > 0.4
    assert all(s["paused"] for i, s in enumerate(playing) if i != index)
    state = browser.execute_script("window.primaShow.pause(); return window.primaShow.sounds()")
    assert all(s["paused"] for s in state)  # paused with the playhead
    errors = [e["message"] for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == []


def test_audio_needs_espeak_ng(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Without the library, a usage error that says how to install it, before anything runs."""
    import prima.audio

    monkeypatch.setattr(prima.audio, "available", lambda: "espeak-ng is not installed")
    err = io.StringIO()
    page = tmp_path / "x.html"
    assert main(["show", str(SAMPLE_10), "--audio", "-o", str(page)], err=err) == 2
    assert "espeak-ng is not installed" in err.getvalue() and not page.exists()


def test_speech_timed_by_the_synthesiser_cuts_where_the_voice_ends_a_word() -> None:
    """``--speech-timing tts``: a run's utterances take as long as espeak-ng's voice
    takes, and the interrupt policy cuts one where the voice ends the word under way;
    the page's sound is then the voice itself, up to the cut."""
    from prima.audio import SynthesisedTiming
    from prima.show._sound import clips

    timing = SynthesisedTiming(2.5)
    rows = [line.to_dict() for line in Run(INTERRUPT, speech=timing).run()]
    tick = 1 / 50
    speak = next(r for r in rows if r["kind"] == "end" and r["command"] == "Speak")
    start = next(r for r in rows if r["kind"] == "start" and r["ab"] == speak["ab"])
    said = float(speak["detail"]["result"].split("duration=")[1].split(",")[0])
    assert said == pytest.approx(timing.said(start["text"])[0], abs=tick)
    assert said != pytest.approx(MODEL(start["text"]), abs=tick)  # not the 2.5 words/s model
    [cut] = [r for r in rows if r["kind"] == "end" and r.get("reason") == "interrupt"]
    whole = cut["text"]
    k = len(cut["detail"]["spoken"].split())
    assert cut["detail"]["spoken"] == " ".join(whole.split()[:k])
    [made] = [c for c in clips(rows, INTERRUPT, timing) if c.utterance.cut]
    assert made.utterance.duration == pytest.approx(timing.said(whole)[1][k - 1], abs=tick)
    voice = timing.speech(whole).samples
    halved = [(a + b) // 2 for a, b in zip(voice[0:40:2], voice[1:40:2], strict=True)]
    assert list(made.samples[:20]) == halved  # the voice itself, from its start


def test_tts_timing_runs_a_scenario(tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    assert main(["run", str(SAMPLE_10), "--format", "jsonl", "--out", str(trace)]) == 0
    err = io.StringIO()
    assert main(["show", str(trace), "--speech-timing", "tts", "-o",
                 str(tmp_path / "x.html")], err=err) == 2
    assert "--speech-timing tts times a run: give a scenario, not a trace" in err.getvalue()
