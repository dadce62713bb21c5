"""PRIMA as a user installs it: its wheel, built from this checkout, installed into a
fresh virtual environment outside the checkout, and the documented commands run there
on what ships in it: ``prima check`` of a shipped EA (beside every shipped FA, on every
shipped robot, on the shipped maps), ``prima run`` of a shipped scenario (and ``prima
test`` of it against its shipped golden trace), ``prima show`` of its trace and ``prima
lsp`` answering an editor's first request.

No network (the tests run where there is none): the wheel is built by pip with this
environment's setuptools (``--no-build-isolation``: no build environment of pip's own,
which would download setuptools) and installed with ``--no-index --no-deps``. The fresh
environment then borrows this one's installed copies of PRIMA's dependencies through a
``.pth`` file, written after the install so that pip never sees them. (``venv
--system-site-packages`` would not do: a virtual environment made from inside another
one sees the base interpreter's packages, not that one's.) The borrowed folders come
after the fresh environment's own, so ``prima`` is imported from the wheel, which the
tests check, and never from the checkout.

Slow (about a minute): ``-m 'not slow'`` leaves it out; the full suite and CI run it.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
import venv
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from prima.cli import main
from prima.shipped import FOLDERS

ROOT = Path(__file__).resolve().parents[1]

pytestmark = [pytest.mark.slow, pytest.mark.pure]  # (pure: it builds its own copy of PRIMA)

EXTRAS = ("show", "lsp")
"""The extras the commands below need besides PRIMA's own dependencies."""


@dataclass(frozen=True)
class Install:
    bin: Path
    site: Path
    """The fresh environment's site-packages, where the wheel put ``prima``."""
    home: Path
    """A folder outside the checkout, where the commands run."""

    def run(self, *args: str, stdin: bytes | None = None) -> subprocess.CompletedProcess[bytes]:
        env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
        env["PATH"] = f"{self.bin}{os.pathsep}{env.get('PATH', '')}"
        return subprocess.run([str(self.bin / args[0]), *args[1:]], cwd=self.home, env=env,
                              input=stdin, capture_output=True, timeout=600, check=False)


def _source(folder: Path) -> Path:
    """This checkout's files (those git tracks or would, else the tree without what a
    build or a run leaves), copied to ``folder``: the build writes there, not here."""
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                             "--exclude-standard"], cwd=ROOT, capture_output=True, check=False)
    if listed.returncode != 0:
        shutil.copytree(ROOT, folder, ignore=shutil.ignore_patterns(
            ".git", "__pycache__", "*.so", "build", "*.egg-info", ".*_cache"))
        return folder
    for name in (n.decode() for n in listed.stdout.split(b"\0") if n):
        if (ROOT / name).is_file():
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, folder / name)
    return folder


def _borrowed() -> list[str]:
    """The folders this environment's copies of PRIMA's dependencies (with the extras the
    commands need) are installed in: what the fresh environment's ``.pth`` file adds."""
    wanted = []
    for text in importlib.metadata.requires("prima") or []:
        name, _, marker = text.partition(";")
        extra = re.search(r"extra\s*==\s*['\"]([\w-]+)['\"]", marker)
        if extra is None or extra.group(1) in EXTRAS:
            wanted.append(re.split(r"[\s\[<>=!~]", name.strip(), maxsplit=1)[0])
    folders = {str(importlib.metadata.distribution(n).locate_file("")) for n in wanted}
    return sorted(folders)


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Install]:
    base = tmp_path_factory.mktemp("wheel")
    source = _source(base / "source")
    wheels = base / "wheels"
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps",
                            "--no-build-isolation", "--no-index", "-w", str(wheels), "."],
                           cwd=source, capture_output=True, text=True, check=False)
    assert built.returncode == 0, built.stdout + built.stderr
    (wheel,) = wheels.glob("prima-*.whl")
    env = base / "env"
    venv.create(env, with_pip=True)  # (ensurepip: pip's own copy, no download)
    bin_ = env / ("Scripts" if os.name == "nt" else "bin")
    python = bin_ / "python"
    done = subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-index",
                           "--no-deps", str(wheel)], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; "
                                "print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    (site / "borrowed-from-the-tests.pth").write_text("\n".join(_borrowed()) + "\n")
    home = base / "elsewhere"
    home.mkdir()
    yield Install(bin_, site, home)


