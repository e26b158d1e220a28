"""Keep PyBullet's C output away from Python's standard output.

PyBullet writes warnings and banners from C straight to file descriptors 1 and
2 (``No inertial data for link ...``, ``b3Printf: ...``).  Swapping
``sys.stdout`` does not catch them, and a command whose standard output is read
by a machine (``--json``) would be corrupted.  So these helpers redirect at the
file-descriptor level with :func:`os.dup2`, flushing both Python's and C's
buffers on the way in and out so that nothing written before lands in the wrong
place and nothing written inside leaks out later.

The redirection is process-wide: do not print from another thread while inside.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import tempfile
from collections.abc import Iterator

_libc: ctypes.CDLL | None
try:
    _libc = ctypes.CDLL(None)
except OSError:  # pragma: no cover - platforms without a loadable C library handle
    _libc = None


def _flush_all() -> None:
    """Flush Python's text streams and every C ``FILE*`` buffer."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    if _libc is not None:
        with contextlib.suppress(Exception):
            _libc.fflush(None)


class Captured:
    """What the C side wrote while a :func:`captured` block ran (set on exit)."""

    def __init__(self) -> None:
        self.text = ""


@contextlib.contextmanager
def _redirected(target_fd: int, fds: tuple[int, ...]) -> Iterator[None]:
    _flush_all()
    saved = [os.dup(fd) for fd in fds]
    try:
        for fd in fds:
            os.dup2(target_fd, fd)
        yield
    finally:
        _flush_all()
        for fd, copy in zip(fds, saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)


@contextlib.contextmanager
def silenced(stdout: bool = True, stderr: bool = True) -> Iterator[None]:
    """Send file descriptors 1 and/or 2 to ``/dev/null`` for the block."""
    fds = tuple(fd for fd, wanted in ((1, stdout), (2, stderr)) if wanted)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        with _redirected(devnull, fds):
            yield
    finally:
        os.close(devnull)


@contextlib.contextmanager
def captured(stdout: bool = True, stderr: bool = True) -> Iterator[Captured]:
    """Collect what is written to file descriptors 1 and/or 2 during the block.

    Used by tests to prove that loading a model prints no warning, and by
    callers who want to log PyBullet's complaints instead of dropping them.
    """
    fds = tuple(fd for fd, wanted in ((1, stdout), (2, stderr)) if wanted)
    result = Captured()
    with tempfile.TemporaryFile() as sink:
        try:
            with _redirected(sink.fileno(), fds):
                yield result
        finally:
            sink.seek(0)
            result.text = sink.read().decode("utf-8", errors="replace")
