"""The red-team corpus: hostile inputs, one table row each, with the verdict each must get.

Every input is written by a stranger. A row says what it attacks, how its
file is made (small ones inline, big ones generated here: nothing of megabyte
size is committed), and the verdict: rejected with the first error at a given
place (a ``(line, col)``, or the first occurrence of a piece of the file's
text) saying a given fragment, or accepted. :mod:`tests.redteam.runner` runs
each under a CPU-time limit (2 s unless the row says otherwise) and a memory limit.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from prima.dsl import load_document
from prima.scenario import load_scenario
from tests.redteam.runner import Accepted, Case, Make, Rejected

ROOT = Path(__file__).resolve().parents[2]
HUGE = "1" + "0" * 400        # a decimal the schemas accept; infinite as a float
TINY = "0." + "0" * 400 + "1"  # more than 0 as a decimal; 0 as a float


# ---------------------------------------------------------------- how inputs are made

def write(name: str, content: str | bytes, extra: Callable[[Path], object] | None = None) -> Make:
    """A file ``name`` with ``content`` (and whatever ``extra`` adds to the folder)."""
    def make(folder: Path) -> Path:
        if extra is not None:
            extra(folder)
        path = folder / name
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
        return path
    return make


def pxml(body: str, *, kind: str = "ea", prolog: str = "", root: str = "") -> str:
    return (f'{prolog}<pxml xmlns="urn:prima:pxml:1" kind="{kind}" name="t"{root}>\n'
            f"{body}\n</pxml>\n")


def doc(body: str, **kwargs: str) -> Make:
    return write("t.pxml", pxml(body, **kwargs))


STATE = '<state id="s" initial="true"/>'


def entry(actions: str) -> str:
    return f'<state id="s" initial="true"><entry>{actions}</entry></state>'


def var(expr: str) -> Make:
    """A document whose one variable is initialised by ``expr``."""
    return doc(f'<var name="x" expr="{expr}"/>\n{STATE}')


MAP = ('<map xmlns="urn:prima:map:1" name="m">\n'
       '  <place name="a" x="0" y="0"/>\n  <area name="r" x1="0" y1="0" x2="1" y2="1"/>\n'
       '</map>\n')


def scenario(body: str = "", *, attrs: str = 'name="s" until="10"', apps: str = "",
             robot: str = '<robot place="a"/>', href: str = "map.xml",
             extra: Callable[[Path], object] | None = None) -> Make:
    """A scenario on a one-place map (``extra`` adds files it names)."""
    text = (f'<scenario xmlns="urn:prima:scenario:1" {attrs}>\n  <map href="{href}"/>\n'
            f"  {apps}\n  {robot}\n{body}</scenario>\n")

    def files(folder: Path) -> None:
        (folder / "map.xml").write_text(MAP)
        if extra is not None:
            extra(folder)
    return write("s.xml", text, files)


def user(children: str, attrs: str = 'x="0" y="0"') -> Make:
    return scenario(f"  <user {attrs}>{children}</user>\n")


def map_file(body: str) -> Make:
    return write("m.xml", f'<map xmlns="urn:prima:map:1" name="m">\n{body}\n</map>\n')


def robot(old: str, new: str) -> Make:
    """The shipped robot profile with one piece of text replaced."""
    text = (ROOT / "robots" / "home-robot.xml").read_text()
    assert old in text, old
    return write("robot.xml", text.replace(old, new, 1))


def fifo(name: str) -> Callable[[Path], object]:
    return lambda folder: os.mkfifo(folder / name)


def app(name: str, kind: str = "ea", body: str = STATE) -> Callable[[Path], object]:
    return lambda folder: (folder / name).write_text(pxml(body, kind=kind))


def special(target: str, name: str = "t.pxml") -> Make:
    """``name`` as a symbolic link to ``target`` (a device, say)."""
    def make(folder: Path) -> Path:
        path = folder / name
        path.symlink_to(target)
        return path
    return make


def made(make: Callable[[Path], Path]) -> Make:
    return make


def _named_pipe(folder: Path) -> Path:
    os.mkfifo(folder / "app.pxml")
    return folder / "app.pxml"


def _folder_with_a_pipe(folder: Path) -> Path:
    (folder / "apps").mkdir()
    os.mkfifo(folder / "apps" / "a.xml")  # not a .pxml: found in a folder, skipped
    (folder / "apps" / "ok.pxml").write_text(pxml(STATE))
    return folder / "apps"


def _symlink_loop(folder: Path) -> Path:
    (folder / "apps").mkdir()
    (folder / "apps" / "loop").symlink_to(folder / "apps")
    (folder / "apps" / "ok.pxml").write_text(pxml(STATE))
    return folder / "apps"


def _nth(text: str, piece: str, n: int) -> int:
    """Where the ``n``-th occurrence of ``piece`` in ``text`` starts."""
    at = -1
    for _ in range(n):
        at = text.index(piece, at + 1)
    return at


def _nested_templates(levels: int) -> str:
    """``not not not "{...}"`` nested ``levels`` deep, escaped for a string and an attribute."""
    expr = "1"
    for _ in range(levels):
        body = "{" + expr + "}"
        expr = "not not not " + '"' + body.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return expr.replace("&", "&amp;").replace('"', "&quot;")


DEEP_TEMPLATES = _nested_templates(11)


# ---------------------------------------------------------------- work after acceptance

def match_hostile_answer(path: Path) -> None:
    """A pattern of four '*' against a 500-character answer: linear, not backtracking."""
    grammar = load_document(path).grammars["g"]
    assert grammar.match("word " * 100) is None  # the first 500 characters are heard
    assert grammar.match("word " * 90 + "a b c d") == " ".join(["word"] * 90)


def match_many_synonyms(path: Path) -> None:
    grammar = load_document(path).grammars["g"]
    for _ in range(100):
        assert grammar.match("say " * 100 + "w4999 x") == "v"


def search_long_prompt(path: Path) -> None:
    script = load_scenario(path).user
    assert script is not None
    assert not script.answers[0].matches("a" * 10_000)


def no_file_was_written(path: Path) -> None:
    assert not (path.parent / "PWNED").exists()


# ---------------------------------------------------------------- the corpus

XML = [
    Case("xxe-file", "an external entity reading a local file",
         write("t.pxml", '<!DOCTYPE pxml [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
                         + pxml(entry('<log text="&x;"/>'))),
         Rejected("DOCTYPE declarations are not allowed", (1, 1))),
    Case("xxe-network", "an external entity fetched over the network",
         write("t.pxml", '<!DOCTYPE pxml [<!ENTITY x SYSTEM "http://127.0.0.1:9/x">]>\n'
                         + pxml(entry('<log text="&x;"/>'))),
         Rejected("DOCTYPE declarations are not allowed", (1, 1))),
    Case("billion-laughs", "exponential entity expansion",
         write("t.pxml", '<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY l "lol">\n'
                         + "".join(f' <!ENTITY l{i} "{f"&l{i - 1};" * 10 if i else "&l;" * 10}">\n'
                                   for i in range(9))
                         + "]>\n" + pxml(entry('<log text="&l8;"/>'))),
         Rejected("DOCTYPE declarations are not allowed", (2, 1))),
    Case("quadratic-blowup", "one large entity repeated many times",
         write("t.pxml", f'<!DOCTYPE p [<!ENTITY a "{"x" * 50_000}">]>\n'
                         + pxml(entry(f'<log text="{"&a;" * 1000}"/>'))),
         Rejected("DOCTYPE declarations are not allowed", (1, 1))),
    Case("external-dtd", "a DTD loaded from the network",
         write("t.pxml", '<!DOCTYPE pxml SYSTEM "http://127.0.0.1:9/pxml.dtd">\n' + pxml(STATE)),
         Rejected("DOCTYPE declarations are not allowed", (1, 1))),
    Case("parameter-entities", "parameter entities pulling an external subset",
         write("t.pxml", '<!DOCTYPE p [<!ENTITY % e SYSTEM "file:///etc/passwd"> %e;]>\n'
                         + pxml(STATE)),
         Rejected("DOCTYPE declarations are not allowed", (1, 1))),
    Case("doctype-after-comment", "a DOCTYPE hidden after a comment and blank lines",
         write("t.pxml", '<!-- hello -->\n\n   <!doctype pxml>\n' + pxml(STATE)),
         Rejected("DOCTYPE declarations are not allowed", (3, 4))),
    Case("xinclude", "XInclude of a local file (never processed)",
         doc('<state id="s" initial="true">'
             '<xi:include xmlns:xi="http://www.w3.org/2001/XInclude" href="/etc/passwd"/>'
             "</state>"),
         Rejected("<include> is not allowed inside <state>", "<xi:include")),
    Case("schema-location-pipe", "xsi schema location hints pointing at a named pipe",
         write("t.pxml", pxml(STATE, root=' xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"'
                                          ' xsi:noNamespaceSchemaLocation="evil.xsd"'
                                          ' xsi:schemaLocation="urn:prima:pxml:1 evil.xsd"'),
               fifo("evil.xsd")),
         Accepted()),
    Case("schema-location-pipe-invalid",
         "the same hints on an invalid document (xmlschema runs too)",
         write("t.pxml", pxml('<state id="s" initial="maybe"/>',
                              root=' xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"'
                                   ' xsi:schemaLocation="urn:prima:pxml:1 evil.xsd"'),
               fifo("evil.xsd")),
         Rejected("attribute initial='maybe'", 'maybe"')),
    Case("stylesheet-pi", "a processing instruction naming a remote stylesheet",
         write("t.pxml", '<?xml-stylesheet href="http://127.0.0.1:9/x.xsl"?>\n' + pxml(STATE)),
         Accepted()),
    Case("utf16-bom", "UTF-16 with a byte order mark (bytes that hide a DOCTYPE)",
         write("t.pxml", ("\ufeff" + pxml(STATE)).encode("utf-16-le")),
         Rejected("must be UTF-8 (this one looks like UTF-16 or UTF-32)", (1, 1))),
    Case("utf16-no-bom", "UTF-16 big-endian without a byte order mark",
         write("t.pxml", pxml(STATE, prolog='<?xml version="1.0" encoding="UTF-16"?>\n')
               .encode("utf-16-be")),
         Rejected("must be UTF-8", (1, 1))),
    Case("utf32", "UTF-32",
         write("t.pxml", pxml(STATE).encode("utf-32")),
         Rejected("must be UTF-8", (1, 1))),
    Case("declared-latin1", "a declared encoding other than UTF-8",
         write("t.pxml", pxml(STATE, prolog='<?xml version="1.0" encoding="ISO-8859-1"?>\n')
               .encode("latin-1")),
         Rejected("must be UTF-8, not 'ISO-8859-1'", "ISO-8859-1")),
    Case("utf8-bom", "a UTF-8 byte order mark (allowed; columns do not shift)",
         write("t.pxml", ("\ufeff" + pxml('<state id="s" initial="maybe"/>')).encode()),
         Rejected("attribute initial='maybe'", 'maybe"')),
    Case("nul-byte", "a NUL byte inside the document",
         write("t.pxml", pxml(entry('<log text="a\x00b"/>')).encode()),
         Rejected("malformed XML", "\x00")),
    Case("invalid-utf8", "bytes that are not UTF-8",
         write("t.pxml", pxml(entry('<log text="ab"/>')).encode().replace(b"ab", b"a\xff\xfeb")),
         Rejected("malformed XML: Invalid bytes in character encoding", "\ufffd")),
    Case("oversize", "a document one byte over 1 MiB",
         write("t.pxml", pxml(STATE + " " * (1 << 20))),
         Rejected("the limit is 1048576", (1, 1))),
    Case("overdeep", "elements nested 65 deep",
         doc(entry("<if cond='true'>" * 61 + "<log text='x'/>" + "</if>" * 61)),
         Rejected("elements nest deeper than 64 levels", "<log")),
    Case("very-deep", "elements nested 10,000 deep (libxml2 stops at 256)",
         doc("<a>" * 10_000 + "</a>" * 10_000),
         Rejected("malformed XML: Excessive depth in document", "<a>" * 255, offset=767)),
    Case("many-attributes", "47,000 unknown attributes on one element (1 MiB)",
         doc('<state id="s" initial="true" '
             + " ".join(f'a{i:06d}="xxxxxxxxxx"' for i in range(47_000)) + "/>"),
         Rejected("<state>: attribute 'a000000' is not allowed here", 'xxxxxxxxxx"')),
    Case("many-unknown-elements", "50,000 unknown elements (1 MiB)",
         doc(STATE + "\n" + "".join(f"<unknown-el{i:06d}/>\n" for i in range(50_000))),
         Rejected("<unknown-el000000> is not allowed at the top of the document",
                  "<unknown-el000000")),
    Case("many-comments", "100,000 comments and processing instructions",
         doc(entry("<!--x--><?p x?>" * 60_000)), Accepted()),
]

EXPRESSIONS = [
    Case("python-eval", "Python code in an expression",
         var("__import__('os').system('touch PWNED')"),
         Rejected("expression: unexpected '.'", ".system"), then=no_file_was_written),
    Case("dunder-attributes", "reaching object internals through dunder attributes",
         var("().__class__.__bases__[0].__subclasses__()"),
         Rejected("expression:", "()", offset=1)),
    Case("lambda", "a Python lambda", var("(lambda: 1)()"),
         Rejected("expression:", ": 1")),
    Case("open-file", "calling open() to read a file", var("open('/etc/passwd')"),
         Rejected("unknown function 'open'", "open")),
    Case("template-injection", "Python code inside a text's {...}",
         doc(entry("<log text=\"{__import__('os').system('x')}\"/>")),
         Rejected("expression: unexpected '.'", ".system")),
    Case("format-string", "a Python format string", var("'{0.__class__}'.format(1)"),
         Rejected("expression: unexpected '.'", ".format")),
    Case("huge-literal", "a number beyond 2^53", var("99999999999999999999"),
         Rejected("number too large", "99999")),
    Case("exponent-literal", "1e999 (no exponents in PXML numbers)", var("1e999"),
         Rejected("expression: unexpected 'e999'", "e999")),
    Case("long-literal", "a 25-digit number", var("9" * 25),
         Rejected("number too long", "999")),
    Case("huge-number-argument", "a number argument of 400 digits (infinite as a float)",
         doc(entry(f'<request><turn angle="{HUGE}"/></request>')),
         Rejected("is too large a number", HUGE)),
    Case("deep-parentheses", "parentheses nested 300,000 deep",
         var("(" * 300_000 + "1" + ")" * 300_000),
         Rejected("expression: longer than 10,000 characters", "((", offset=10_000)),
    Case("deep-in-length", "parentheses nested 4,999 deep, within the length limit",
         var("(" * 4_999 + "1" + ")" * 4_999),
         Rejected("expression: nested more than 50 levels deep", "((", offset=50)),
    Case("deep-unary", "300,000 unary minus signs", var("-" * 300_000 + "1"),
         Rejected("expression: longer than 10,000 characters", "--", offset=10_000)),
    Case("long-sum", "a sum of 4,000 terms (a left-deep tree)", var("+".join(["1"] * 4_000)),
         Rejected("expression: nested more than 50 levels deep", "1+", offset=101)),
    Case("deep-not", "60 nested 'not'", var("not " * 60 + "true"),
         Rejected("nested more than 50 levels deep", "not", offset=200)),
    Case("deep-templates", "string templates nested in strings, each behind three 'not'",
         var(DEEP_TEMPLATES),  # the first 'not' of the eleventh level is the 51st level
         Rejected("nested more than 50 levels deep", (2, len('<var name="x" expr="')
                                                         + _nth(DEEP_TEMPLATES, "not", 31) + 1))),
    Case("deep-calls", "function calls nested 60 deep", var("abs(" * 60 + "1" + ")" * 60),
         Rejected("nested more than 50 levels deep", "abs", offset=200)),
    Case("long-chain", "a chain of 30,000 Commands",
         doc(entry("<chain>" + ", ".join(["StopMoving()"] * 30_000) + "</chain>")),
         Rejected("chain: longer than 100,000 characters", "StopMoving", offset=100_000)),
    Case("many-commands", "a chain of 101 Commands",
         doc(entry("<chain>" + ", ".join(["StopMoving()"] * 101) + "</chain>")),
         Rejected("chain: more than 100 Commands", "StopMoving", offset=1400)),
    Case("many-requests", "a request of 101 Commands",
         doc(entry("<request>" + "<stop-moving/>" * 101 + "</request>")),
         Rejected("a request may hold at most 100 Commands", "<stop-moving", offset=1400)),
    Case("divide-by-zero", "1 / 0: a fault when it runs, which stops that application alone",
         var("1 / 0"), Accepted()),
    Case("constant-fault", "a constant that cannot be computed", var("-'a'"),
         Rejected("expression: '-' needs a number", "'a'")),
    Case("long-text", "a literal text of 10,001 characters",
         doc(entry(f'<log text="{"a" * 10_001}"/>')),
         Rejected("text: longer than 10,000 characters", "aaa", offset=10_000)),
    Case("unclosed", "an unclosed string and brace", doc(entry("<log text=\"{'abc}\"/>")),
         Rejected("text: '{' is not closed", "{'abc")),
    Case("cdata-chain", "a chain in a CDATA section, located inside it",
         doc(entry("<chain><![CDATA[Speak(1 <)]]></chain>")),
         Rejected("chain:", ")]]>")),
    Case("escaped-operator", "&amp;&amp; in a condition, located at the written '&'",
         doc(entry('<if cond="true &amp;&amp; false"><log text="x"/></if>')),
         Rejected("'&&' is not an operator", "&amp;")),
    # Each of these expressions is parsed (lark, about 40 microseconds each): linear, but
    # seconds for a full 1 MiB; a quadratic cost would take hours.
    Case("many-faults", "47,000 undefined variables, one per text (1 MiB)",
         doc(entry('<log text="{nope}"/>\n' * 47_000)),
         Rejected("undefined variable 'nope'", "nope"), seconds=6),
    Case("many-syntax-faults", "49,000 expression syntax faults on one line (1 MiB)",
         doc(entry('<log text="{1 +}"/>' * 49_000)),
         Rejected("ends too early", "}"), seconds=8),
]

GRAMMARS = [
    Case("pattern-four-stars", "a pattern of four '*' against a 500-character answer",
         doc('<grammar id="g"><pattern>* a * b * c * d</pattern></grammar>\n' + STATE),
         Accepted(), then=match_hostile_answer),
    Case("pattern-too-long", "a pattern of 21 items",
         doc('<grammar id="g"><pattern>' + "* a " * 10 + "b</pattern></grammar>\n" + STATE),
         Rejected("a pattern needs 1 to 20 words", "<pattern")),
    Case("patterns-too-many", "51 patterns in one grammar",
         doc('<grammar id="g">' + "<pattern>a *</pattern>" * 51 + "</grammar>\n" + STATE),
         Rejected("at most 50 patterns", "<pattern", offset=50 * len("<pattern>a *</pattern>"))),
    Case("pattern-captures", "five captures", doc(
         '<grammar id="g"><pattern>* # * # *</pattern></grammar>\n' + STATE),
         Rejected("at most 4 times", "<pattern")),
    Case("many-synonyms", "10,000 synonyms of two words",
         doc('<grammar id="g"><choice value="v">'
             + " | ".join(f"w{i} x" for i in range(10_000)) + "</choice></grammar>\n" + STATE),
         Accepted(), then=match_many_synonyms),
]

SCENARIOS = [
    Case("regex-bomb", "a catastrophically backtracking answer rule",
         user('<answer matches="(a+)+$" say="x"/>'), Rejected("a group ('(')", "(a+)")),
    Case("regex-bomb-2", "nested repetition in an answer rule",
         user('<answer matches="x|(x+x+)+y" say="x"/>'), Rejected("a group ('(')", "(x+")),
    Case("regex-repeat", "a counted repetition", user('<answer matches="a{1000}" say="x"/>'),
         Rejected("repetition ('{')", "{1000")),
    Case("regex-backreference", "a backreference", user('<answer matches="(a)\\1" say="x"/>'),
         Rejected("a group", "(a)")),
    Case("regex-class", "a character class", user('<answer matches="[a-z]b" say="x"/>'),
         Rejected("a character class", "[a-z]")),
    Case("regex-long", "an answer rule of 201 characters",
         user(f'<answer matches="{"x" * 201}" say="x"/>'),
         Rejected("matches: longer than 200 characters", "xxx", offset=200)),
    Case("regex-safe-long-prompt", "a safe rule searched in a 10,000-character prompt",
         user('<answer matches="' + "|".join(["a" * 19 + "b"] * 9) + '" say="x"/>'),
         Accepted(), then=search_long_prompt),
    Case("until-exponent", "until='1e999' (not a decimal)",
         scenario(attrs='name="s" until="1e999"'),
         Rejected("attribute until='1e999'", "1e999")),
    Case("until-inf", "until='INF'", scenario(attrs='name="s" until="INF"'),
         Rejected("attribute until='INF'", "INF")),
    Case("until-nan", "until='NaN'", scenario(attrs='name="s" until="NaN"'),
         Rejected("attribute until='NaN'", "NaN")),
    Case("until-huge", "until of 400 digits", scenario(attrs=f'name="s" until="{HUGE}"'),
         Rejected("is too large: at most 1e+06 s", HUGE)),
    Case("until-tiny", "until that is 0 as a float", scenario(attrs=f'name="s" until="{TINY}"'),
         Rejected("must be greater than 0", TINY)),
    Case("until-zero", "until='0'", scenario(attrs='name="s" until="0"'),
         Rejected("attribute until='0'", '0"')),
    Case("rate-odd", "a rate the simulator cannot step at",
         scenario(attrs='name="s" until="10" rate="7"'),
         Rejected("rate must be a multiple of 10", '7"')),
    Case("rate-huge", "a rate of a million steps a second",
         scenario(attrs='name="s" until="10" rate="1000000"'),
         Rejected("rate='1000000' is too large", "1000000")),
    Case("seed-digits", "a seed of 5,000 digits (Python refuses to convert it)",
         scenario(attrs=f'name="s" until="10" seed="{"7" * 5000}"'),
         Rejected("seed='77777777777777777...' is too large", "777")),
    Case("negative-time", "an action at a negative time",
         user('<touch at="-1"/>'), Rejected("attribute at='-1'", "-1")),
    Case("tiny-speed", "a walking speed that is 0 as a float",
         user("", attrs=f'x="0" y="0" speed="{TINY}"'), Rejected("must be greater than 0", TINY)),
    Case("huge-coordinate", "a coordinate of 400 digits",
         scenario(robot=f'<robot x="{HUGE}" y="0"/>'), Rejected("is too large", HUGE)),
    Case("nth-digits", "an answer's nth of 400 digits",
         user(f'<answer nth="{HUGE}" say="x"/>'), Rejected("nth=", HUGE)),
    Case("ea-is-a-pipe", "the EA a scenario names is a named pipe",
         scenario(apps='<apps ea="ea.pxml"/>', extra=fifo("ea.pxml")),
         Rejected("file 'ea.pxml' is not a regular file", "ea.pxml")),
    Case("map-is-a-folder", "the map a scenario names is a folder",
         scenario(href="maps", extra=lambda folder: (folder / "maps").mkdir()),
         Rejected("map file 'maps' is not a regular file", "maps")),
    Case("fa-is-a-device", "the FA a scenario names is a device",
         scenario(apps='<apps fa="/dev/zero"/>'),
         Rejected("file '/dev/zero' is not a regular file", "/dev/zero")),
    Case("zone-ea-bomb", "a zone loads an EA with an entity bomb",
         scenario('  <zone name="z" ea="zone.pxml" area="r"/>\n',
                  extra=lambda folder: (folder / "zone.pxml").write_text(
                      '<!DOCTYPE p [<!ENTITY a "aaaa">]>' + pxml(STATE))),
         Rejected("DOCTYPE declarations are not allowed", (1, 1), file="zone.pxml")),
    Case("self-reference", "a scenario naming itself as its map, profile and EA",
         write("s.xml", '<scenario xmlns="urn:prima:scenario:1" name="s" until="10">\n'
                        '  <map href="s.xml"/>\n  <apps ea="s.xml"/>\n'
                        '  <robot x="0" y="0" profile="s.xml"/>\n</scenario>\n'),
         Rejected("expected a <map> element in namespace 'urn:prima:map:1'", (1, 1))),
    Case("mutual-reference", "two scenarios naming each other as their maps",
         write("a.xml", '<scenario xmlns="urn:prima:scenario:1" name="a" until="10">\n'
                        '  <map href="b.xml"/>\n  <robot x="0" y="0"/>\n</scenario>\n',
               lambda folder: (folder / "b.xml").write_text(
                   '<scenario xmlns="urn:prima:scenario:1" name="b" until="10">\n'
                   '  <map href="a.xml"/>\n  <robot x="0" y="0"/>\n</scenario>\n')),
         Rejected("'b.xml' is not a map (its root is in 'urn:prima:scenario:1')", 'b.xml"')),
    Case("ea-in-fa-slot", "an EA named as the FA",
         scenario(apps='<apps fa="ea.pxml"/>', extra=app("ea.pxml")),
         Rejected("'ea.pxml' is an EA (kind=\"ea\"); it cannot run as the FA", "ea.pxml")),
    Case("say-empty", "a user who says nothing (an empty <say>), heard as a barge-in",
         user('<say at="1" text=""/>'),
         Rejected("blank words are no speech", 'text=""', offset=6)),
    Case("say-blank", "a user who says a space and a tab",
         user('<say at="1" text=" &#9;"/>'),
         Rejected("blank words are no speech", 'text="', offset=6)),
    Case("answer-blank", "an answer rule that says a tab",
         user('<answer contains="x" say="&#9;"/>'),
         Rejected("blank words are no answer", 'say="', offset=5)),
]

MAPS = [
    Case("wall-tiny", "a wall thickness that is 0 as a float",
         map_file(f'<wall x1="0" y1="0" x2="1" y2="0" thickness="{TINY}"/>'),
         Rejected("thickness=", TINY)),
    Case("place-huge", "a place at a coordinate of 400 digits",
         map_file(f'<place name="a" x="{HUGE}" y="0"/>'), Rejected("x=", HUGE)),
    Case("facing-nan", "facing='NaN'", map_file('<place name="a" x="0" y="0" facing="NaN"/>'),
         Rejected("attribute facing='NaN'", "NaN")),
    Case("map-many-unknown", "12,000 edges to unknown places among 12,000 places",
         map_file("".join(f'<place name="p{i}" x="0" y="{i / 1000}"/>' for i in range(12_000))
                  + "".join(f'<edge from="p{i}" to="q{i}"/>' for i in range(12_000))),
         Rejected("unknown place 'q0' (known: p0, p1, p10, p100", 'q0"')),
]

PROFILES = [
    Case("radius-zero", "radius='0'", robot('radius="0.2"', 'radius="0"'),
         Rejected("attribute radius='0'", 'radius="0"', offset=8)),
    Case("radius-tiny", "a radius that is 0 as a float", robot('radius="0.2"', f'radius="{TINY}"'),
         Rejected("radius='0.000000000000000...' must be greater than 0", TINY)),
    Case("speed-inf", "max-speed='inf'", robot('max-speed="0.4"', 'max-speed="inf"'),
         Rejected("attribute max-speed='inf'", "inf")),
    Case("speed-huge", "a max-speed of 400 digits", robot('max-speed="0.4"', f'max-speed="{HUGE}"'),
         Rejected("max-speed='10000000000000000...' is too large", HUGE)),
    Case("speech-rate-zero", "a speech rate that is 0 as a float",
         robot('<speech rate="2.5"/>', f'<speech rate="{TINY}"/>'),
         Rejected("rate='0.000000000000000...' must be greater than 0", TINY)),
    Case("budget-text", "a text budget over MAX_TEXT",
         robot("  </devices>\n", '  </devices>\n  <budgets text="10001"/>\n'),
         Rejected("text='10001' is too large: at most 10,000", "10001")),
    Case("budget-share", "a wait share longer than its window",
         robot("  </devices>\n", '  </devices>\n  <budgets wait-share="90"/>\n'),
         Rejected("wait-share=90 s is longer than its window", 'wait-share="', offset=12)),
    Case("budget-inf", "a longest-ab of 400 digits",
         robot("  </devices>\n", f'  </devices>\n  <budgets longest-ab="{HUGE}"/>\n'),
         Rejected("longest-ab=", HUGE)),
    Case("default-nan", "a number parameter's default of 'nan'",
         robot('name="volume" kind="number"', 'name="volume" kind="number" default="nan"'),
         Rejected("default='nan' is not a number", 'nan"')),
    Case("profile-doctype", "a profile with an entity",
         robot('<robot xmlns', '<!DOCTYPE robot [<!ENTITY e "x">]>\n<robot xmlns'),
         Rejected("DOCTYPE declarations are not allowed", "<!DOCTYPE")),
    Case("robot-budget-text", "an application's literal text over its robot's budget",
         write("t.pxml", pxml(entry('<log text="' + "a" * 21 + '"/>')),
               robot("  </devices>\n", '  </devices>\n  <budgets text="20"/>\n')),
         Rejected("text: longer than 20", "aaa", offset=20), argv=("--robot", "{dir}/robot.xml")),
]

FILES = [
    Case("named-pipe", "a named pipe given as a document (reading it blocks forever)",
         made(_named_pipe), Rejected("a named pipe: PRIMA reads only regular files", (1, 1))),
    Case("device", "a device given as a document", special("/dev/zero"),
         Rejected("a device: PRIMA reads only regular files", (1, 1))),
    Case("robot-folder", "a folder given as the robot profile", doc(STATE),
         Rejected("a directory: PRIMA reads only regular files", (1, 1), file="."),
         argv=("--robot", "{dir}")),
    Case("folder-with-pipe", "a named pipe among the files of a folder",
         made(_folder_with_a_pipe), Accepted()),
    Case("symlink-loop", "a folder containing a symbolic link to itself",
         made(_symlink_loop), Accepted()),
]

CASES = [*XML, *EXPRESSIONS, *GRAMMARS, *SCENARIOS, *MAPS, *PROFILES, *FILES]
