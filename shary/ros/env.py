"""Where shary's ROS 2 traffic goes, and whether rclpy can be used in this interpreter.

Two facts of the ``ros-jazzy-*`` wheels shape this module (docs/ros2.md):

* their shared libraries are found through ``LD_LIBRARY_PATH``, which the
  wheels' start-up hook (``ros_wheels_bootstrapper``) computes from
  ``sys.prefix``; in a virtual environment that sees the wheels through
  ``--system-site-packages`` the libraries live under the base interpreter, so
  the hook looks in the wrong place and ``import rclpy`` fails.
  :func:`library_path` gives the right value, and :func:`ros_environment`
  puts it in the environment of the processes shary starts;
* ROS 2 discovery reaches the whole subnet by default: shary keeps it on this
  host (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) unless the user set it.

Nothing here imports rclpy, so ``shary`` works without the ``ros`` extra.
"""

from __future__ import annotations

import importlib
import os
import site
import sys
from pathlib import Path

DISCOVERY_RANGE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
DEFAULT_RANGE = "LOCALHOST"
"""ROS 2 traffic stays on this host unless the user says otherwise."""


def library_path(environ: dict[str, str] | None = None) -> str:
    """``LD_LIBRARY_PATH`` with the ROS wheels' library folders in front (the base
    interpreter's ``lib`` and every ``ros_*.libs`` folder of every site-packages)."""
    environ = os.environ if environ is None else environ
    folders = [str(Path(prefix) / "lib") for prefix in dict.fromkeys((sys.prefix,
                                                                      sys.base_prefix))]
    for packages in site.getsitepackages():
        folders += sorted(str(p) for p in Path(packages).glob("ros_*.libs") if p.is_dir())
    old = [p for p in environ.get("LD_LIBRARY_PATH", "").split(os.pathsep) if p]
    return os.pathsep.join(dict.fromkeys(folders + old))


def ros_environment(environ: dict[str, str] | None = None, **extra: str) -> dict[str, str]:
    """The environment for a process that uses ROS 2: the wheels' library path, traffic
    kept on this host unless ``environ`` says otherwise, then ``extra``."""
    env = dict(os.environ if environ is None else environ)
    env.setdefault(DISCOVERY_RANGE, DEFAULT_RANGE)
    env["LD_LIBRARY_PATH"] = library_path(env)
    env["_ROS_WHEELS_BOOTSTRAP_COMPLETE"] = "1"  # the wheels' hook would recompute it wrongly
    env.update(extra)
    return env


def keep_on_host() -> None:
    """Make this process's ROS 2 traffic stay on this host unless the user said otherwise
    (read by rclpy when it initialises a context)."""
    os.environ.setdefault(DISCOVERY_RANGE, DEFAULT_RANGE)


def unavailable() -> str | None:
    """Why rclpy, or shary's interface package, cannot be used in this interpreter (with
    what to do), or None."""
    for module, what in (("rclpy", "rclpy"),
                         ("shary_interfaces.action", "shary's interface package")):
        try:
            importlib.import_module(module)
        except ImportError as err:
            if "cannot open shared object" in str(err):
                return (f"{what} is installed but its libraries are not found ({err.msg}); "
                        f"run with LD_LIBRARY_PATH={library_path()} (docs/ros2.md)")
            return f"{what} is not installed ({err}); install it with pip install '.[ros]'"
    return None


def reexec_with_libraries() -> None:
    """Start this program again with the ROS wheels' libraries found, when they are not
    (a virtual environment over the base interpreter's wheels): the libraries must be
    on ``LD_LIBRARY_PATH`` before the process starts.  Done once (guarded by a variable);
    a program that needs rclpy calls it before importing it (never a library: the
    process is not its own)."""
    problem = unavailable()
    if problem is None or "not installed" in problem or os.environ.get("_SHARY_ROS_REEXEC"):
        return
    env = ros_environment(_SHARY_ROS_REEXEC="1")
    os.execve(sys.executable, sys.orig_argv, env)
