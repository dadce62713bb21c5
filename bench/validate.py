"""Benchmark: ``prima validate`` of 100 distinct documents, cold, against xmllint.

Usage: python bench/validate.py [--repeats N] [--seed S] [--keep DIR]

The corpus is generated from a seed: 100 applications (FAs and EAs) of 3 to
10 states, their variables, grammars, Commands in chains and as elements,
conditions, texts and names drawn at random, so that no two files are the
same text and a parse memoised in one file is of little use in the next. A
tenth of them are invalid, each with one fault of another kind: schema
faults (an unknown element, a missing or unknown attribute, a bad value),
expression faults (``=`` for ``==``, ``&&``, an unknown function, an unclosed
``{``), meaning faults (an undefined variable or state, an unknown Command, a
missing ``,`` in a chain).

Cases, each a fresh process, in interleaved rounds (CPU time, medians):

- ``prima validate FOLDER``: expected to exit 1, and to report exactly the
  invalid documents (checked on every run);
- the peer, ``xmllint --noout --schema schemas/pxml.xsd FILES`` on the same
  files (the schema alone: it finds the schema faults, not the others).

Then the same validation in this process with everything already built (as an
editor integration validating on every save would), against xmllint's figure.
Bytecode is cached for the children as in ``bench/cold.py`` (``--no-bytecode``
to measure with the environment as it is).
"""

from __future__ import annotations

import argparse
import random
import re
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from xml.sax.saxutils import escape

from _measure import ROOT, child_cpu, cpu, fmt_time, interleaved, interpreter, report
from cold import bytecode_mode, use_bytecode

from prima.dsl import collect, validate_paths

PRIMA = [sys.executable, "-m", "prima"]
SCHEMA = ROOT / "schemas" / "pxml.xsd"
N_DOCUMENTS = 100
TARGET = 1.0
"""The target: cold ``prima validate`` of the corpus in at most 1 s of CPU (docs/benchmarks.md)."""

WORDS = (
    "apple", "river", "window", "garden", "lamp", "story", "music", "coffee", "paper",
    "bridge", "morning", "table", "orange", "silver", "quiet", "yellow", "ladder", "pocket",
    "summer", "winter", "rabbit", "piano", "candle", "forest", "marble", "basket", "cloud",
    "pencil", "harbor", "meadow", "violet", "copper", "lantern", "velvet", "canyon",
    "feather", "island", "thunder", "blossom", "compass",
)
GESTURES = ("nod", "shake-head", "wave", "bow", "happy", "sad", "surprised")
PLACES = ("kidode_room", "hall", "entrance", "panel_1", "lab", "kitchen")
EVENTS = ("human-found", "human-lost", "message", "place-reached", "sound-heard")

FAULTS = (
    "schema-unknown-element", "schema-missing-attribute", "schema-bad-value",
    "schema-unknown-attribute", "expr-assign", "expr-and-and", "expr-unknown-function",
    "text-unclosed-brace", "undefined-variable", "undefined-state", "unknown-command",
    "chain-missing-comma",
)


