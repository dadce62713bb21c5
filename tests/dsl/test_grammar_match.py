"""Answer grammars: choices with synonyms and patterns."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import pytest

from prima.dsl import Grammar, load_document

DOC = b"""<pxml xmlns="urn:prima:pxml:1" kind="fa" name="g">
  <grammar id="rooms">
    <choice value="kidode_room">Prof. Kidode's room | Kidode</choice>
    <choice>hall | the hall</choice>
  </grammar>
  <grammar id="reply"><choice value="no">no | nothing</choice><pattern>yes *</pattern></grammar>
  <grammar id="hour"><pattern>#</pattern><pattern>at # o'clock</pattern></grammar>
  <state id="s" initial="true"/>
</pxml>"""


@pytest.fixture(scope="module")
def grammars(tmp_path_factory: pytest.TempPathFactory) -> Mapping[str, Grammar]:
    path: Path = tmp_path_factory.mktemp("g") / "g.pxml"
    path.write_bytes(DOC)
    return load_document(path).grammars


@pytest.mark.parametrize("grammar, heard, value", [
    ("rooms", "Prof. Kidode's room.", "kidode_room"),
    ("rooms", "I'm going to KIDODE, please", "kidode_room"),
    ("rooms", "The hall", "hall"),
    ("rooms", "the kitchen", None),
    ("rooms", "Kidodes", None),
    ("reply", "No.", "no"),
    ("reply", "Yes. I see. I'll wait in your room.", "i see ill wait in your room"),
    ("rooms", "Kidode's office", "kidode_room"),
    ("reply", "yes", "yes"),
    ("reply", "maybe", None),
    ("hour", "18", "18"),
    ("hour", "at 7 o'clock", "7"),
    ("hour", "at 7 oclock", "7"),
    ("hour", "eighteen", None),
])
def test_match(grammars: Mapping[str, Grammar], grammar: str, heard: str,
               value: str | None) -> None:
    assert grammars[grammar].match(heard) == value
