"""Where output goes: one way to prepare and write the files and folders a command makes.

A command that writes (``shary run --out``, ``shary render -o``, ``shary
import-scxml -o``, ``shary plan -o``, ``shary log --jsonl``, the context log)
may be pointed at a file where a folder is wanted, at a path through a file, at
a folder it may not write, or at a full disk.  Python says so with a bare
exception name (``FileExistsError``, ``NotADirectoryError``, ``PermissionError``,
``OSError: [Errno 28]``); here every such case becomes an :class:`OutputError`
that names the path, says what is wrong and what to do, and which the ``shary``
command prints as ``PATH: error: what is wrong (what to do)`` with exit status 2.
An output path has no line to point at, so the message has no ``LINE:COL``
(docs/architecture.md, "User files").

Two rules keep a failure from losing anything:

* the place is checked (:func:`output_folder`, :func:`output_file`) before the
  work that fills it, so a long run does not end on "cannot write";
* a file is written whole or not at all (:func:`write_output`,
  :func:`open_output`): the text goes to a new file beside the target, which
  replaces the target only once it is complete, so a full disk never leaves a
  truncated drawing where the last good one was.  Special files (``/dev/null``,
  ``/dev/stdout``, a pipe) are written in place.
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

# errno -> (what is wrong, what to do)
_REASONS: dict[int, tuple[str, str]] = {
    errno.ENOSPC: ("the disk is full", "free some space, or write somewhere else"),
    errno.EDQUOT: ("the disk quota is used up", "free some space, or write somewhere else"),
    errno.EFBIG: ("the file would pass this system's file-size limit",
                  "raise the limit ('ulimit -f'), or write somewhere else"),
    errno.EROFS: ("the file system is read-only", "write to a folder on a writable disk"),
    errno.EACCES: ("no permission to write here",
                   "choose a folder you can write to, or change its permissions"),
    errno.EPERM: ("the system does not allow writing here",
                  "choose a folder you can write to"),
    errno.ENAMETOOLONG: ("the name is too long", "choose a shorter path"),
    errno.EISDIR: ("this is a folder, not a file", "name a file inside it"),
    errno.ENOENT: ("a folder on the way does not exist",
                   "create the folder, or choose another path"),
    errno.EIO: ("the disk reported an input/output error",
                "check the disk, or write somewhere else"),
}


class OutputError(Exception):
    """An output cannot be written to ``path``: ``message`` says why, ``hint`` what to do."""

    def __init__(self, path: str | Path, message: str, hint: str):
        self.path, self.message, self.hint = str(path), message, hint
        super().__init__(f"{self.path}: error: {message} ({hint})")


def refused(path: str | Path, err: OSError) -> OutputError:
    """The :class:`OutputError` for an ``OSError`` met while writing ``path``."""
    if err.errno == errno.ENOENT:
        return OutputError(path, *_not_found(Path(path)))
    message, hint = _REASONS.get(err.errno or 0, (
        err.strerror or str(err), "choose another place to write"))
    return OutputError(path, message, hint)


def _not_found(path: Path) -> tuple[str, str]:
    """What "no such file or directory" means when writing ``path``: a link on the way
    that leads nowhere, or a folder that refuses new entries whatever the permissions
    (a file system the kernel makes up, as ``/proc`` and ``/sys``)."""
    for ancestor in [path, *path.parents]:
        if ancestor.is_symlink() and not ancestor.exists():
            return (f"{ancestor} is a link to {os.readlink(ancestor)}, which does not exist",
                    "fix the link, or choose another path")
        if ancestor.is_dir():
            return (f"nothing can be made in {ancestor}: the system makes up what is in it",
                    "choose a folder on a disk")
    return _REASONS[errno.ENOENT]


def output_folder(path: str | Path) -> Path:
    """Make sure ``path`` is a folder this process can write into (creating it and its
    parents if needed) and return it; otherwise raise :class:`OutputError`."""
    folder = Path(path)
    broken = next((a for a in [folder, *folder.parents] if a.is_symlink() and not a.exists()),
                  None)
    if broken is not None:
        raise OutputError(path, *_not_found(broken))
    if folder.exists():
        if not folder.is_dir():
            raise OutputError(path, "this is a file, not a folder",
                              "name a folder, or move the file away")
        _check_writable(path, folder)
        return folder
    blocking = _file_on_the_way(folder)
    if blocking is not None:
        raise OutputError(path, f"{blocking} is not a folder, so nothing can be made under it",
                          "choose a path whose parents are folders")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise refused(path, err) from None
    return folder


def output_file(path: str | Path, *, inputs: Iterable[str | Path] = ()) -> Path:
    """Make sure a file can be written at ``path`` (its folder is created if needed)
    and return it; otherwise raise :class:`OutputError`.  Nothing is written yet.

    ``inputs`` are the files the command reads: writing over one of them would
    destroy what is being read, so that is refused too.
    """
    target = Path(path)
    if target.is_dir():
        raise OutputError(path, "this is a folder, not a file", "name a file inside it")
    for source in inputs:
        if target.exists() and Path(source).exists() and os.path.samefile(target, source):
            raise OutputError(path, f"this is {source}, which the command reads",
                              "write to another file")
    parent = target.parent
    blocking = _file_on_the_way(parent)
    if blocking is not None:
        raise OutputError(path, f"{blocking} is not a folder, so nothing can be written under it",
                          "choose a path whose parents are folders")
    if not parent.is_dir():
        try:
            output_folder(parent)
        except OutputError as err:
            raise OutputError(path, err.message, err.hint) from None
    if target.exists() and not os.access(target, os.W_OK):
        raise refused(path, OSError(_denied(target), ""))
    _check_writable(path, parent)
    return target


def write_output(path: str | Path, data: str | bytes) -> None:
    """Write ``data`` (text as UTF-8) to ``path``, whole or not at all."""
    with open_output(path, binary=isinstance(data, bytes)) as stream:
        stream.write(data)


@contextmanager
def open_output(path: str | Path, *, binary: bool = False) -> Iterator[IO]:
    """A stream whose content replaces ``path`` when the block ends without error.

    On an error (a full disk, an exception in the block) the target is left as
    it was and the partial file is removed.
    """
    target = output_file(path)
    real = Path(os.path.realpath(target))
    if real.exists() and not stat.S_ISREG(real.stat().st_mode):
        yield from _in_place(path, real, binary)
        return
    temporary = real.with_name(f".{real.name}.{os.getpid()}.part")
    try:
        # os.open with 0o666 lets the umask decide the mode, as a plain open() would.
        fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        with os.fdopen(fd, "wb" if binary else "w", **({} if binary else {
                "encoding": "utf-8", "newline": ""})) as stream:
            yield stream
        if real.exists():
            os.chmod(temporary, stat.S_IMODE(real.stat().st_mode))
        os.replace(temporary, real)
    except OSError as err:
        temporary.unlink(missing_ok=True)
        raise refused(path, err) from None
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _in_place(path: str | Path, real: Path, binary: bool) -> Iterator[IO]:
    try:
        with open(real, "wb" if binary else "w",
                  **({} if binary else {"encoding": "utf-8", "newline": ""})) as stream:
            yield stream
    except OSError as err:
        raise refused(path, err) from None


def _check_writable(path: str | Path, folder: Path) -> None:
    """Refuse a folder this process may not write into (``os.access`` also sees a
    read-only file system, which no permission bit, even root's, gets past)."""
    if not os.access(folder, os.W_OK | os.X_OK):
        raise refused(path, OSError(_denied(folder), ""))


def _denied(where: Path) -> int:
    """Why ``os.access`` said no: a read-only file system or a permission."""
    try:
        read_only = bool(os.statvfs(where).f_flag & os.ST_RDONLY)
    except OSError:
        read_only = False
    return errno.EROFS if read_only else errno.EACCES


def _file_on_the_way(folder: Path) -> Path | None:
    """The first existing ancestor of ``folder`` that is not a folder, if any."""
    for ancestor in [*reversed(folder.parents), folder]:
        if ancestor.exists() and not ancestor.is_dir():
            return ancestor
        if not ancestor.exists():
            return None
    return None
