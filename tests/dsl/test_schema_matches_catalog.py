"""The XSD's Command elements and the Command catalog must never drift apart."""

from __future__ import annotations

from pathlib import Path

from lxml import etree

from prima.catalog import STANDARD_COMMANDS
from prima.dsl import element_name

XSD = Path(__file__).parents[2] / "schemas" / "pxml.xsd"
XS = {"xs": "http://www.w3.org/2001/XMLSchema"}


def _command_elements() -> dict[str, set[str]]:
    tree = etree.parse(str(XSD))
    group = tree.find(".//xs:group[@name='command']", XS)
    out = {}
    for el in group.iterfind("xs:choice/xs:element", XS):
        out[el.get("name")] = {a.get("name") for a in el.iterfind(".//xs:attribute", XS)}
    return out


def test_every_common_command_has_an_element_with_its_parameters() -> None:
    elements = _command_elements()
    for spec in STANDARD_COMMANDS:
        name = element_name(spec.name)
        assert name in elements, name
        assert elements[name] == {p.name for p in spec.params}, name  # id comes from CommandBase
    assert set(elements) == {element_name(c.name) for c in STANDARD_COMMANDS} | {"command"}
