"""Processes that die with the one that started them, and Ctrl-C passed on one at a time.

``shary run SCENARIO --ros --world`` starts the world and the supervisor as processes of
their own.  Killed with SIGKILL, the parent cannot stop them, and they would run on: the
supervisor sending goals, the world serving them, nobody watching.  On Linux a child can
ask the kernel to send it a signal when its parent dies (``prctl(PR_SET_PDEATHSIG)``):
:func:`die_with_parent` gives the function that asks it, run in the child between fork
and exec (``subprocess.Popen(preexec_fn=...)``).  The signal is SIGTERM, so that the
child stops as it stops on SIGTERM: a supervisor safely (:mod:`shary.ros.stop`).

The children run in a session of their own, so that a Ctrl-C at the terminal reaches
the parent only, and :func:`wait_passing_interrupts` passes each Ctrl-C on to the
child once: the first asks the supervisor for its safe stop, the second abandons it, as
at a terminal of its own (the terminal's Ctrl-C reaching both at once would be two).
"""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
from collections.abc import Callable

PR_SET_PDEATHSIG = 1
"""``prctl`` option: the signal this process gets when its parent dies (linux/prctl.h)."""


def die_with_parent() -> Callable[[], None] | None:
    """The ``preexec_fn`` that makes a child get SIGTERM when this process dies (None
    where the kernel has no such thing: not Linux).  libc is loaded here, before the
    fork: the child only calls it."""
    if not sys.platform.startswith("linux"):
        return None
    prctl = ctypes.CDLL(None, use_errno=True).prctl
    parent = os.getpid()

    def in_child() -> None:
        prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
        if os.getppid() != parent:  # the parent died before the request was made
            os.kill(os.getpid(), signal.SIGTERM)

    return in_child


def wait_passing_interrupts(child: subprocess.Popen) -> int:
    """Wait for ``child`` to end, passing each Ctrl-C this process gets on to it as
    SIGINT; its exit status."""
    while True:
        try:
            return child.wait()
        except KeyboardInterrupt:
            child.send_signal(signal.SIGINT)
