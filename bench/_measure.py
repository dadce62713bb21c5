"""How every benchmark in bench/ measures: CPU time, medians, interleaved repeats.

This machine is noisy (absolute figures drift by 40%), so a benchmark never
reports one timing of one case. It runs each case of a comparison once per
round, round after round (``interleaved``), so that a slow spell of the machine
falls on every case alike; it reports the median CPU time of each case; and it
prints each case as a ratio to a peer measured in the same rounds, which is
the figure that stays put from one machine state to the next.

CPU time, not wall time: ``time.process_time`` for work done in this process,
and the children's user + system time (``resource.getrusage``) for a cold
process started with :func:`child_cpu`.
"""

from __future__ import annotations

import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

try:
    import prima  # noqa: F401
except ModuleNotFoundError:  # running from a checkout without installing
    sys.path.insert(0, str(ROOT))


def in_tree(path: Path, tree: Path) -> Path | None:
    """Another checkout's own copy of a file of this tree (an earlier build's scenario,
    with the documents it names as they were then), if it has one."""
    try:
        theirs = tree / path.resolve().relative_to(ROOT)
    except ValueError:
        return None
    return theirs if theirs.exists() else None


def in_checkout(tree: Path, argv: Sequence[str]) -> list[str]:
    """The command line that runs ``argv`` (a script and its arguments, ``-m MODULE ...``
    or ``-c CODE ...``) with the build of the checkout ``tree``, wholly on its own files:
    its ``prima`` and its robots, schemas, applications and scenarios too, whatever this
    environment has installed (``bench/_tree.py``: an editable install of this checkout
    would map today's in). Run it from any folder."""
    return [sys.executable, str(Path(__file__).with_name("_tree.py")), str(tree), *argv]


def cpu(fn: Callable[[], object]) -> float:
    """CPU seconds this process spends in ``fn()``."""
    start = time.process_time()
    fn()
    return time.process_time() - start


def child_cpu(argv: Sequence[str], *, ok: tuple[int, ...] = (0,), cwd: Path | None = None,
              env: Mapping[str, str] | None = None) -> float:
    """CPU seconds (user + system) of one cold process running ``argv``.

    The process's output is swallowed; an exit status not in ``ok`` stops the
    benchmark with the process's error output, as a benchmark of a failing
    command measures nothing.
    """
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(list(argv), capture_output=True, text=True, check=False, cwd=cwd,
                          env=None if env is None else dict(env))
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in ok:
        sys.exit(f"{' '.join(argv)} exited {done.returncode}:\n{done.stderr}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def interleaved(cases: dict[str, Callable[[], float]], repeats: int) -> dict[str, float]:
    """Median of each case's own measure (seconds) over ``repeats`` rounds.

    Each case is a function that does the work once and returns what it cost
    (``lambda: cpu(work)``, ``lambda: child_cpu(argv)``). One round runs every
    case once, in order; the rounds interleave the cases.
    """
    samples: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(repeats):
        for name, case in cases.items():
            samples[name].append(case())
    return {name: statistics.median(values) for name, values in samples.items()}


def interpreter() -> str:
    """Which Python measured: absolute figures depend on how it was built as much as on
    the machine (an optimized build, with PGO and LTO, can run the same code 10% faster
    than one without)."""
    return (f"measured with {platform.python_implementation()} {platform.python_version()}"
            f" installed in {sys.base_prefix}")


def fmt_time(seconds: float) -> str:
    """A duration in the unit that reads best: s, ms or us."""
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e6:.1f} us"


def report(title: str, medians: dict[str, float], peer: str, *,
           unit: Callable[[float], str] = fmt_time, repeats: int | None = None) -> None:
    """Print one table: each case's median and its ratio to ``peer``'s median."""
    rounds = f", median of {repeats} interleaved rounds" if repeats else ""
    print(f"{title} (CPU time{rounds}; ratio to {peer})")
    width = max(len(name) for name in medians)
    base = medians[peer]
    for name, value in medians.items():
        ratio = value / base if base else float("inf")
        print(f"  {name:<{width}}  {unit(value):>10}  {ratio:8.2f}x")


def copy_checkout(folder: Path) -> None:
    """Copy this checkout's files into ``folder``: those git tracks or would (not what it
    ignores: built modules, caches, runs' output), or, when git cannot say, the whole
    tree without its caches and built files."""
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                             "--exclude-standard"], cwd=ROOT, capture_output=True, check=False)
    if listed.returncode != 0:
        shutil.copytree(ROOT, folder, dirs_exist_ok=True, ignore=shutil.ignore_patterns(
            ".git", "__pycache__", "*.so", "build", "*.egg-info", ".*_cache"))
        return
    for name in (n.decode() for n in listed.stdout.split(b"\0") if n):
        if (ROOT / name).is_file():
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, folder / name)


COMPILED_HELP = ("measure this checkout's compiled build (setup.py, PRIMA_MYPYC=1), built "
                 "first in a temporary copy: needs mypy, a C compiler and Python's headers, "
                 "about three minutes of CPU time")
"""The help of a benchmark's ``--compiled`` (:func:`compiled_copy`)."""


def compiled_copy(folder: Path) -> Path:
    """This checkout's compiled build (``setup.py``, ``PRIMA_MYPYC=1``), made in ``folder``:
    the checkout copied there (:func:`copy_checkout`), its modules compiled in place, and
    checked to load compiled. Needs mypy (the lint extra), a C compiler and Python's
    headers; about three minutes of CPU time (docs/judging.md, A compiled build). Returns
    ``folder``, a tree to run (:func:`in_checkout`) like a checkout. (In place, not ``pip
    install``: the tests and benchmarks run in that tree, beside the compiled modules.)"""
    copy_checkout(folder)
    print(f"building the compiled build in {folder} (about three minutes of CPU time) ...",
          file=sys.stderr, flush=True)
    env = {**os.environ, "PRIMA_MYPYC": "1"}
    done = subprocess.run([sys.executable, "setup.py", "-q", "build_ext", "--inplace"],
                          cwd=folder, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        sys.exit("the compiled build failed:\n" + "\n".join(
            (done.stdout + done.stderr).strip().splitlines()[-20:]))
    check = subprocess.run(in_checkout(folder, ["-c", "import prima, sys; "
                                                "sys.exit(0 if prima.compiled() else 1)"]),
                           check=False)
    if check.returncode != 0:
        sys.exit(f"{folder}: built, but prima does not load compiled there")
    return folder