def _text(done: subprocess.CompletedProcess[bytes]) -> str:
    return done.stdout.decode() + done.stderr.decode()


def test_prima_is_imported_from_the_wheel(installed: Install) -> None:
    done = installed.run("python", "-c", "import prima; print(prima.__file__)")
    assert done.returncode == 0, _text(done)
    assert Path(done.stdout.decode().strip()).parent == installed.site / "prima"
    assert installed.run("prima", "--version").stdout.decode().strip() == "prima 0.1.0"


def test_every_shipped_file_is_in_the_wheel(installed: Install) -> None:
    """What a checkout ships beside the code (apps/, robots/, scenarios/, schemas/) is
    in the install, file for file, where prima.shipped finds it."""
    for folder in FOLDERS:
        def files(top: Path) -> set[str]:
            return {str(p.relative_to(top)) for p in top.rglob("*")
                    if p.is_file() and p.suffix not in (".py", ".pyc")}
        assert files(ROOT / folder) == files(installed.site / "prima" / folder), folder


def test_check_of_a_shipped_ea_says_what_it_says_in_a_checkout(
        installed: Install, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """Every shipped FA, every shipped robot, a shipped map: the same check, word for word
    (the install's paths aside), as in the checkout."""
    args = ["check", "apps/ea/cafe.pxml", "--runs", "2", "--jobs", "1", "--worst", "0"]
    done = installed.run("prima", *args)
    assert done.returncode == 0, _text(done)
    monkeypatch.chdir(ROOT)
    assert main(args) == 0
    here = capsys.readouterr().out
    assert "cafe beside 8 FA(s) on 2 robot(s)" in here
    there = done.stdout.decode().replace(f"{installed.site / 'prima'}{os.sep}", "")
    assert _untimed(there) == _untimed(here)


def _untimed(text: str) -> str:
    """A check's output without the CPU time each cell's runs took (it varies)."""
    return re.sub(r"judged, [0-9.]+ s", "judged, N s", text)


def test_run_test_and_show_of_a_shipped_scenario(installed: Install) -> None:
    scenario = "scenarios/thesis/sample-03.xml"
    done = installed.run("prima", "run", scenario, "-o", "sample-03.jsonl")
    assert done.returncode == 0, _text(done)
    assert (installed.home / "sample-03.jsonl").stat().st_size > 0
    # the same trace as the checkout's golden one, which ships beside it
    done = installed.run("prima", "test", scenario)
    assert done.returncode == 0 and done.stdout.decode().startswith("same "), _text(done)
    # an FA by its name, as --fa takes a shipped one
    done = installed.run("prima", "run", scenario, "--fa", "fa1-emotions", "--until", "5")
    assert done.returncode == 0 and "fa1-emotions" in done.stdout.decode(), _text(done)
    done = installed.run("prima", "show", "sample-03.jsonl", "--scenario", scenario,
                         "-o", "sample-03.html")
    assert done.returncode == 0, _text(done)
    page = (installed.home / "sample-03.html").read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "Prof. Kidode" in page


def _framed(*messages: dict[str, object]) -> bytes:
    out = b""
    for message in messages:
        body = json.dumps(message).encode()
        out += b"Content-Length: %d\r\n\r\n" % len(body) + body
    return out


def _unframed(data: bytes) -> list[dict[str, object]]:
    found = []
    while data:
        head, _, rest = data.partition(b"\r\n\r\n")
        length = int(re.search(rb"Content-Length: (\d+)", head).group(1))  # type: ignore[union-attr]
        found.append(json.loads(rest[:length]))
        data = rest[length:]
    return found


def test_lsp_answers_an_editors_first_request(installed: Install) -> None:
    done = installed.run("prima", "lsp", stdin=_framed(
        {"jsonrpc": "2.0", "id": 1, "method": "initialize",
         "params": {"processId": None, "rootUri": None, "capabilities": {}}},
        {"jsonrpc": "2.0", "method": "initialized", "params": {}},
        {"jsonrpc": "2.0", "id": 2, "method": "shutdown", "params": None},
        {"jsonrpc": "2.0", "method": "exit", "params": None}))
    assert done.returncode == 0, _text(done)
    answers = {m.get("id"): m for m in _unframed(done.stdout)}
    capabilities = answers[1]["result"]["capabilities"]  # type: ignore[index]
    assert "completionProvider" in capabilities and "hoverProvider" in capabilities
    assert answers[2]["result"] is None
