"""Run a command with the build of another checkout, wholly on its own files.

Usage: python bench/_tree.py TREE SCRIPT [ARG ...]
       python bench/_tree.py TREE -m MODULE [ARG ...]
       python bench/_tree.py TREE -c CODE [ARG ...]

``PYTHONPATH=TREE`` alone does not do it where this checkout is installed editable
(``pip install -e .``): the install's import hook maps ``prima.robots``,
``prima.schemas``, ``prima.apps`` and ``prima.scenarios`` to this checkout's
``robots/``, ``schemas/``, ``apps/`` and ``scenarios/`` (a checkout has no
``prima/robots``: its ``pyproject.toml`` maps those packages to folders beside
``prima/``), so an earlier build ran with today's robot profiles and schemas, or
crashed on them. Here the editable install's hooks are taken out, and each package
that TREE's own ``pyproject.toml`` maps (``[tool.setuptools.package-dir]``) is found
in TREE, as an install of TREE would find it; then the command runs as ``python``
would run it (``sys.argv`` and ``sys.path[0]`` as it sets them). Used by every
benchmark that runs another build (:func:`_measure.in_checkout`).
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import re
import runpy
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType


def package_dirs(tree: Path) -> dict[str, Path]:
    """The packages ``tree``'s ``pyproject.toml`` maps to folders, and those folders
    (``prima`` is ``tree/prima`` whatever it says; without a ``pyproject.toml``, the
    data packages are the folders of today's layout that the tree has)."""
    dirs = {"prima": tree / "prima"}
    for name in ("apps", "robots", "scenarios", "schemas"):  # (the layout, when it says none)
        if (tree / name).is_dir():
            dirs[f"prima.{name}"] = tree / name
    try:
        text = (tree / "pyproject.toml").read_text(encoding="utf-8")
    except OSError:
        return dirs
    section = re.search(r"^\[tool\.setuptools\.package-dir\]\s*$(.*?)(?=^\[|\Z)", text,
                        re.MULTILINE | re.DOTALL)
    if section is not None:
        for name, folder in re.findall(r'^\s*"([\w.]+)"\s*=\s*"([^"]*)"', section.group(1),
                                       re.MULTILINE):
            dirs[name] = tree / folder
    return dirs


class _TreeFinder(importlib.abc.MetaPathFinder):
    """Finds each mapped package in its folder of the tree (a namespace package when the
    folder has no ``__init__.py``, as the import system makes one), and a compiled
    build's shared runtime (mypyc's ``<hash>__mypyc`` extension, which a build in place
    leaves at the tree's top, beside ``prima/``: every compiled module imports it)."""

    def __init__(self, tree: Path, dirs: dict[str, Path]) -> None:
        self.tree = tree
        self.dirs = dirs

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        if fullname.endswith("__mypyc") and "." not in fullname:
            return importlib.machinery.PathFinder.find_spec(fullname, [str(self.tree)])
        folder = self.dirs.get(fullname)
        if folder is None:
            return None
        # (the path finder looks for the name's last part in the folder's parent; the
        # folder's own name may differ: "prima.robots" is "robots/")
        tail = fullname.rpartition(".")[2]
        if folder.name == tail:
            return importlib.machinery.PathFinder.find_spec(fullname, [str(folder.parent)])
        init = folder / "__init__.py"
        if init.exists():
            return importlib.util.spec_from_file_location(
                fullname, init, submodule_search_locations=[str(folder)])
        spec = importlib.machinery.ModuleSpec(fullname, None, is_package=True)
        spec.submodule_search_locations = [str(folder)]  # (a namespace package)
        return spec


def isolate(tree: Path) -> None:
    """Make this process import PRIMA from ``tree`` only."""
    sys.meta_path[:] = [f for f in sys.meta_path
                        if not getattr(f, "__module__", "").startswith("__editable__")]
    sys.path_hooks[:] = [h for h in sys.path_hooks
                         if not getattr(h, "__module__", "").startswith("__editable__")]
    sys.path[:] = [p for p in sys.path if not p.startswith("__editable__")]
    sys.path_importer_cache.clear()
    for name in [n for n in sys.modules if n == "prima" or n.startswith("prima.")]:
        del sys.modules[name]
    sys.meta_path.insert(0, _TreeFinder(tree, package_dirs(tree)))


def main(argv: list[str]) -> None:
    if len(argv) < 2:
        sys.exit(__doc__)
    tree = Path(argv[0]).resolve()
    isolate(tree)
    if argv[1] == "-m":
        sys.argv = [argv[2], *argv[3:]]
        sys.path[0] = str(Path.cwd())
        runpy.run_module(argv[2], run_name="__main__", alter_sys=True)
    elif argv[1] == "-c":
        sys.argv = ["-c", *argv[3:]]
        sys.path[0] = ""
        exec(compile(argv[2], "<string>", "exec"), {"__name__": "__main__"})  # noqa: S102
    else:
        script = Path(argv[1]).resolve()
        sys.argv = [str(script), *argv[2:]]
        sys.path[0] = str(script.parent)
        runpy.run_path(str(script), run_name="__main__")


if __name__ == "__main__":
    main(sys.argv[1:])
