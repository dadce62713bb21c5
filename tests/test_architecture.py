"""The architecture, checked: packages meet only through each other's public API.

Walks every import statement in ``prima/`` (including imports inside
functions) and checks that:

- a module imports another subpackage only as the package itself
  (``from prima.mediator import Call``), never one of its modules;
- no module imports a private name (``_name``) or a private module from
  another package;
- imports go in the designed direction: the mediator knows neither the DSL,
  the interpreter nor the simulator; the simulator knows no documents; the DSL
  knows no mediator;
- the shared vocabulary modules import nothing heavy;
- every subpackage names its public API in ``__all__``, and it all exists;
- a command imports only what it needs: ``prima --help`` nothing heavy,
  ``prima validate`` of a document no simulator;
- there is no import circle anywhere, between packages or between the modules of one
  (every import counted, deferred or under ``TYPE_CHECKING`` too), no import runs up
  the layers (bench/architecture.py's ``LAYERS``: the shared vocabulary, the core,
  scenario and run, what reads runs, many runs and the services, the command line),
  and nothing imports the command line.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import pytest

import prima

ROOT = Path(prima.__file__).parent
SUBPACKAGES = sorted(p.name for p in ROOT.iterdir() if (p / "__init__.py").exists())
NEUTRAL = ("prima.record", "prima.vocab", "prima.catalog", "prima.errors", "prima.escape",
           "prima.suggest", "prima.signals", "prima.term", "prima.shipped")
LIGHT = ("prima.judge", "prima.judge._thresholds")
"""What `prima --help` may import beyond the CLI and the neutral modules: the table of
thresholds its commands' options are made from."""
HEAVY = {"lxml", "lark", "pymunk", "xmlschema"}

FORBIDDEN: dict[str, set[str]] = {
    "prima.mediator": {"prima.dsl", "prima.interpreter", "prima.sim", "prima.run", "prima.trace",
                       "prima.cli", "prima.xmlio", "prima.term", "prima.scenario"},
    "prima.sim": {"prima.dsl", "prima.interpreter", "prima.run", "prima.trace", "prima.cli",
                  "prima.term", "prima.scenario"},
    "prima.dsl": {"prima.mediator", "prima.interpreter", "prima.sim", "prima.run",
                  "prima.trace", "prima.cli", "prima.term"},
    "prima.interpreter": {"prima.sim", "prima.run", "prima.trace", "prima.cli", "prima.term"},
}
"""Importer unit -> PRIMA units it must not import (the core knows no terminal)."""

ONLY: dict[str, set[str]] = {
    "prima.record": set(),
    "prima.vocab": {"prima.record"},
    "prima.errors": {"prima.record"},
    "prima.catalog": {"prima.record", "prima.vocab"},
    "prima.xmlio": {"prima.errors", "prima.record", "prima.suggest", "prima.shipped"},
    "prima.escape": set(),
    "prima.suggest": set(),
    "prima.signals": set(),
    "prima.term": {"prima.escape", "prima.record"},
    "prima.shipped": set(),
}
"""Shared modules -> the only PRIMA units they may import."""


def _graph() -> ModuleType:
    """bench/architecture.py, which measures what these tests hold PRIMA to."""
    path = ROOT.parent / "bench" / "architecture.py"
    spec = importlib.util.spec_from_file_location("architecture_bench", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclasses look their module up)
    spec.loader.exec_module(module)
    return module


GRAPH = _graph()