class Doc:
    """One generated document: names drawn for it, its lines, the fault to plant."""

    def __init__(self, rng: random.Random, index: int, fault: str | None) -> None:
        self.rng = rng
        self.index = index
        self.fault = fault
        self.planted = False
        self.kind = "ea" if index % 3 == 2 else "fa"
        tag = f"{index:02d}{rng.randrange(1000):03d}"
        self.name = f"{rng.choice(WORDS)}-{rng.choice(WORDS)}-{tag}"
        self.numbers = [f"{rng.choice(WORDS)}_{tag}_{i}" for i in range(rng.randint(1, 3))]
        self.texts = [f"{rng.choice(WORDS)}_{i}_{rng.randrange(100)}"
                      for i in range(rng.randint(1, 3))]
        self.grammars = [f"g_{rng.choice(WORDS)}_{i}" for i in range(rng.randint(1, 2))]
        self.states = [f"{rng.choice(WORDS)}-{i}" for i in range(rng.randint(3, 10))]
        self.qa = 0
        self.lines: list[str] = []

    # ------------------------------------------------------------ pieces

    def words(self, lo: int = 2, hi: int = 7) -> str:
        return " ".join(self.rng.choice(WORDS) for _ in range(self.rng.randint(lo, hi)))

    def sentence(self) -> str:
        text = self.words().capitalize()
        if self.rng.random() < 0.4:
            text += f" {{{self.rng.choice(self.numbers + self.texts)}}}"
        return text + self.rng.choice(".!?")

    def condition(self) -> str:
        rng = self.rng
        parts = []
        for _ in range(rng.randint(1, 3)):
            if rng.random() < 0.6:
                parts.append(f"{rng.choice(self.numbers)} {rng.choice(['<', '>=', '==', '!='])} "
                             f"{rng.randrange(50)}")
            else:
                parts.append(f"{rng.choice(self.texts)} == '{rng.choice(WORDS)}'")
        cond = f" {rng.choice(['and', 'or'])} ".join(parts)
        return f"not ({cond})" if rng.random() < 0.2 else cond

    def chain_step(self, label: str | None = None) -> str:
        rng = self.rng
        if label:
            return f"{label}: QA(\"{self.sentence()}\", {rng.choice(self.grammars)}, " \
                   f"{rng.choice(self.texts)})"
        pick = rng.randrange(6)
        if pick == 0:
            return f"TopologicalMove({rng.choice(PLACES)})"
        if pick == 1:
            return f"Turn({rng.randint(-180, 180)})"
        if pick == 2:
            return f"Gesture(\"{rng.choice(GESTURES)}\")"
        if pick == 3:
            return f"SetDirection(toward={rng.choice(PLACES)})"
        return f"Speak(\"{self.sentence()}\")"

    def element_command(self) -> str:
        rng = self.rng
        pick = rng.randrange(4)
        if pick == 0:
            return f'<speak text="{self.sentence()}"/>'
        if pick == 1:
            return f'<turn angle="{{{rng.choice(self.numbers)} * {rng.randint(2, 9)}}}"/>'
        if pick == 2:
            return f'<topological-move to="{rng.choice(PLACES)}"/>'
        return f'<gesture name="{rng.choice(GESTURES)}"/>'

    def plant(self, kind: str) -> bool:
        """Whether to plant the fault ``kind`` here (the first place it fits)."""
        if self.fault == kind and not self.planted:
            self.planted = True
            return True
        return False

    # ------------------------------------------------------------ the document

    def text(self) -> str:
        rng = self.rng
        out = self.lines
        out.append('<?xml version="1.0" encoding="UTF-8"?>')
        out.append(f"<!-- generated: document {self.index}, {self.words(3, 9)} -->")
        out.append(f'<pxml xmlns="urn:prima:pxml:1" kind="{self.kind}" name="{self.name}">')
        out.append(f"  <description>{self.words(5, 15)}</description>")
        for name in self.numbers:
            out.append(f'  <var name="{name}" expr="{rng.randrange(100)}"/>')
        for name in self.texts:
            out.append(f'  <var name="{name}" expr="\'{rng.choice(WORDS)}\'"/>')
        for grammar in self.grammars:
            out.append(f'  <grammar id="{grammar}">')
            for _ in range(rng.randint(1, 3)):
                value = rng.choice(WORDS)
                out.append(f'    <choice value="{value}">{value} | {self.words(1, 3)}</choice>')
            out.append("  </grammar>")
        for i, state in enumerate(self.states):
            self.state(state, initial=i == 0)
        if self.fault and not self.planted:  # a fault that found no place: at the end
            self.fault, fault = None, self.fault
            self.lines.insert(-1, _late_fault(fault, self))
        out.append("</pxml>")
        return "\n".join(out) + "\n"

    def state(self, state: str, initial: bool) -> None:
        rng, out = self.rng, self.lines
        attrs = ' initial="true"' if initial else ""
        out.append(f'  <state id="{state}"{attrs}>')
        out.append("    <entry>")
        label = f"ask{self.qa}" if rng.random() < 0.5 else None
        steps = [self.chain_step() for _ in range(rng.randint(0, 3))]
        if label:
            steps.append(self.chain_step(label))
            self.qa += 1
        if self.plant("unknown-command"):
            steps.append(f"{rng.choice(WORDS).capitalize()}Move({rng.choice(PLACES)})")
        if steps:
            sep = " " if self.plant("chain-missing-comma") and len(steps) > 1 else ", "
            out.append(f"      <chain>{sep.join(steps)}</chain>")
        if rng.random() < 0.5 or not steps:
            out.append("      <request>")
            for _ in range(rng.randint(1, 3)):
                out.append(f"        {self.element_command()}")
            if self.plant("schema-unknown-element"):
                out.append(f"        <{rng.choice(WORDS)}-{rng.choice(WORDS)}/>")
            out.append("      </request>")
        if self.plant("text-unclosed-brace"):
            out.append(f'      <log text="{self.words()} {{{rng.choice(self.numbers)}"/>')
        out.append("    </entry>")
        following = self.states[(self.states.index(state) + 1) % len(self.states)]
        for i in range(rng.randint(1, 3)):
            self.handler(following if i == 0 else rng.choice(self.states))
        if label:
            out.append(f'    <on-answer of="{label}"><goto state="{rng.choice(self.states)}"/>'
                       "</on-answer>")
        out.append("  </state>")

    def handler(self, target: str) -> None:
        rng, out = self.rng, self.lines
        cond = self.condition()
        if self.plant("expr-assign"):
            cond = cond.replace(" == ", " = ", 1) if " == " in cond else \
                f"{rng.choice(self.numbers)} = {rng.randrange(9)}"
        elif self.plant("expr-and-and"):
            cond = f"{cond} && {rng.choice(self.numbers)} > {rng.randrange(9)}"
        elif self.plant("expr-unknown-function"):
            cond = f"{rng.choice(['sqrt', 'floor', 'ceil', 'log'])}({rng.choice(self.numbers)})" \
                   f" > {rng.randrange(9)}"
        elif self.plant("undefined-variable"):
            cond = f"{cond} and {rng.choice(WORDS)}_undeclared > 1"
        event = rng.choice(EVENTS)
        if self.plant("schema-bad-value"):
            out.append(f'    <on event="{event}" reactive="{rng.choice(WORDS)}">')
        elif self.plant("schema-unknown-attribute"):
            out.append(f'    <on event="{event}" {rng.choice(WORDS)}="{rng.choice(WORDS)}">')
        else:
            out.append(f'    <on event="{event}" cond="{escape(cond)}">')
        number = rng.choice(self.numbers)
        out.append(f'      <assign name="{number}" expr="{number} + {rng.randint(1, 5)}"/>')
        if rng.random() < 0.4:
            out.append(f'      <if cond="{escape(self.condition())}">')
            out.append(f'        <log text="{self.sentence()}"/>')
            out.append("      <else/>")
            out.append(f"        <chain>Speak(\"{self.sentence()}\")</chain>")
            out.append("      </if>")
        if self.plant("undefined-state"):
            target = f"{target}-nowhere"
        if self.plant("schema-missing-attribute"):
            out.append("      <goto/>")
        else:
            out.append(f'      <goto state="{target}"/>')
        out.append("    </on>")


