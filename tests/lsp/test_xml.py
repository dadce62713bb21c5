"""The forgiving scan of a buffer, taken over from one version to the next: always the
scan of the new text, tag for tag, whatever the edit."""

from __future__ import annotations

import random
from pathlib import Path

from prima.lsp._xml import XmlText, rescan, scan

ROOT = Path(__file__).resolve().parents[2]
TYPED = ["a", " ", "x1", '"', "'", "<", ">", "/>", "\n", "=", "&amp;", "\u00e9", "", "",
         "</a>", "<b c='d'>", "-->", "<!--", "]]>"]


def _tags(x: XmlText) -> object:
    index = {id(t): i for i, t in enumerate(x.tags)}
    return ([(t.name, t.start, t.end, t.closed, t.empty, t.content_end, t.raw_name,
              index.get(id(t.parent)), [index[id(c)] for c in t.children],
              [(a.name, a.name_start, a.value_start, a.value_end, a.raw) for a in t.attrs])
             for t in x.tags], x.ends, x.others, x.source)


def test_a_scan_taken_over_is_the_scan_of_the_new_text() -> None:
    rng = random.Random(7)
    files = [*sorted((ROOT / "apps").rglob("*.pxml")), ROOT / "scenarios" / "maps" / "office.xml",
             ROOT / "robots" / "guide-robot.xml"]
    taken = 0
    for path in files:
        text = path.read_text(encoding="utf-8")
        current = scan(text)
        for step in range(120):
            if step % 3 == 0:  # some tags' attributes read, as requests read them
                for tag in current.tags[step % 5::4]:
                    tag.attrs  # noqa: B018
            at = rng.randrange(len(text) + 1)
            cut = min(len(text), at + rng.choice([0, 0, 0, 1, 2, 5]))
            new = text[:at] + rng.choice(TYPED) + text[cut:]
            after = rescan(current, new)
            taken += after is current
            assert _tags(after) == _tags(scan(new)), (path.name, step, new[at - 30:at + 30])
            current, text = after, new
    assert taken > 200  # most typing is taken over, not scanned again


def test_typing_in_a_value_or_a_text_is_taken_over() -> None:
    text = '<pxml a="1"><state id="s"><chain>Speak("hi")</chain></state></pxml>'
    first = scan(text)
    typed = text.replace('id="s"', 'id="st"')
    assert rescan(first, typed) is first and first.tags[1].get("id") == "st"
    again = typed.replace('Speak("hi")', 'Speak("hi there")')
    assert rescan(first, again) is first
    assert first.tags[2].text(again) == (first.tags[2].end, 'Speak("hi there")')
    assert rescan(first, again.replace("<chain>", "<chain x>")) is not first  # markup