@dataclass(frozen=True)
class Import:
    importer: str
    line: int
    module: str
    names: tuple[str, ...]


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports() -> list[Import]:
    found = []
    for path in sorted(ROOT.rglob("*.py")):
        name = _module_name(path)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found += [Import(name, node.lineno, a.name, ()) for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                found.append(Import(name, node.lineno, node.module,
                                    tuple(a.name for a in node.names)))
    return found


IMPORTS = _imports()


def unit(module: str) -> str:
    """The package a module belongs to, or the top-level module itself; a package's
    ``__main__`` (``python -m prima.sim``) is an entry point, a unit of its own."""
    parts = module.split(".")
    if parts[0] != "prima" or len(parts) == 1 or parts[-1] == "__main__":
        return module
    return "prima." + parts[1]


def test_the_walk_sees_the_packages_and_their_imports() -> None:
    assert {"dsl", "interpreter", "mediator", "sim"} <= set(SUBPACKAGES)
    assert any(i.importer == "prima.run" and i.module == "prima.mediator" for i in IMPORTS)


def test_packages_are_imported_only_through_their_public_api() -> None:
    bad = []
    for i in IMPORTS:
        target = unit(i.module)
        if not i.module.startswith("prima.") or target == unit(i.importer):
            continue
        if target.split(".")[1] in SUBPACKAGES and i.module != target:
            bad.append(f"{i.importer}:{i.line} imports {i.module} (use {target})")
        if any(part.startswith("_") for part in i.module.split(".")):
            bad.append(f"{i.importer}:{i.line} imports the private module {i.module}")
        bad += [f"{i.importer}:{i.line} imports the private name {n} from {i.module}"
                for n in i.names if n.startswith("_")]
    assert bad == []


def test_imports_go_in_the_designed_direction() -> None:
    bad = []
    for i in IMPORTS:
        src, target = unit(i.importer), unit(i.module)
        if not target.startswith("prima.") or target == src:
            continue
        if target in FORBIDDEN.get(src, ()) or (src in ONLY and target not in ONLY[src]):
            bad.append(f"{i.importer}:{i.line} imports {i.module}")
    assert bad == []


@pytest.mark.parametrize("module", sorted(NEUTRAL))
def test_the_shared_vocabulary_imports_nothing_heavy(module: str) -> None:
    heavy = [i for i in IMPORTS if i.importer == module and i.module.split(".")[0] in HEAVY]
    assert heavy == []


@pytest.mark.parametrize("package", SUBPACKAGES)
def test_every_package_names_its_public_api(package: str) -> None:
    module = importlib.import_module(f"prima.{package}")
    names = getattr(module, "__all__", None)
    assert names, f"prima.{package} has no __all__"
    assert [n for n in names if not hasattr(module, n)] == []
    assert [n for n in names if n.startswith("_")] == []


def test_the_mediator_is_one_class_without_mixins() -> None:
    from prima.mediator import Mediator

    assert Mediator.__mro__ == (Mediator, object)


_IMPORTED_AFTER = """
import contextlib, io, sys
from prima.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    status = main(sys.argv[1:])
print(status, *sorted(sys.modules))
"""


def _imported_by(*argv: str) -> tuple[int, set[str]]:
    """The exit status of ``prima ARGV`` in a fresh interpreter, and the modules it imported."""
    done = subprocess.run([sys.executable, "-c", _IMPORTED_AFTER, *argv], capture_output=True,
                          text=True, check=True)
    status, *modules = done.stdout.split()
    return int(status), set(modules)


def _roots(modules: set[str]) -> set[str]:
    return {m.split(".")[0] for m in modules}


def test_prima_help_imports_nothing_heavy() -> None:
    status, modules = _imported_by("--help")
    assert status == 0
    assert _roots(modules) & HEAVY == set()
    assert {m for m in modules if m.startswith("prima.") and unit(m) != "prima.cli"} \
        <= {*NEUTRAL, *LIGHT}


def test_the_prima_process_leaves_what_python_made_at_start_to_no_collection() -> None:
    """(gc.freeze: 2% of a cold ``prima validate``, bench/cold.py)"""
    code = ("import gc, sys\nsys.argv = ['prima', '--version']\n"
            "from prima.__main__ import main\nmain()\nprint(gc.get_freeze_count())")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert int(done.stdout.split()[-1]) > 1_000


def test_running_valid_documents_imports_no_lark() -> None:
    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "thesis" / "sample-03.xml"
    status, modules = _imported_by("run", str(scenario))
    assert status == 0
    assert "prima.run" in modules and "pymunk" in modules  # it did run
    assert "lark" not in _roots(modules)


def test_a_syntax_fault_is_worded_by_lark(tmp_path: Path) -> None:
    app = Path(__file__).resolve().parents[1] / "apps" / "fa" / "fa2-follow.pxml"
    text = app.read_text(encoding="utf-8")
    bad = tmp_path / "bad.pxml"
    bad.write_text(text.replace('cond="', 'cond="(', 1), encoding="utf-8")
    status, modules = _imported_by("validate", str(bad))
    assert status == 1
    assert "lark" in _roots(modules)


def test_validating_a_document_imports_no_simulator_mediator_or_interpreter() -> None:
    app = Path(__file__).resolve().parents[1] / "apps" / "fa" / "fa2-follow.pxml"
    status, modules = _imported_by("validate", str(app))
    assert status == 0
    assert "prima.dsl._expr" in modules and "lxml" in modules  # the check did run
    # lark words syntax faults and xmlschema schema faults: a valid document needs neither
    assert _roots(modules) & {"pymunk", "xmlschema", "lark"} == set()
    assert {unit(m) for m in modules} & {"prima.sim", "prima.mediator",
                                         "prima.interpreter", "prima.run"} == set()
    # its schemas and its robot found in their packages' folders (prima.shipped.packaged):
    # importlib.resources would bring these, about 6 ms of a cold start
    assert modules & {"importlib.resources", "tempfile", "zipfile"} == set()


def test_prima_version_imports_no_command() -> None:
    status, modules = _imported_by("--version")
    assert status == 0
    assert {m for m in modules if m.startswith("prima.cli._")} <= {
        "prima.cli._main", "prima.cli._common", "prima.cli._options"}
    assert "prima.judge" not in modules


def test_a_command_imports_no_other_commands_module() -> None:
    app = Path(__file__).resolve().parents[1] / "apps" / "fa" / "fa2-follow.pxml"
    status, modules = _imported_by("validate", str(app))
    assert status == 0
    commands = {m for m in modules if m.startswith("prima.cli._")} - {
        "prima.cli._main", "prima.cli._common", "prima.cli._options"}
    assert commands == {"prima.cli._validate"}
    assert {"prima.judge", "urllib.request", "http.client"} & modules == set()


def test_every_package_is_installed() -> None:
    """A non-editable install ships only the packages pyproject.toml lists."""
    import tomllib

    listed = set(tomllib.loads((ROOT.parent / "pyproject.toml").read_text())
                 ["tool"]["setuptools"]["packages"])
    found = {"prima", *(f"prima.{name}" for name in SUBPACKAGES)}
    assert found <= listed


def test_the_compiled_build_compiles_modules_that_are_there() -> None:
    """setup.py's list for the compiled build (PRIMA_MYPYC=1) names existing modules."""
    tree = ast.parse((ROOT.parent / "setup.py").read_text())
    compiled = next(ast.literal_eval(node.value) for node in tree.body
                    if isinstance(node, ast.Assign)
                    and [getattr(t, "id", None) for t in node.targets] == ["COMPILED"])
    assert compiled and all((ROOT.parent / path).is_file() for path in compiled)
    assert "prima/trace.py" in compiled  # (what prima.compiled() looks at)


def test_there_is_no_import_circle() -> None:
    """Between packages and between the modules of one: a circle that a deferred import
    or ``TYPE_CHECKING`` hides is a circle still (the mediator's parts reach its
    configuration in a module of its own; behaviours and the scripted user are given a
    narrow interface, not the simulator)."""
    assert GRAPH.module_circles(ROOT.parent) == []


def test_no_import_runs_up_the_layers() -> None:
    assert [f"{e.importer}:{e.line} imports {e.imported}"
            for e in GRAPH.upward(ROOT.parent)] == []


def test_every_unit_has_its_layer() -> None:
    units = {GRAPH.unit(name) for name in GRAPH.modules(ROOT.parent)}
    assert sorted(u for u in units if GRAPH.layer(u) is None) == []


def test_nothing_imports_the_command_line() -> None:
    """Only the entry points (``python -m prima``) import ``prima.cli``: the library
    (the language server included) reaches what a command does through the library."""
    bad = [f"{e.importer}:{e.line}" for e in GRAPH.edges(ROOT.parent)
           if GRAPH.unit(e.imported) == "prima.cli" and GRAPH.unit(e.importer) != "prima.cli"
           and not e.importer.endswith("__main__")]
    assert bad == []


def test_the_graph_sees_deferred_and_type_only_imports() -> None:
    """The walk finds an import inside a function and one under ``TYPE_CHECKING``."""
    found = {(e.importer, e.imported) for e in GRAPH.edges(ROOT.parent)}
    assert ("prima.sim._simulator", "prima.sim._setting") in found  # TYPE_CHECKING
    assert ("prima.lsp._workspace", "prima.scenario") in found  # inside a function


def test_no_function_is_over_80_lines() -> None:
    """A function reads on one screen; complexity has its own gate (ruff's mccabe, at
    15 in pyproject.toml: over it, the gate fails)."""
    assert GRAPH.long_functions(ROOT.parent, 80) == []


def test_the_architecture_page_shows_every_unit_in_its_layer() -> None:
    """docs/architecture.md's picture names every package and module the layers give."""
    text = (ROOT.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    picture = text.split("## Layers", 1)[1].split("```")[1]
    shown = {name: n for n, line in enumerate(picture.splitlines())
             for name in GRAPH.LAYERS if name != "prima"
             and (name.split(".")[-1] in line.replace("/", " ").split()
                  or name.replace(".", "/") + ".py" in line)}
    assert sorted(set(GRAPH.LAYERS) - {"prima"} - set(shown)) == []
