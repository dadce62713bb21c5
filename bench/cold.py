"""Benchmark: cold ``prima`` processes, as a user starts them.

Usage: python bench/cold.py [--repeats N] [--against TREE]

Every case is a fresh process, ``python -m prima ...`` with this benchmark's
interpreter (the ``prima`` script does the same imports), so each figure
includes the interpreter's start, PRIMA's imports and the one-off building of
schemas and parsers. Each is measured as that process's CPU time (user +
system), the median over interleaved rounds, and shown as a ratio to a bare
``python -c pass`` started in the same rounds:

- ``prima --version`` and ``prima --help``;
- ``prima validate`` of one application (apps/fa/fa2-follow.pxml);
- ``prima run`` of scenarios/thesis/fig5-7.xml;
- the 17 thesis scenarios (scenarios/thesis/*.xml) as 17 ``prima run``
  processes, one after the other: the sum of their CPU time in each round.

The targets we hold these to are checked at the end. With ``--against TREE`` (a
checkout of an earlier build: ``git worktree add /tmp/before 74e2f0f``, installed
in an environment of its own whose interpreter ``--against-python`` names), ``prima
--version``, ``prima validate`` of that build's own copy of the document and its own
17 thesis scenarios run in the same rounds, from that tree, and this build must cost
no more than it.

Compiled bytecode: an installed PRIMA has its ``.pyc`` files (pip compiles
them at install), but a checkout under ``PYTHONDONTWRITEBYTECODE`` would
compile every module of PRIMA again in every process (about 90 ms). So the
children write and read their bytecode in a temporary folder of this
benchmark (``PYTHONPYCACHEPREFIX``), filled by one warm-up round that is not
counted; ``--no-bytecode`` measures with the environment as it is instead.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from _measure import ROOT, child_cpu, fmt_time, interleaved, interpreter, report

PRIMA = [sys.executable, "-m", "prima"]
ONE_DOCUMENT = ROOT / "apps" / "fa" / "fa2-follow.pxml"
FIG5_7 = ROOT / "scenarios" / "thesis" / "fig5-7.xml"
THESIS = sorted((ROOT / "scenarios" / "thesis").glob("*.xml"))

TARGETS = {
    "prima validate (one document)": 0.25,
    f"{len(THESIS)} thesis scenarios (separate runs)": 5.0,
}
"""The targets: CPU seconds at most (docs/benchmarks.md)."""


EARLIER = " (earlier build)"
AGAINST = ("prima --version", "prima validate (one document)",
           f"{len(THESIS)} thesis scenarios (separate runs)")
"""The cases measured on an earlier build too (``--against``): this build's cost must be
at most that build's."""


def _thesis() -> float:
    return sum(child_cpu([*PRIMA, "run", str(path)]) for path in THESIS)


def cases() -> dict[str, Callable[[], float]]:
    return {
        "python -c pass": lambda: child_cpu([sys.executable, "-c", "pass"]),
        "prima --version": lambda: child_cpu([*PRIMA, "--version"]),
        "prima --help": lambda: child_cpu([*PRIMA, "--help"]),
        "prima validate (one document)": lambda: child_cpu([*PRIMA, "validate",
                                                            str(ONE_DOCUMENT)]),
        "prima run fig5-7": lambda: child_cpu([*PRIMA, "run", str(FIG5_7)]),
        f"{len(THESIS)} thesis scenarios (separate runs)": _thesis,
    }


def earlier_cases(tree: Path, python: str) -> dict[str, Callable[[], float]]:
    """:data:`AGAINST` run from ``tree``, an earlier build's checkout, by ``python`` (an
    environment with that build installed: an editable install of this one would hand
    it this build's robots), on its own copy of the document."""
    def run(*argv: str) -> Callable[[], float]:
        return lambda: child_cpu([python, "-m", "prima", *argv], cwd=tree)
    runs = [run("run", str(tree / path.relative_to(ROOT))) for path in THESIS]
    return {
        f"prima --version{EARLIER}": run("--version"),
        f"prima validate (one document){EARLIER}": run(
            "validate", str(tree / ONE_DOCUMENT.relative_to(ROOT))),
        f"{len(THESIS)} thesis scenarios (separate runs){EARLIER}":
            lambda: sum(each() for each in runs),
    }


def use_bytecode(folder: str) -> None:
    """Let the child processes cache their bytecode in ``folder``, as an install does."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    os.environ["PYTHONPYCACHEPREFIX"] = folder


def bytecode_mode() -> str:
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return "PYTHONDONTWRITEBYTECODE set, every module compiled in every process"
    if os.environ.get("PYTHONPYCACHEPREFIX"):
        return "cached, as in an installed package"
    return "the environment's"


def check_targets(medians: dict[str, float]) -> bool:
    """Print each target and whether it is met; whether all are."""
    print("targets:")
    met_all = True
    limits = [(name, limit, fmt_time(limit)) for name, limit in TARGETS.items()]
    limits += [(name, medians[name + EARLIER], "the earlier build's "
                f"{fmt_time(medians[name + EARLIER])}") for name in AGAINST
               if name + EARLIER in medians]
    for name, limit, than in limits:
        met = medians[name] <= limit
        met_all = met_all and met
        print(f"  {name:<40} {fmt_time(medians[name]):>9} <= {than:>7}: "
              f"{'met' if met else 'NOT met'} ({medians[name] / limit:.2f}x)")
    print(interpreter())
    return met_all


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, metavar="N",
                        help="interleaved rounds (default 5)")
    parser.add_argument("--no-bytecode", action="store_true",
                        help="leave the environment's bytecode setting as it is")
    parser.add_argument("--against", type=Path, metavar="TREE",
                        help="an earlier build's checkout: prima --version, validate and "
                             "the thesis runs measured there too, in the same rounds")
    parser.add_argument("--against-python", metavar="PYTHON", default=sys.executable,
                        help="the interpreter of an environment with TREE installed "
                             "(default: this one)")
    args = parser.parse_args()
    if args.against is not None and not (args.against / "prima").is_dir():
        parser.error(f"--against {args.against}: not a checkout of prima")
    if len(THESIS) != 17:
        print(f"note: {len(THESIS)} thesis scenarios, not 17")
    with tempfile.TemporaryDirectory(prefix="prima-bench-pyc-") as pyc:
        if not args.no_bytecode:
            use_bytecode(pyc)
        measured = cases()
        if args.against is not None:
            measured.update(earlier_cases(args.against.resolve(), args.against_python))
        interleaved(measured, 1)  # warm-up: bytecode written, files in the page cache
        medians = interleaved(measured, args.repeats)
    report("cold processes", medians, "python -c pass", repeats=args.repeats)
    print(f"  (python -m prima; bytecode: {bytecode_mode()})")
    return 0 if check_targets(medians) else 1


if __name__ == "__main__":
    sys.exit(main())
