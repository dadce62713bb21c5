"""The JSON Schema of the jsonl trace (``schemas/trace.schema.json``): every shipped
scenario's trace validates, and a record it does not know fails."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from prima.run import Run

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = json.loads((ROOT / "schemas" / "trace.schema.json").read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)
SHIPPED = sorted(p for p in (ROOT / "scenarios").rglob("*.xml")
                 if "maps" not in p.parts and p.parent.name != "all-off")


def test_the_schema_is_a_valid_json_schema() -> None:
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


@pytest.mark.parametrize("scenario", SHIPPED, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_every_shipped_trace_validates(scenario: Path) -> None:
    for line in Run(scenario).run():
        row = json.loads(json.dumps(line.to_dict()))
        errors = sorted(VALIDATOR.iter_errors(row), key=str)
        assert not errors, f"seq {row['seq']}: {errors[0].message}"


GOOD: dict[str, Any] = {"t": 1.5, "seq": 7, "kind": "start", "app": "fa", "ab": 3, "tree": 0,
                        "command": "Speak", "text": "Hello.", "devices": ["speaker"],
                        "reason": "free-devices", "detail": {"command_id": 4}}


@pytest.mark.parametrize("change", [
    {"kind": "teleport"},                        # a kind it does not know
    {"colour": "red"},                           # a field it does not know
    {"detail": {"command_id": 4, "mood": 1}},    # a detail it does not know
    {"ab": "three"},                             # a field of the wrong type
    {"t": -1},                                   # time goes from 0
])
def test_a_record_the_schema_does_not_know_fails(change: dict[str, Any]) -> None:
    assert VALIDATOR.is_valid(GOOD)
    assert not VALIDATOR.is_valid({**GOOD, **change})
    without_app = {k: v for k, v in GOOD.items() if k != "app"}
    assert not VALIDATOR.is_valid(without_app)   # a start names its application
