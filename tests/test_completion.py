"""Shell completion: commands, options, their values, policy names and files, as the
shell gets them from ``prima`` itself (argcomplete), and through bash for real."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from prima.cli import build_parser, main
from prima.completion import Files, attach
from prima.vocab import POLICIES

ROOT = Path(__file__).parents[1]
EVERY_POLICY = [f"{name}={state}" for name in ("all", *POLICIES) for state in ("on", "off")]


def _environment(**more: str) -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT), **more)
    for name in ("NO_COLOR", "FORCE_COLOR", "CLICOLOR_FORCE", "_ARC_DEBUG"):
        env.pop(name, None)
    return env


def complete(line: str, cwd: Path = ROOT) -> list[str]:
    """What ``prima`` offers the shell for ``line`` (the cursor at its end), asked as the
    shell asks it: ``prima`` run with argcomplete's variables."""
    fd, answer = tempfile.mkstemp()
    os.close(fd)
    try:
        subprocess.run([sys.executable, "-m", "prima"], cwd=cwd, check=True,
                       capture_output=True, env=_environment(
                           _ARGCOMPLETE="1", _ARGCOMPLETE_SHELL="bash",
                           _ARGCOMPLETE_SUPPRESS_SPACE="1", COMP_LINE=line,
                           COMP_POINT=str(len(line)), _ARGCOMPLETE_STDOUT_FILENAME=answer))
        said = Path(answer).read_text()
    finally:
        os.unlink(answer)
    return said.split("\v") if said else []


def test_commands() -> None:
    assert complete("prima ") == ["validate", "run", "debug", "test", "judge", "sweep",
                                  "check", "show", "plot", "live", "lsp", "completion"]
    assert complete("prima ju") == ["judge"]


@pytest.mark.parametrize("command", ["run", "debug", "test", "judge", "sweep", "show", "plot",
                                     "live"])
def test_policy_names(command: str) -> None:
    assert complete(f"prima {command} --policy ") == EVERY_POLICY
    assert complete(f"prima {command} --policy inter") == ["interrupt=on", "interrupt=off"]


def test_options_and_their_choices() -> None:
    assert complete("prima sweep --ji") == ["--jitter"]
    assert complete("prima run --format ") == ["text", "jsonl", "chrome-trace", "mcap"]
    assert complete("prima judge --max-s") == ["--max-splits", "--max-silences", "--max-stuck"]
    assert complete("prima --color ") == ["auto", "always", "never"]
    assert "--color" in complete("prima validate --c")


def test_files_of_the_kind_each_argument_takes(tmp_path: Path) -> None:
    for name in ("s.xml", "a.pxml", "t.jsonl", "p.svg", "notes.txt"):
        (tmp_path / name).write_text("")
    (tmp_path / "sub").mkdir()
    assert complete("prima run ", tmp_path) == ["s.xml", "sub/"]
    assert complete("prima run s.xml --fa ", tmp_path) == ["a.pxml", "sub/"]
    assert complete("prima validate ", tmp_path) == ["a.pxml", "s.xml", "sub/"]
    assert complete("prima judge ", tmp_path) == ["s.xml", "sub/", "t.jsonl"]
    assert complete("prima plot s.xml -o ", tmp_path) == ["p.svg", "sub/"]
    assert complete("prima sweep s.xml --out ", tmp_path) == ["sub/"]
    assert complete("prima run s.xml --robot su", tmp_path) == ["sub/"]
    assert complete("prima live ", tmp_path) == ["a.pxml", "s.xml", "sub/"]
    assert complete("prima live s.xml --save-dir ", tmp_path) == ["sub/"]


def test_every_argument_that_takes_a_file_or_a_policy_has_a_completer() -> None:
    parser = build_parser()
    attach(parser)
    takes = {"SCENARIO", "DOC", "PROFILE", "MAP", "RUN", "INPUT", "FILE", "DIR", "PATH",
             "NAME=on|off"}
    missing = [f"{name} {action.dest}"
               for name, sub in parser._subparsers._group_actions[0].choices.items()  # type: ignore[union-attr]
               for action in sub._actions
               if action.metavar in takes and not hasattr(action, "completer")]
    assert missing == []


def test_files_completes_inside_a_folder(tmp_path: Path) -> None:
    (tmp_path / "apps").mkdir()
    (tmp_path / "apps" / "x.pxml").write_text("")
    (tmp_path / "apps" / ".hidden.pxml").write_text("")
    prefix = str(tmp_path / "apps") + "/"
    assert Files(".pxml")(prefix) == [prefix + "x.pxml"]
    assert Files(".pxml")(prefix + ".") == [prefix + ".hidden.pxml"]
    assert Files(".pxml")(str(tmp_path / "nowhere") + "/") == []


@pytest.mark.parametrize("shell", ["bash", "zsh", "fish"])
def test_prima_completion_prints_the_shells_code(shell: str,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["completion", shell]) == 0
    code = capsys.readouterr().out
    assert "_ARGCOMPLETE" in code and "prima" in code


@pytest.mark.skipif(shutil.which("bash") is None, reason="no bash")
def test_bash_completes_the_policies(tmp_path: Path) -> None:
    """The acceptance: ``prima run --policy <TAB>`` in bash, with the code
    ``prima completion bash`` prints, lists the policies."""
    (tmp_path / "prima").write_text(f'#!/bin/sh\nexec "{sys.executable}" -m prima "$@"\n')
    (tmp_path / "prima").chmod(0o755)
    script = ('eval "$(prima completion bash)"\n'
              'for COMP_LINE in "prima run --policy " "prima run --policy interrupt="; do\n'
              '  COMP_POINT=${#COMP_LINE}; _python_argcomplete prima\n'
              '  echo "${COMPREPLY[*]}"\n'
              'done\n')
    done = subprocess.run(["bash", "--norc", "--noprofile", "-c", script], check=True,
                          capture_output=True, text=True, cwd=ROOT,
                          env=_environment(PATH=f"{tmp_path}{os.pathsep}{os.environ['PATH']}"))
    assert done.stdout.splitlines() == [" ".join(EVERY_POLICY), "on off"], done.stderr


def test_only_completing_imports_argcomplete() -> None:
    from tests.test_architecture import _imported_by

    for argv in (["--help"], ["validate", str(ROOT / "apps" / "fa" / "fa2-follow.pxml")]):
        status, modules = _imported_by(*argv)
        assert status == 0 and "argcomplete" not in modules and "prima.completion" not in modules
