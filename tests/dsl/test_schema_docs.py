"""The schemas document every element and attribute, and the common Commands' part of
``pxml.xsd`` is the one generated from the catalog: run ``python -m prima.dsl._build_schema``
after editing the catalog."""

from __future__ import annotations

from pathlib import Path

import pytest
from lxml import etree

from prima.catalog import STANDARD_COMMANDS
from prima.dsl._build_schema import BEGIN, END, command_elements, schema_source

SCHEMAS = Path(__file__).resolve().parents[2] / "schemas"
XS = "{http://www.w3.org/2001/XMLSchema}"
REBUILD = "the catalog changed: rebuild pxml.xsd with python -m prima.dsl._build_schema"


def test_the_command_elements_are_the_catalogs() -> None:
    text = (SCHEMAS / "pxml.xsd").read_text(encoding="utf-8")
    assert schema_source(text) == text, REBUILD
    assert text.count(BEGIN) == text.count(END) == 1


def test_every_common_command_and_argument_is_documented_once_in_the_catalog() -> None:
    generated = command_elements()
    for spec in STANDARD_COMMANDS:
        assert spec.doc, spec.name
        assert spec.describe() in generated.replace("&quot;", '"')
        for param in spec.params:
            assert param.doc, f"{spec.name}({param.name})"


@pytest.mark.parametrize("schema", ["pxml.xsd", "robot.xsd", "scenario.xsd", "map.xsd"])
def test_every_element_and_attribute_is_documented(schema: str) -> None:
    tree = etree.parse(str(SCHEMAS / schema))
    undocumented = [
        f"line {el.sourceline}: {el.get('name')}"
        for el in tree.iter(f"{XS}element", f"{XS}attribute")
        if el.get("name") and not "".join(
            el.xpath("string(xs:annotation/xs:documentation)",
                     namespaces={"xs": XS[1:-1]})).strip()]
    assert not undocumented
