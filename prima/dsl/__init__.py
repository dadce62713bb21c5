"""PXML documents and robot profiles: secure loading, schemas, meaning checks.

This is the package's public API; its modules (``prima.dsl._loader`` and so
on) are private. In the direction data flows:

- loading: :func:`load_document`, :func:`check_document`, :func:`check_parsed`
  turn PXML bytes into a :class:`Document` or located problems;
- robot profiles: :func:`load_profile`, :func:`parse_profile`,
  :func:`profile_from_xml`, :func:`default_profile` give a :class:`RobotProfile`;
- validation of files and folders, as ``prima validate`` does it:
  :func:`collect`, :func:`check_file`, :func:`validate_paths` and
  :class:`Validation` (each file once) give a :class:`Report`;
- the model the interpreter runs (:class:`Document`, :class:`State`,
  :class:`Handler`, the actions, :class:`CommandCall`, :class:`Grammar`, with
  :func:`words` and :func:`match_pattern` for its answers, and
  :func:`literal_places`: the places it names, as :class:`PlaceRef`, which
  :func:`unknown_places` checks against a map's place names);
- the expression language: :func:`compile_expression`, :func:`compile_template`,
  :func:`parse_chain` give :class:`Compiled` closures run over a :class:`Scope`;
  its lark :func:`parser` is loaded from tables prebuilt from ``pxml.lark``
  (:func:`prebuilt_parser`; :func:`build_parser` builds it from the grammar);
  :func:`fast_parse` builds the tree lark would of a valid text, as a
  :class:`ParseTree` of :class:`ParseToken`, without importing lark, or
  declines (and lark parses it, wording any fault);
- the schema: :func:`command_elements` is the common Commands' part of
  ``schemas/pxml.xsd``, generated from the catalog, and :func:`schema_source`
  the schema's text with that part made anew (``python -m prima.dsl._build_schema``).
"""

from prima.dsl._build_schema import command_elements, schema_source
from prima.dsl._commands import element_name
from prima.dsl._expr import (
    CLOCK_FUNCTIONS,
    FUNCTIONS,
    ChainArg,
    ChainStep,
    Compiled,
    Scope,
    compile_expression,
    compile_template,
    parse_chain,
    to_text,
    truthy,
)
from prima.dsl._fastparse import parse as fast_parse
from prima.dsl._grammar import build as build_parser
from prima.dsl._grammar import parser
from prima.dsl._grammar import prebuilt as prebuilt_parser
from prima.dsl._syntax import Token as ParseToken
from prima.dsl._syntax import Tree as ParseTree
from prima.dsl._kept import Kept, keeping
from prima.dsl._loader import (
    NAMESPACE,
    check_document,
    check_parsed,
    load_document,
    structure_problems,
)
from prima.dsl._model import (
    Action,
    Assign,
    AtomicBlock,
    CancelTimer,
    Choice,
    CommandCall,
    Document,
    EventDecl,
    Goto,
    Grammar,
    Handler,
    HandlerKind,
    If,
    Loc,
    Log,
    Pattern,
    PlaceRef,
    Raise,
    Request,
    Send,
    StartTimer,
    State,
    StreamBlock,
    Variable,
    literal_places,
    match_pattern,
    words,
)
from prima.dsl._profile import NAMESPACE as ROBOT_NAMESPACE
from prima.dsl._profile import (
    STANDARD_GESTURES,
    RobotProfile,
    default_profile,
    load_profile,
    parse_profile,
    profile_from_xml,
)
from prima.dsl._validate import (
    Checker,
    Header,
    PathNotFoundError,
    Report,
    Validation,
    check_file,
    collect,
    root_namespace,
    unknown_places,
    validate_paths,
)

__all__ = [
    "CLOCK_FUNCTIONS",
    "FUNCTIONS",
    "NAMESPACE",
    "ROBOT_NAMESPACE",
    "STANDARD_GESTURES",
    "Action",
    "Assign",
    "AtomicBlock",
    "CancelTimer",
    "ChainArg",
    "ChainStep",
    "Checker",
    "Choice",
    "CommandCall",
    "Compiled",
    "Document",
    "Kept",
    "EventDecl",
    "Goto",
    "Grammar",
    "Handler",
    "HandlerKind",
    "Header",
    "If",
    "Loc",
    "Log",
    "ParseToken",
    "ParseTree",
    "PathNotFoundError",
    "Pattern",
    "PlaceRef",
    "Raise",
    "Report",
    "Request",
    "RobotProfile",
    "Scope",
    "Send",
    "StartTimer",
    "State",
    "StreamBlock",
    "Validation",
    "Variable",
    "check_document",
    "check_file",
    "build_parser",
    "check_parsed",
    "collect",
    "command_elements",
    "compile_expression",
    "compile_template",
    "default_profile",
    "element_name",
    "fast_parse",
    "keeping",
    "load_document",
    "literal_places",
    "unknown_places",
    "load_profile",
    "match_pattern",
    "parse_chain",
    "parse_profile",
    "parser",
    "prebuilt_parser",
    "profile_from_xml",
    "root_namespace",
    "schema_source",
    "structure_problems",
    "to_text",
    "truthy",
    "validate_paths",
    "words",
]
