"""The package's boundary: a public API, private modules, no mediator underneath."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

import prima.dsl
from prima.errors import PrimaError

ROOT = Path(__file__).parents[2]


def test_public_api_names_exist() -> None:
    missing = [name for name in prima.dsl.__all__ if not hasattr(prima.dsl, name)]
    assert missing == []
    assert sorted(prima.dsl.__all__) == sorted(set(prima.dsl.__all__))


def test_loading_documents_does_not_import_the_other_packages() -> None:
    code = ("import sys, prima.dsl; "
            "print(' '.join(m for m in sys.modules if m.startswith('prima.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert [m for m in out if m.split(".")[1] in ("mediator", "interpreter", "sim")] == []


def test_nothing_outside_the_package_imports_its_private_modules() -> None:
    private = re.compile(r"^\s*(from|import)\s+prima\.dsl\._", re.M)
    dsl = ROOT / "prima" / "dsl"
    offenders = [str(path.relative_to(ROOT))
                 for folder in ("prima", "tests", "bench") for path in (ROOT / folder).rglob("*.py")
                 if dsl not in path.parents and private.search(path.read_text(encoding="utf-8"))]
    assert offenders == []


def test_a_missing_path_is_a_prima_error_and_a_file_not_found_error(tmp_path: Path) -> None:
    with pytest.raises(PrimaError) as info:
        prima.dsl.collect([tmp_path / "no-such-file.pxml"])
    assert isinstance(info.value, FileNotFoundError)
