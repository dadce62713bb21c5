"""The schemas document every element and attribute, and the common Commands' part of
``pxml.xsd`` is the one generated from the catalog: run ``python -m prima.dsl._build_schema``
after editing the catalog."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from lxml import etree

from prima.catalog import STANDARD_COMMANDS
from prima.dsl import command_elements, schema_source

SCHEMAS = Path(__file__).resolve().parents[2] / "schemas"
XS = "{http://www.w3.org/2001/XMLSchema}"
REBUILD = "the catalog changed: rebuild pxml.xsd with python -m prima.dsl._build_schema"


def test_the_command_elements_are_the_catalogs() -> None:
    text = (SCHEMAS / "pxml.xsd").read_text(encoding="utf-8")
    assert schema_source(text) == text, REBUILD
    assert text.count("<!-- generated from prima/catalog.py") == 1


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


ROOT = SCHEMAS.parent
SCHEMA_OF = {"urn:prima:pxml:1": "pxml.xsd", "urn:prima:robot:1": "robot.xsd",
             "urn:prima:scenario:1": "scenario.xsd", "urn:prima:map:1": "map.xsd"}
SHIPPED = sorted([*ROOT.glob("apps/*/*.pxml"), *ROOT.glob("robots/*.xml"),
                  *ROOT.glob("scenarios/*/*.xml")])
_MODEL = re.compile(r'<\?xml-model href="([^"]+)" type="application/xml" '
                    r'schematypens="http://www\.w3\.org/2001/XMLSchema"\?>')


def test_every_shipped_document_binds_its_schema_on_its_first_line() -> None:
    """An editor that reads ``xml-model`` (VS Code's XML extension, oXygen) finds the
    schema; on the declaration's line, so no line number of a document moved."""
    assert len(SHIPPED) >= 47
    for path in SHIPPED:
        first = path.read_text(encoding="utf-8").split("\n", 1)[0]
        assert first.startswith('<?xml version="1.0" encoding="UTF-8"?>'), path
        found = _MODEL.search(first)
        assert found, f"{path}: no xml-model instruction on line 1"
        schema = (path.parent / found.group(1)).resolve()
        namespace = etree.QName(etree.parse(str(path)).getroot()).namespace
        assert schema == (SCHEMAS / SCHEMA_OF[str(namespace)]).resolve(), path
        assert etree.XMLSchema(etree.parse(str(schema))).validate(etree.parse(str(path))), path


def test_the_catalog_maps_every_namespace_to_its_schema() -> None:
    catalog = etree.parse(str(SCHEMAS / "catalog.xml")).getroot()
    uris = {el.get("name"): el.get("uri")
            for el in catalog.iter("{urn:oasis:names:tc:entity:xmlns:xml:catalog}uri")}
    assert uris == SCHEMA_OF
    assert all((SCHEMAS / schema).is_file() for schema in uris.values())
