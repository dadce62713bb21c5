"""Writing a command's output file: one path for every command that writes one.

``prima run --out``, ``show -o``, ``plot -o``, ``sweep --out`` and ``test --update``
all write through :func:`written`: into a temporary file beside the target,
renamed over it once written, so a run that fails half-way (or a full disk)
leaves no half-written file in its place, and the file appears whole. Ctrl-C
and SIGTERM (:class:`KeyboardInterrupt`) keep what was written so far: an
interrupted run's trace is still its trace up to then. A target that is not a
regular file (``/dev/stdout``, a named pipe) is written directly. Whatever goes
wrong writing becomes an :class:`~prima.errors.OutputError` that names the file
as a terminal can show it (:func:`prima.escape.shown_path`): a message, never a
traceback.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, BinaryIO, TextIO, cast

from prima.errors import OutputError
from prima.escape import shown_path, terminal

__all__ = ["check_folder", "check_target", "written", "written_bytes"]


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


def check_target(path: str | Path) -> str | None:
    """What stops ``path`` from being written (checked before any work), or None."""
    target = Path(path)
    shown = shown_path(target)
    if target.is_dir():
        return f"{shown} is a folder"
    folder = target.parent
    if not folder.is_dir():
        return f"{shown}: no such folder {shown_path(folder)}"
    if not (target.exists() and not target.is_file()) and not os.access(folder, os.W_OK | os.X_OK):
        return f"{shown}: the folder {shown_path(folder)} is not writable"
    return None


def check_folder(path: str | Path) -> str | None:
    """What stops files from being written in the folder ``path`` (made if need be),
    checked before any work, or None."""
    folder = Path(path)
    shown = shown_path(folder)
    if folder.exists() and not folder.is_dir():
        return f"{shown} is a file"
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{shown}: {shown_path(existing)} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"{shown}: the folder {shown_path(existing)} is not writable"
    return None


def _mode() -> int:
    """The permissions a new file gets (what open() would give it: 0o666 less the umask)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def written(path: str | Path) -> contextlib.AbstractContextManager[TextIO]:
    """A text file (UTF-8) to write ``path`` with, put in place when the block ends."""
    return cast("contextlib.AbstractContextManager[TextIO]", _written(path, binary=False))


def written_bytes(path: str | Path) -> contextlib.AbstractContextManager[BinaryIO]:
    """A binary file to write ``path`` with (a picture), put in place when the block ends."""
    return cast("contextlib.AbstractContextManager[BinaryIO]", _written(path, binary=True))


@contextlib.contextmanager
def _written(path: str | Path, *, binary: bool) -> Iterator[IO[Any]]:
    target = Path(path)
    shown = shown_path(target)
    mode = "wb" if binary else "w"
    encoding = None if binary else "utf-8"
    if target.exists() and not target.is_file() and not target.is_dir():
        try:
            with open(target, mode, encoding=encoding) as direct:
                yield direct
        except OSError as exc:
            raise OutputError(f"cannot write {shown}: {_reason(exc)}") from exc
        return
    problem = check_target(target)
    if problem:
        raise OutputError(f"cannot write {problem}")
    try:
        fd, temp = tempfile.mkstemp(prefix=".prima-", suffix=".part", dir=target.parent)
    except OSError as exc:
        raise OutputError(f"cannot write {shown}: {_reason(exc)}") from exc
    keep = False
    try:
        with os.fdopen(fd, mode, encoding=encoding) as out:
            try:
                yield out
            except KeyboardInterrupt:  # Ctrl-C, SIGTERM: what was written stays written
                keep = True
                raise
            finally:
                if keep:
                    out.flush()
        keep = True
    except OSError as exc:
        keep = False
        raise OutputError(f"cannot write {shown}: {_reason(exc)}") from exc
    except UnicodeEncodeError as exc:  # a file name that is not UTF-8, written into it
        keep = False
        raise OutputError(f"cannot write {shown}: it would hold a name that is not UTF-8 "
                          f"({terminal(exc.object[exc.start:exc.end])})") from exc
    finally:
        _settle(temp, target, keep)


def _settle(temp: str, target: Path, keep: bool) -> None:
    """Put the written file in place (``keep``), or remove it."""
    if keep:
        try:
            os.chmod(temp, _mode())
            os.replace(temp, target)
            return
        except OSError as exc:
            with contextlib.suppress(OSError):
                os.unlink(temp)
            raise OutputError(f"cannot write {shown_path(target)}: {_reason(exc)}") from exc
    with contextlib.suppress(OSError):
        os.unlink(temp)
