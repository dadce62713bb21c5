"""What ships with PRIMA besides its code: the applications (``apps/fa``, ``apps/ea``),
the robot profiles (``robots/``), the scenarios and their maps (``scenarios/``) and the
schemas (``schemas/``), each a package of data (``prima.apps``, ``prima.robots``,
``prima.scenarios``, ``prima.schemas``) found in the package's folder (:func:`packaged`).

A checkout keeps these folders at its top; an install keeps them in the package, beside
one another as in the checkout (``prima/apps``, ``prima/scenarios``, ...), so a scenario's
``../../apps/fa/fa2-follow.pxml`` names the same FA in both. An editable install finds
them in the checkout, a wheel in the install: the answers below are the same either way.

A command line names them as a checkout does (``scenarios/thesis/sample-03.xml``,
``apps/fa/fa2-follow.pxml``), or an application, a robot or a map by its name
(``--fa fa2-follow``, ``--robot guide-robot``, ``--map museum``): :func:`locate` says
which file that is when the current folder has no such file (docs/cli.md, What ships
with PRIMA).
"""

from __future__ import annotations

import importlib
from pathlib import Path

__all__ = ["FOLDERS", "NAMED", "locate", "packaged", "shipped"]

FOLDERS = {"apps": "prima.apps", "robots": "prima.robots", "scenarios": "prima.scenarios",
           "schemas": "prima.schemas"}
"""Each shipped folder, as a checkout's top names it, and the package that holds it."""

NAMED = {"fa": ("apps/fa", ".pxml"), "ea": ("apps/ea", ".pxml"), "robot": ("robots", ".xml"),
         "map": ("scenarios/maps", ".xml")}
"""What a bare name names, by kind: ``--fa fa2-follow`` is ``apps/fa/fa2-follow.pxml``."""


def packaged(package: str, *names: str) -> Path:
    """The file ``names`` in the folder of one of PRIMA's packages
    (``packaged("prima.schemas", "pxml.xsd")``), on disk: the file
    :func:`importlib.resources.files` names. PRIMA is installed as files (by pip, or as
    an editable install of a checkout), never run from a zip archive, so the package's
    folder is enough; importing :mod:`importlib.resources` would cost every command
    about 6 ms of its start (it brings :mod:`tempfile`, :mod:`shutil` and
    :mod:`zipfile`). Raises :class:`ModuleNotFoundError` for an install without that
    package."""
    return Path(next(iter(importlib.import_module(package).__path__))).joinpath(*names)


def shipped(*parts: str) -> Path | None:
    """The shipped file or folder at ``parts`` (``shipped("apps", "fa")``,
    ``shipped("scenarios/maps")``), or None when this install has no such thing.
    Named relative to the current folder when it is inside it (a checkout: messages
    then say ``apps/fa/fa2-follow.pxml``, not where the checkout is)."""
    names = [name for part in parts for name in Path(part).parts]
    if not names or names[0] not in FOLDERS or ".." in names:
        return None
    try:
        path = packaged(FOLDERS[names[0]], *names[1:])
    except ModuleNotFoundError:  # (an install without that folder's package)
        return None
    if not _exists(path):
        return None
    try:
        return path.relative_to(Path.cwd())
    except ValueError:
        return path


def locate(text: str, kind: str | None = None) -> str:
    """What a path given on a command line names: ``text`` itself when it exists (the
    current folder's own file comes first); else the shipped file or folder at that
    path (``scenarios/thesis/sample-03.xml``); else, for a ``kind`` of :data:`NAMED`,
    the shipped one of that name (``fa2-follow``); else ``text`` unchanged, for the
    command to say there is no such file."""
    given = Path(text)
    if _exists(given) or given.is_absolute():
        return text
    found = shipped(text)
    if found is None and kind in NAMED and len(given.parts) == 1 and not given.suffix:
        folder, suffix = NAMED[kind]
        found = shipped(folder, text + suffix)
    return str(found) if found is not None else text


def _exists(path: Path) -> bool:
    """Whether ``path`` names something; a name the system cannot even look up (too long,
    a NUL in it) names nothing, and the command says there is no such file."""
    try:
        return path.exists()
    except (OSError, ValueError):
        return False
