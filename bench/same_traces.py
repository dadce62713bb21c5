"""Do two builds make the same traces? The check a speed change passes before it lands:
a change meant only to make runs cheaper leaves every trace byte for byte as it was.

Usage: python bench/same_traces.py --against TREE [--runs 40] [--jobs 2] [SCENARIO ...]
       python bench/same_traces.py --compiled [--runs 40] [--jobs 2] [SCENARIO ...]

``TREE`` is a checkout of the other build (``git worktree add /tmp/before <commit>``);
``--compiled`` makes the other build this checkout's compiled one (``setup.py``,
``PRIMA_MYPYC=1``), built first in a temporary copy.
For each scenario (default: every scenario this tree ships), runs 0 to ``--runs`` - 1
are made: run 0 as written, the others with their timings jittered by 5 s as a sweep
jitters them (``prima.batch``, seed 7). Each build runs its own copy of the scenario
and of the documents it names (as :mod:`bench.sweep`'s ``--against`` does), in
processes of its own, and hashes each run's whole jsonl trace and the rows the judge
reads in a judged run that writes no trace (a sweep's runs; SHA-256). Prints the
runs whose traces differ, and exits 1 if any does (or if a run fails in one build
only).
"""

from __future__ import annotations

import argparse
import copy
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from _measure import ROOT, compiled_copy, in_checkout, in_tree

JITTER = 5.0
SEED = 7

_HASH = """
import hashlib, json, sys
from prima.run import Run
out = {}
for path in sys.argv[1:]:
    digest = hashlib.sha256()
    try:
        for line in Run(path).run():
            digest.update(json.dumps(line.to_dict(), sort_keys=True).encode())
        try:
            rows = []
            run = Run(path, rows=rows.append)
        except TypeError:  # (a build from before judged runs' rows)
            rows = None
        made = None
        if rows is not None:
            run.run()
            made = hashlib.sha256()
            for row in rows:  # (in its own key order: the rows are made, not written)
                made.update(json.dumps(row).encode())
        out[path] = digest.hexdigest() + (" rows " + made.hexdigest() if made else "")
    except Exception as exc:  # noqa: BLE001 - a failing run is a result to compare
        out[path] = f"error: {type(exc).__name__}: {exc}"
print(json.dumps(out))
"""
"""What each build runs on its variants: the hash of each run's trace and of the rows a
judged run hands the judge (``Run(rows=...)``, made without a trace: a sweep's), or its
error."""


def shipped() -> list[Path]:
    """Every scenario this tree ships (the maps left out)."""
    return sorted(p for p in (ROOT / "scenarios").rglob("*.xml") if "maps" not in p.parts)


def variants(scenario: Path, folder: Path, runs: int) -> list[Path]:
    """The scenario's runs 0 .. runs - 1 as files in ``folder``, beside the documents they
    name (run 0 as written, the others jittered)."""
    from lxml import etree

    from prima.batch import bundle_scenario
    from prima.batch._variants import rng, shift_timings

    root = etree.fromstring(bundle_scenario(scenario).unpack(folder).read_bytes())
    out = []
    for i in range(runs):
        variant = copy.deepcopy(root)
        if i:
            shift_timings(variant, rng(SEED, i), JITTER)
        path = folder / f"run-{i}.xml"
        path.write_bytes(etree.tostring(variant, encoding="UTF-8", xml_declaration=True))
        out.append(path)
    return out


def hashes(tree: Path, paths: list[Path]) -> list[str]:
    """Each path's trace hash as the build in ``tree`` runs it, in a process of its own."""
    done = subprocess.run(in_checkout(tree, ["-c", _HASH, *map(str, paths)]),
                          capture_output=True, text=True, check=False, cwd=tree)
    if done.returncode != 0:
        sys.exit(f"{tree}: {done.stderr.strip().splitlines()[-1] if done.stderr else 'failed'}")
    found = json.loads(done.stdout)
    return [found[str(p)] for p in paths]


def compare(scenario: Path, tree: Path, runs: int) -> list[str]:
    """What differs between the two builds' runs of one scenario (one line each)."""
    theirs_source = in_tree(scenario, tree)
    if theirs_source is None:
        return [f"{scenario}: the other build has no such scenario"]
    with tempfile.TemporaryDirectory() as scratch:
        mine_dir, theirs_dir = Path(scratch, "this"), Path(scratch, "other")
        mine = hashes(ROOT, variants(scenario, mine_dir, runs))
        theirs = hashes(tree, variants(theirs_source, theirs_dir, runs))
    name = scenario.resolve().relative_to(ROOT) if scenario.resolve().is_relative_to(ROOT) \
        else scenario
    return [f"{name} run {i}: {a[:16]} here, {b[:16]} there"
            for i, (a, b) in enumerate(zip(mine, theirs, strict=True)) if _differ(a, b)]


def _differ(mine: str, theirs: str) -> bool:
    """Whether two runs' hashes differ: the traces', and the rows' where both builds
    make rows (an earlier build may not)."""
    a, _, a_rows = mine.partition(" rows ")
    b, _, b_rows = theirs.partition(" rows ")
    return a != b or bool(a_rows and b_rows and a_rows != b_rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="*", type=Path)
    other = parser.add_mutually_exclusive_group(required=True)
    other.add_argument("--against", type=Path, metavar="TREE",
                       help="a checkout of the other build")
    other.add_argument("--compiled", action="store_true",
                       help="the other build is this checkout's compiled one (built first "
                            "in a temporary copy: mypy, a C compiler and Python's headers)")
    parser.add_argument("--runs", type=int, default=40, help="runs per scenario (default 40)")
    parser.add_argument("--jobs", type=int, default=2, help="scenarios at once (default 2)")
    args = parser.parse_args(argv)
    if args.against is not None and not (args.against / "prima").is_dir():
        parser.error(f"--against {args.against}: not a checkout of prima")
    if args.runs < 1 or args.jobs < 1:
        parser.error("--runs and --jobs must be at least 1")
    scenarios = args.scenarios or shipped()
    with tempfile.TemporaryDirectory(prefix="prima-compiled-") as scratch:
        tree = compiled_copy(Path(scratch)) if args.compiled else args.against
        with ThreadPoolExecutor(args.jobs) as pool:
            found = list(pool.map(lambda s: compare(s, tree, args.runs), scenarios))
    differ = [line for lines in found for line in lines]
    for line in differ:
        print(line)
    total = len(scenarios) * args.runs
    print(f"{total:,} runs of {len(scenarios)} scenario(s): "
          + (f"{len(differ)} differ" if differ else "every trace the same in both builds"))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
