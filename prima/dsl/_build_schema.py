"""The common Commands' elements of ``schemas/pxml.xsd``, generated from the Command catalog.

The catalog (:mod:`prima.catalog`) is the one place a Command's arguments and
its documentation are written. The element form of each common Command (its
element, its attributes, their types and whether they are required) and the
schema's documentation of them (``CommandSpec.describe``, ``Param.describe``)
are generated from it, between two marker comments of the schema; editors show
that documentation from the schema, and ``prima lsp`` shows the same text on
hover. A developer's step, after editing the catalog
(``tests/dsl/test_schema_docs.py`` fails until it is done)::

    python -m prima.dsl._build_schema
"""

from __future__ import annotations

import sys
from collections.abc import Iterable

from prima.catalog import STANDARD_COMMANDS, CommandSpec, Param, ParamKind
from prima.dsl._commands import element_name
from prima.shipped import packaged

__all__ = ["BEGIN", "END", "command_elements", "schema_source"]

BEGIN = ("<!-- generated from prima/catalog.py by python -m prima.dsl._build_schema: "
         "edit the catalog, not this -->")
END = "<!-- end of the generated Commands -->"

_TYPES = {
    ParamKind.TEXT: "xs:string",
    ParamKind.NUMBER: "p:NumberArg",
    ParamKind.PLACE: "p:SymbolArg",
    ParamKind.GESTURE: "p:SymbolArg",
    ParamKind.SYMBOL: "p:SymbolArg",
    ParamKind.GRAMMAR: "p:Name",
    ParamKind.VARIABLE: "p:VarName",
}
"""The schema type of an attribute, by its parameter's kind."""

_INDENT = "      "


def _escape(text: str) -> str:
    """``text`` as XML character data (``&``, ``<`` and ``>`` escaped)."""
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _doc(text: str, indent: str) -> str:
    return (f"{indent}<xs:annotation><xs:documentation>{_escape(text)}"
            "</xs:documentation></xs:annotation>\n")


def _attribute(param: Param) -> str:
    use = ' use="required"' if param.required else ""
    at = _INDENT + "    "
    return (f'{at}<xs:attribute name="{param.name}" type="{_TYPES[param.kind]}"{use}>\n'
            + _doc(param.describe(), at + "  ") + f"{at}</xs:attribute>\n")


def _element(spec: CommandSpec) -> str:
    name = element_name(spec.name)
    doc = _doc(spec.describe(), _INDENT + "  ")
    if not spec.params:
        return (f'{_INDENT}<xs:element name="{name}" type="p:CommandBase">\n{doc}'
                f"{_INDENT}</xs:element>\n")
    return (f'{_INDENT}<xs:element name="{name}">\n{doc}'
            f'{_INDENT}  <xs:complexType><xs:complexContent><xs:extension base="p:CommandBase">\n'
            + "".join(_attribute(p) for p in spec.params)
            + f"{_INDENT}  </xs:extension></xs:complexContent></xs:complexType>\n"
            f"{_INDENT}</xs:element>\n")


def command_elements(commands: Iterable[CommandSpec] = STANDARD_COMMANDS) -> str:
    """The schema text of the common Commands' elements, between the markers."""
    return (f"{_INDENT}{BEGIN}\n" + "".join(_element(c) for c in commands)
            + f"{_INDENT}{END}\n")


def schema_source(current: str) -> str:
    """``current`` (the text of ``pxml.xsd``) with its generated part made anew."""
    start = current.index(f"{_INDENT}{BEGIN}\n")
    end = current.index(f"{_INDENT}{END}\n") + len(f"{_INDENT}{END}\n")
    return current[:start] + command_elements() + current[end:]


def main() -> None:
    target = packaged("prima.schemas", "pxml.xsd")
    target.write_text(schema_source(target.read_text(encoding="utf-8")), encoding="utf-8")
    print(f"wrote {target}", file=sys.stderr)


if __name__ == "__main__":
    main()
