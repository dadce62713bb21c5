"""The architecture's figures: modules and lines per package, import circles, upward
imports, long and complex functions, the command line's size and fan-out.

    python bench/architecture.py [CHECKOUT]

CHECKOUT (default: this one) is a checkout's root, so the figures of two commits can be
set side by side (``git worktree add /tmp/old COMMIT``). The import graph is read from
the source with :mod:`ast`, every import statement counted (at the top, inside
functions, under ``TYPE_CHECKING``): a circle that only a deferred import breaks is a
circle still. tests/test_architecture.py holds PRIMA to what it finds.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

LAYERS: dict[str, int] = {
    # 0: the shared vocabulary and helpers every layer may use
    **dict.fromkeys(("prima", "prima.record", "prima.vocab", "prima.errors", "prima.escape",
                     "prima.suggest", "prima.signals", "prima.term", "prima.shipped",
                     "prima.catalog", "prima.xmlio", "prima.tracefile", "prima.output",
                     "prima.completion", "prima.collecting", "prima.audio"), 0),
    # 1: the core: documents, their interpreter, the mediator, the simulated world
    **dict.fromkeys(("prima.dsl", "prima.interpreter", "prima.mediator", "prima.sim"), 1),
    # 2: a scenario made ready, run, and its trace
    **dict.fromkeys(("prima.scenario", "prima.trace", "prima.timeline", "prima.run"), 2),
    # 3: what reads runs and traces
    **dict.fromkeys(("prima.judge", "prima.chrome_trace", "prima.golden", "prima.debug",
                     "prima.plot", "prima.show", "prima.mcap"), 3),
    # 4: many runs, and the long-lived services
    **dict.fromkeys(("prima.batch", "prima.sweep", "prima.check", "prima.live", "prima.lsp",
                     "prima.pytest_plugin"), 4),
    # 5: the command line, which nothing imports
    **dict.fromkeys(("prima.cli", "prima.__main__"), 5),
}
"""Unit (a subpackage or a top-level module) -> its layer: a unit may import its own
layer and those below, never one above."""


@dataclass(frozen=True)
class Edge:
    importer: str
    line: int
    imported: str


def modules(root: Path) -> dict[str, Path]:
    """Every module of ``prima`` under the checkout ``root``, by dotted name."""
    found = {}
    for path in sorted((root / "prima").rglob("*.py")):
        parts = path.relative_to(root).with_suffix("").parts
        found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def unit(module: str) -> str:
    """The subpackage a module belongs to, or the top-level module itself; a
    subpackage's ``__main__`` (``python -m prima.sim``) is an entry point of its own."""
    parts = module.split(".")
    return module if len(parts) <= 2 or parts[-1] == "__main__" else ".".join(parts[:2])


def layer(name: str) -> int | None:
    """A unit's layer (every ``__main__`` is at the command line's), or None if it has
    none yet."""
    return LAYERS["prima.cli"] if name.endswith(".__main__") else LAYERS.get(name)


def _targets(node: ast.AST, package: str, known: dict[str, Path]) -> Iterator[str]:
    if isinstance(node, ast.Import):
        yield from (a.name for a in node.names if a.name in known)
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = package.split(".")[: len(package.split(".")) - node.level + 1]
            module = ".".join(base + ([node.module] if node.module else []))
        else:
            module = node.module or ""
        for alias in node.names:
            if f"{module}.{alias.name}" in known:
                yield f"{module}.{alias.name}"
            elif module in known:
                yield module


def edges(root: Path) -> list[Edge]:
    """Every import of one PRIMA module by another, where it is written."""
    known = modules(root)
    found = []
    for name, path in known.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            found += [Edge(name, getattr(node, "lineno", 0), t)
                      for t in _targets(node, package, known) if t != name]
    return found


def _graph(found: list[Edge], key: object = None) -> dict[str, set[str]]:
    graph: dict[str, set[str]] = defaultdict(set)
    for e in found:
        a, b = (unit(e.importer), unit(e.imported)) if key == "unit" else (e.importer,
                                                                           e.imported)
        if a != b:
            graph[a].add(b)
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import graph's strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10_000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def module_circles(root: Path) -> list[list[str]]:
    """Import circles between modules (inside a package or across packages)."""
    return circles(_graph(edges(root)))


def upward(root: Path) -> list[Edge]:
    """Imports from a lower layer to a higher one (units missing from LAYERS count as
    upward: a new unit must be given its layer)."""
    found = []
    for e in edges(root):
        below, above = layer(unit(e.importer)), layer(unit(e.imported))
        if unit(e.importer) != unit(e.imported) and (below if below is not None else -1) < (
                above if above is not None else 99):
            found.append(e)
    return found


def long_functions(root: Path, limit: int = 80) -> list[tuple[str, int]]:
    """Functions longer than ``limit`` lines (decorators and docstrings included)."""
    found = []
    for name, path in modules(root).items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = (node.end_lineno or node.lineno) - node.lineno + 1
                if length > limit:
                    found.append((f"{name}.{node.name}", length))
    return sorted(found)


def complex_functions(root: Path, limit: int = 20) -> list[str]:
    """Functions of cyclomatic complexity over ``limit``, as ruff's mccabe counts it."""
    done = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--select", "C901", "--output-format",
         "concise", "--config", f"lint.mccabe.max-complexity={limit}", "--no-cache",
         "--isolated", "prima"], cwd=root, capture_output=True, text=True, check=False)
    return [line for line in done.stdout.splitlines() if "C901" in line]


def sizes(root: Path) -> dict[str, tuple[int, int]]:
    """Unit -> (modules, lines)."""
    table: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    for name, path in modules(root).items():
        row = table[unit(name)]
        row[0] += 1
        row[1] += len(path.read_text(encoding="utf-8").splitlines())
    return {k: (v[0], v[1]) for k, v in sorted(table.items())}


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    root = Path(args[0] if args else Path(__file__).resolve().parents[1]).resolve()
    table = sizes(root)
    print(f"modules {sum(m for m, _ in table.values())}, "
          f"lines {sum(n for _, n in table.values())}")
    for name, (count, lines) in table.items():
        print(f"  {name:24} {count:3} modules {lines:6} lines")
    found = module_circles(root)
    print(f"import circles (modules): {len(found)}")
    for c in found:
        print("  " + " <-> ".join(c))
    units = circles(_graph(edges(root), "unit"))
    print(f"import circles (packages): {len(units)}")
    for c in units:
        print("  " + " <-> ".join(c))
    up = upward(root)
    print(f"upward imports: {len(up)}")
    for e in up:
        print(f"  {e.importer}:{e.line} -> {e.imported}")
    long = long_functions(root)
    print(f"functions over 80 lines: {len(long)}")
    for name, length in long:
        print(f"  {name} ({length})")
    complex_ = complex_functions(root)
    print(f"functions over complexity 20: {len(complex_)}")
    for line in complex_:
        print("  " + line)
    cli = [(n, p) for n, p in modules(root).items() if unit(n) == "prima.cli"]
    fan = {unit(e.imported) for e in edges(root) if unit(e.importer) == "prima.cli"}
    print(f"cli: {len(cli)} modules, {sum(len(p.read_text().splitlines()) for _, p in cli)} "
          f"lines, largest {max(len(p.read_text().splitlines()) for _, p in cli)}, "
          f"imports {len(fan - {'prima.cli'})} units")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
