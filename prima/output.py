"""Writing a command's output file: one path for every command that writes one.

Where output goes, the same rule in every command: a folder that an output file
(``--out``, ``-o``) or an output folder (``prima sweep --out``) needs is made, with
its parents, when the output is written (and removed again if nothing could be
written in it); a path that cannot become one (a file in its way, a folder that is
not writable) is refused before any work (:func:`check_target`,
:func:`check_folder`), and so is an output that names one of the command's inputs
(the scenario, a document, map or robot profile it names, a trace read: compared
as files, :func:`same_file`), so a typo never overwrites what a user made. A
command that writes a file or folder its command line does not name writes it in
the current folder, named after its input (:func:`named_after`: ``prima show RUN``
writes ``NAME.html``, ``prima sweep`` ``sweep-NAME/``).

Every output file is written through :class:`Staged` (:func:`written`,
:func:`written_bytes`): into a temporary file beside the target, renamed over it
once written, so a run that fails half-way, a full disk or a process killed
(even with SIGKILL) leaves the earlier file byte for byte as it was, and the file
appears whole; a log read back after a stop (a sweep's results file) is written in
place instead, line by line (:class:`Log`), so that a process killed outright keeps
the lines it wrote. Ctrl-C and SIGTERM (:class:`KeyboardInterrupt`) keep what was
written so far only where the caller asks (``partial``: an interrupted run's trace
is still its trace up to then; a page or a picture cut short is discarded). A target
that is not a regular file (``/dev/stdout``, a named pipe) is written directly, or,
for a writer that must seek (an MCAP recording), through a temporary file copied
into it at the end. Whatever goes wrong writing becomes an
:class:`~prima.errors.OutputError` that names the file as a terminal can show it
(:func:`prima.escape.shown_path`, shortened): a message, never a traceback.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any, BinaryIO, TextIO, cast

from prima.errors import OutputError
from prima.escape import shown_path, terminal

__all__ = ["Inputs", "Log", "SHOWN_NAME", "Staged", "check_folder", "check_target", "input_named",
           "make_folder", "named_after", "same_file", "shown", "written", "written_bytes"]

Inputs = Iterable[tuple[str, "str | os.PathLike[str]"]]
"""A command's input files, each with what it is (``("the scenario", "s.xml")``)."""

SHOWN_NAME = 120
"""The most characters of a file's name a message shows (a longer one is shortened in
its middle, with ``...``)."""


def shown(path: str | os.PathLike[str]) -> str:
    """A file's name as an error message shows it: escaped (:func:`shown_path`) and, past
    :data:`SHOWN_NAME` characters, shortened in its middle."""
    text = shown_path(path)
    if len(text) <= SHOWN_NAME:
        return text
    half = (SHOWN_NAME - 3) // 2
    return f"{text[:half]}...{text[-half:]}"


def _reason(exc: OSError) -> str:
    """An OSError's reason as a message says it (``file name too long``)."""
    text = exc.strerror or str(exc)
    return text[:1].lower() + text[1:] if text[1:2].islower() else text


def _failed(path: str | os.PathLike[str], exc: OSError) -> OutputError:
    return OutputError(f"cannot write {shown(path)}: {_reason(exc)}")


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether ``a`` and ``b`` are one file: the same file where both exist (a link, a
    path written two ways), else the same resolved path."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        pass
    try:
        return Path(a).resolve() == Path(b).resolve()
    except (OSError, RuntimeError):  # (a name too long, a loop of links)
        return os.path.abspath(a) == os.path.abspath(b)


def input_named(path: str | os.PathLike[str], inputs: Inputs) -> tuple[str, str] | None:
    """The input (what it is, its path as given) that ``path`` names, if any."""
    for what, given in inputs:
        if same_file(path, given):
            return what, os.fspath(given)
    return None


def _is_input(path: str | os.PathLike[str], inputs: Inputs) -> str | None:
    found = input_named(path, inputs)
    if found is None:
        return None
    what, given = found
    return (f"{shown(path)} is {what} ({shown(given)}), which this command reads: name "
            "another file (nothing was written)")


