"""PRIMA's build backend: setuptools' own (``setuptools.build_meta``), which reads
pyproject.toml and setup.py, with one addition: with ``PRIMA_MYPYC=1`` in the
environment a wheel's build also needs what the compiled build (setup.py) compiles
with, so that one command builds it on a fresh machine, in pip's own build environment:

    PRIMA_MYPYC=1 python -m pip install .

mypyc type-checks what it compiles, as mypy does (pyproject.toml's settings, strict):
it needs mypy, the stubs of lxml, and PRIMA's own dependencies (the modules it compiles
import them). It also needs a C compiler and Python's headers, which no package brings
(Debian's ``gcc`` and ``python3-dev``). docs/judging.md (A compiled build) says more.
pyproject.toml names this module (``build-backend``, ``backend-path``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from setuptools import build_meta as _setuptools
from setuptools.build_meta import (  # noqa: F401 (the hooks this backend does not change)
    build_editable,
    build_sdist,
    build_wheel,
    get_requires_for_build_editable,
    get_requires_for_build_sdist,
    prepare_metadata_for_build_editable,
    prepare_metadata_for_build_wheel,
)

COMPILER = ["mypy>=1.10", "lxml-stubs>=0.5"]
"""What mypyc (part of mypy) needs besides PRIMA's dependencies: the same mypy as the
lint extra's, and lxml's stubs (lxml has no type information of its own)."""


def compiled() -> bool:
    """Whether this build is the compiled one (setup.py reads the same variable)."""
    return os.environ.get("PRIMA_MYPYC") == "1"


def dependencies() -> list[str]:
    """PRIMA's own dependencies, as pyproject.toml lists them (one list, not two)."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # (pyproject.toml's build-system requires tomli there)
        import tomli as tomllib
    with open(Path(__file__).with_name("pyproject.toml"), "rb") as file:
        project = tomllib.load(file)["project"]
    return list(project["dependencies"])


def get_requires_for_build_wheel(config_settings: dict[str, object] | None = None
                                 ) -> list[str]:
    """setuptools' requirements, and, for the compiled build, mypy's. (setuptools asks
    setup.py, which is told not to compile while it is asked: mypyc is not there yet.)"""
    if not compiled():
        return list(_setuptools.get_requires_for_build_wheel(config_settings))
    del os.environ["PRIMA_MYPYC"]
    try:
        needs = list(_setuptools.get_requires_for_build_wheel(config_settings))
    finally:
        os.environ["PRIMA_MYPYC"] = "1"
    return needs + COMPILER + dependencies()
