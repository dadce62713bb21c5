"""Writing a command's output file: one path for every command that writes one.

Where output goes, the same rule in every command: a folder that an output file
(``--out``, ``-o``) or an output folder (``prima sweep --out``) needs is made, with
its parents, when the output is written (and removed again if nothing could be
written in it); a path that cannot become one (a file in its way, a folder that is
not writable) is refused before any work (:func:`check_target`,
:func:`check_folder`). A command that writes a file or folder its command line
does not name writes it in the current folder, named after its input
(:func:`named_after`: ``prima show RUN`` writes ``NAME.html``, ``prima sweep``
``sweep-NAME/``).

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

__all__ = ["check_folder", "check_target", "make_folder", "named_after", "written",
           "written_bytes"]


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


def check_target(path: str | Path) -> str | None:
    """What stops the file ``path`` from being written (checked before any work), or
    None; a missing folder is not in the way (it is made)."""
    target = Path(path)
    shown = shown_path(target)
    if target.is_dir():
        return f"{shown} is a folder"
    if target.exists() and not target.is_file():
        return None  # /dev/stdout, a named pipe: written directly
    problem = _in_the_way(target.parent)
    return f"{shown}: {problem}" if problem else None


def check_folder(path: str | Path) -> str | None:
    """What stops files from being written in the folder ``path`` (made if need be),
    checked before any work, or None."""
    folder = Path(path)
    shown = shown_path(folder)
    if folder.exists() and not folder.is_dir():
        return f"{shown} is a file"
    problem = _in_the_way(folder)
    return f"{shown}: {problem}" if problem else None


def _in_the_way(folder: Path) -> str | None:
    """What stops ``folder`` from being made or written in: its nearest existing
    parent is a file, or is not writable."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{shown_path(existing)} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"the folder {shown_path(existing)} is not writable"
    return None


def named_after(source: str | Path, pattern: str) -> Path:
    """Where a command writes what its command line does not name: in the current
    folder, ``pattern`` with ``{stem}`` the input's name without its suffix
    (``"{stem}.html"``, ``"sweep-{stem}"``)."""
    return Path(pattern.format(stem=Path(source).stem))


def make_folder(path: str | Path, target: str | Path | None = None) -> list[Path]:
    """Make the folder ``path`` and its missing parents; the folders made, innermost
    first (:class:`~prima.errors.OutputError`, naming ``target`` if given, if it cannot
    be made)."""
    folder = Path(path)
    shown = shown_path(path if target is None else target)
    missing = []
    while not folder.is_dir() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    for each in reversed(missing):
        try:
            each.mkdir()
        except FileExistsError:
            if not each.is_dir():
                raise OutputError(f"cannot write {shown}: {shown_path(each)} is not a "
                                  "folder") from None
        except OSError as exc:
            raise OutputError(f"cannot write {shown}: {_reason(exc)}") from exc
    return missing


def _unmake(folders: list[Path]) -> None:
    """Remove the folders :func:`make_folder` made, if they are still empty."""
    for folder in folders:
        with contextlib.suppress(OSError):
            folder.rmdir()


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
    made = make_folder(target.parent, target)
    try:
        fd, temp = tempfile.mkstemp(prefix=".prima-", suffix=".part", dir=target.parent)
    except OSError as exc:
        _unmake(made)
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
        _settle(temp, target, keep, made)


def _settle(temp: str, target: Path, keep: bool, made: list[Path]) -> None:
    """Put the written file in place (``keep``), or remove it, and the folders made
    for it."""
    if keep:
        try:
            os.chmod(temp, _mode())
            os.replace(temp, target)
            return
        except OSError as exc:
            with contextlib.suppress(OSError):
                os.unlink(temp)
            _unmake(made)
            raise OutputError(f"cannot write {shown_path(target)}: {_reason(exc)}") from exc
    with contextlib.suppress(OSError):
        os.unlink(temp)
    _unmake(made)