def check_target(path: str | os.PathLike[str], inputs: Inputs = ()) -> str | None:
    """What stops the file ``path`` from being written (checked before any work), or
    None; a missing folder is not in the way (it is made). An output that names one of
    ``inputs`` is refused. Raises :class:`~prima.errors.OutputError` for a name the
    file system cannot take (too long, say)."""
    target = Path(path)
    if isinstance(path, str) and path == "-":  # (prima run's --out takes it: its trace)
        return "- is standard output, where this command writes no file: name a file (./- " \
               "for one named -)"
    if isinstance(path, str) and path.endswith(("/", os.sep)):
        # (Path drops the slash: notes.txt/ would write over the file notes.txt)
        return f"{shown(path)} names a folder (it ends with /): give the file's name"
    try:
        named = _is_input(target, inputs)
        if named:
            return named
        if target.is_dir():
            return f"{shown(target)} is a folder"
        if target.exists() and not target.is_file():
            return None  # /dev/stdout, a named pipe: written directly
        problem = _in_the_way(target.parent)
    except OSError as exc:
        raise _failed(target, exc) from exc
    return f"{shown(target)}: {problem}" if problem else None


def check_folder(path: str | os.PathLike[str], inputs: Inputs = ()) -> str | None:
    """What stops files from being written in the folder ``path`` (made if need be),
    checked before any work, or None: a file is in its way (which may be one of
    ``inputs``: said so)."""
    folder = Path(path)
    try:
        if folder.exists() and not folder.is_dir():
            found = input_named(folder, inputs)
            if found is None:
                return f"{shown(folder)} is a file"
            return (f"{shown(folder)} is a file: {found[0]} ({shown(found[1])}), which this "
                    "command reads; name a folder (nothing was written)")
        problem = _in_the_way(folder)
    except OSError as exc:
        raise _failed(folder, exc) from exc
    return f"{shown(folder)}: {problem}" if problem else None