def _late_fault(fault: str, doc: Doc) -> str:
    """A fault that found no place in the states, as one more line before ``</pxml>``."""
    other = {
        "unknown-command": "  <on event=\"human-found\"><chain>FlyAway()</chain></on>",
        "chain-missing-comma": "  <on event=\"human-found\"><chain>Speak(\"a\") Speak(\"b\")"
                               "</chain></on>",
    }
    return other.get(fault, f"  <on event=\"human-found\" cond=\"{fault} = 1\"/>")


def make_corpus(folder: Path, seed: int, n: int = N_DOCUMENTS) -> tuple[list[Path], set[Path]]:
    """Write ``n`` distinct documents into ``folder``; all of them, and the invalid ones."""
    rng = random.Random(seed)
    invalid = set(rng.sample(range(n), n // 10))
    faults = iter(rng.sample(FAULTS, len(FAULTS)) * (n // 10 // len(FAULTS) + 1))
    files, bad = [], set()
    texts: set[str] = set()
    for i in range(n):
        doc = Doc(rng, i, next(faults) if i in invalid else None)
        text = doc.text()
        if text in texts:
            sys.exit(f"document {i} repeats another: the generator must vary more")
        texts.add(text)
        path = folder / f"{doc.name}.pxml"
        path.write_text(text, encoding="utf-8")
        files.append(path)
        if i in invalid:
            bad.add(path)
    return files, bad


_PROBLEM = re.compile(r"^(?P<file>.+?):\d+:\d+: error: ", re.M)


def check_reports(folder: Path, bad: set[Path]) -> int:
    """Run ``prima validate FOLDER`` and check that it exits 1 and reports exactly ``bad``."""
    done = subprocess.run([*PRIMA, "validate", str(folder)], capture_output=True, text=True,
                          check=False)
    reported = {Path(m.group("file")) for m in _PROBLEM.finditer(done.stdout)}
    if done.returncode != 1 or reported != bad:
        sys.exit(f"prima validate exited {done.returncode} and reported {len(reported)} "
                 f"documents; expected 1 and these {len(bad)}: "
                 f"{sorted(p.name for p in bad ^ reported)}\n{done.stdout}{done.stderr}")
    return len(reported)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, metavar="N",
                        help="interleaved rounds (default 5)")
    parser.add_argument("--seed", type=int, default=13, help="the corpus' seed (default 13)")
    parser.add_argument("--keep", metavar="DIR", help="write the corpus to DIR and keep it")
    parser.add_argument("--no-bytecode", action="store_true",
                        help="leave the environment's bytecode setting as it is")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="prima-bench-") as tmp:
        folder = Path(args.keep) if args.keep else Path(tmp) / "corpus"
        folder.mkdir(parents=True, exist_ok=True)
        if not args.no_bytecode:
            use_bytecode(str(Path(tmp) / "pyc"))
        files, bad = make_corpus(folder, args.seed)
        lines = sum(len(f.read_text(encoding="utf-8").splitlines()) for f in files)
        reported = check_reports(folder, bad)
        argv = [*PRIMA, "validate", str(folder)]
        xmllint = ["xmllint", "--noout", "--schema", str(SCHEMA), *map(str, files)]
        cases: dict[str, Callable[[], float]] = {
            "xmllint --schema (cold)": lambda: child_cpu(xmllint, ok=(0, 3)),
            "prima validate (cold)": lambda: child_cpu(argv, ok=(1,)),
        }
        interleaved(cases, 1)  # warm-up: bytecode written, files in the page cache
        medians = interleaved(cases, args.repeats)
        found = collect([folder])
        validate_paths(found)  # build the schemas and the parser once
        warm = interleaved({"prima, in-process (warm)": lambda: cpu(lambda: validate_paths(found))},
                           args.repeats)
    print(f"{len(files)} distinct documents, {lines} lines, {len(bad)} invalid "
          f"(prima validate reports {reported}: right)")
    report("validation", {**medians, **warm}, "xmllint --schema (cold)", repeats=args.repeats)
    print(f"  (python -m prima; bytecode: {bytecode_mode()}; the warm figure is measured "
          "after the cold rounds)")
    cold = medians["prima validate (cold)"]
    print(f"target: prima validate (cold) {fmt_time(cold)} <= {fmt_time(TARGET)}: "
          f"{'met' if cold <= TARGET else 'NOT met'}")
    print(interpreter())
    return 0 if cold <= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