def _in_the_way(folder: Path) -> str | None:
    """What stops ``folder`` from being made or written in: its nearest existing
    parent is a file, or is not writable."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"{shown(existing)} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"the folder {shown(existing)} is not writable"
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
    named = path if target is None else target
    missing = []
    try:
        while not folder.is_dir() and folder != folder.parent:
            missing.append(folder)
            folder = folder.parent
    except OSError as exc:
        raise _failed(named, exc) from exc
    for each in reversed(missing):
        try:
            each.mkdir()
        except FileExistsError:
            if not each.is_dir():
                raise OutputError(f"cannot write {shown(named)}: {shown(each)} is not a "
                                  "folder") from None
        except OSError as exc:
            raise _failed(named, exc) from exc
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


_SYSTEM = ("/dev/", "/proc/")
"""Where a path names a stream, not a file to replace (``/dev/stdout``, ``/dev/fd/1``,
``/proc/self/fd/1``), even when the stream is a regular file (a shell's ``>``)."""


def _written_directly(target: Path) -> bool:
    """Whether ``target`` is written directly (a device, a named pipe, a stream of this
    process), not through a file beside it renamed over it."""
    try:
        if target.exists() and not target.is_file():
            return not target.is_dir()
    except OSError as exc:
        raise _failed(target, exc) from exc
    real = os.path.realpath(target)
    return any(os.fspath(target).startswith(system) or real.startswith(system)
               for system in _SYSTEM)


class Staged:
    """An output file being written: a temporary file beside ``path`` (``file``), put in
    its place by :meth:`commit`, or taken away by :meth:`discard`; the file at ``path``
    is untouched until then, whatever happens to this process.

    ``binary``: a binary file, else text (UTF-8, ``\n`` line ends). ``seekable``: the
    writer seeks (an MCAP recording): a target that is not a regular file is written
    through a temporary file copied into it on commit."""

    def __init__(self, path: str | os.PathLike[str], *, binary: bool = False,
                 seekable: bool = False) -> None:
        self.target = Path(path)
        """The file as named (messages name it so)."""
        self._made: list[Path] = []
        self._temp: str | None = None
        self._copy_to: Path | None = None
        self.done = False
        mode = "w+b" if binary and seekable else "wb" if binary else "w"
        encoding = None if binary else "utf-8"
        newline = None if binary else "\n"
        if _written_directly(self.target):
            try:
                if seekable:
                    self._copy_to = self.target
                    self.file: IO[Any] = tempfile.TemporaryFile(mode)  # noqa: SIM115
                else:
                    self.file = open(self.target, mode, encoding=encoding,  # noqa: SIM115
                                     newline=newline)
            except OSError as exc:
                raise _failed(self.target, exc) from exc
            return
        problem = check_target(self.target)
        if problem:
            raise OutputError(f"cannot write {problem}")
        self._real = Path(os.path.realpath(self.target))
        """The file replaced: a symbolic link's target (the link itself stays)."""
        self._made = make_folder(self._real.parent, self.target)
        try:
            fd, self._temp = tempfile.mkstemp(prefix=".prima-", suffix=".part",
                                              dir=self._real.parent)
        except OSError as exc:
            _unmake(self._made)
            raise _failed(self.target, exc) from exc
        try:
            self.file = os.fdopen(fd, mode, encoding=encoding, newline=newline)
        except OSError as exc:
            os.close(fd)
            self._remove()
            raise _failed(self.target, exc) from exc

    def commit(self, *, failed: bool = False) -> None:
        """Put the file written in place of the target (its folder's entry replaced at
        once: a reader sees the old file or the new one, never a part). ``failed``: a
        write to it failed; what reached it is put in place all the same, what did not
        is dropped."""
        if self.done:
            return
        self.done = True
        try:
            if failed:
                self._close()
            else:
                self.file.flush()
                if self._copy_to is not None:
                    self.file.seek(0)
                    with open(self._copy_to, "wb") as direct:
                        shutil.copyfileobj(self.file, direct)
                elif self._temp is not None:
                    os.fsync(self.file.fileno())
                self.file.close()
            if self._temp is not None:
                os.chmod(self._temp, _mode())
                os.replace(self._temp, self._real)
        except OSError as exc:
            self._close()
            self._remove()
            raise _failed(self.target, exc) from exc

    def discard(self) -> None:
        """Take the file written away: the target stays as it was."""
        if self.done:
            return
        self.done = True
        self._close()
        self._remove()

    def _close(self) -> None:
        with contextlib.suppress(OSError):  # (what could not be written is not kept)
            self.file.close()

    def _remove(self) -> None:
        if self._temp is not None:
            with contextlib.suppress(OSError):
                os.unlink(self._temp)
        _unmake(self._made)


class Log:
    """An output file written in place, line by line, each line flushed as it is
    written: a log read back after a stop (a sweep's results file, ``--resume``), where
    what a process killed outright (SIGKILL, a machine lost) wrote must be kept. A
    reader drops a last line cut short. ``keep``: go on after the first ``keep`` bytes
    of the file there (the rest is cut off); else it is written anew."""

    def __init__(self, path: str | os.PathLike[str], *, keep: int = 0) -> None:
        self.target = Path(path)
        problem = check_target(self.target)
        if problem:
            raise OutputError(f"cannot write {problem}")
        made = [] if _written_directly(self.target) else make_folder(self.target.parent,
                                                                     self.target)
        try:
            self.file: TextIO = open(self.target, "r+" if keep else "w",  # noqa: SIM115
                                     encoding="utf-8", newline="\n")
            if keep:
                self.file.seek(keep)
                self.file.truncate()
        except OSError as exc:
            _unmake(made)
            raise _failed(self.target, exc) from exc

    def write(self, line: str) -> None:
        """One line (ending with ``\n``), flushed (:class:`OSError` as the system says)."""
        self.file.write(line)
        self.file.flush()

    def close(self) -> None:
        with contextlib.suppress(OSError):  # (what could not be written is not kept)
            self.file.close()


def written(path: str | os.PathLike[str], *, partial: bool = False
            ) -> contextlib.AbstractContextManager[TextIO]:
    """A text file (UTF-8) to write ``path`` with, put in place when the block ends
    (``partial``: also when Ctrl-C or SIGTERM ends it, with what was written)."""
    return cast("contextlib.AbstractContextManager[TextIO]",
                _written(path, binary=False, partial=partial))


def written_bytes(path: str | os.PathLike[str], *, partial: bool = False,
                  seekable: bool = False) -> contextlib.AbstractContextManager[BinaryIO]:
    """A binary file to write ``path`` with (a picture; ``seekable``: one its writer seeks
    in), put in place when the block ends (``partial``: as :func:`written`)."""
    return cast("contextlib.AbstractContextManager[BinaryIO]",
                _written(path, binary=True, partial=partial, seekable=seekable))


@contextlib.contextmanager
def _written(path: str | os.PathLike[str], *, binary: bool, partial: bool,
             seekable: bool = False) -> Iterator[IO[Any]]:
    staged = Staged(path, binary=binary, seekable=seekable)
    try:
        yield staged.file
    except KeyboardInterrupt:  # Ctrl-C, SIGTERM: kept only if a part is worth keeping
        if partial:
            staged.commit()
        else:
            staged.discard()
        raise
    except OSError as exc:
        staged.discard()
        if isinstance(exc, OutputError):
            raise
        raise _failed(path, exc) from exc
    except UnicodeEncodeError as exc:  # a file name that is not UTF-8, written into it
        staged.discard()
        raise OutputError(f"cannot write {shown(path)}: it would hold a name that is not "
                          f"UTF-8 ({terminal(exc.object[exc.start:exc.end])})") from exc
    except BaseException:
        staged.discard()
        raise
    staged.commit()
