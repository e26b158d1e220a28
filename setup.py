"""shary's extras, computed here because one of them names a folder of this checkout.

The ``ros`` extra installs shary's own ROS 2 interface package (``ros/shary_interfaces``,
the ``RunTask`` action of ``~/run_task``), which no registry has: pip builds it from
this folder.  A requirement can name a folder only by an absolute ``file://`` address,
which ``pyproject.toml`` cannot compute, so the extras are given here (everything else
is in ``pyproject.toml``; docs/architecture.md says why).
"""

from pathlib import Path

from setuptools import setup

INTERFACES = (Path(__file__).resolve().parent / "ros" / "shary_interfaces").as_uri()

setup(extras_require={
    "test": ["pytest>=7", "pytest-timeout>=2.1", "ruff>=0.5", "hypothesis>=6", "selenium>=4.15",
             "cryptography>=41", "grimp>=3.5", "pytest-xdist>=3.5"],
    "bench": ["gtpyhop>=1.4", "oxrdflib>=0.4", "python-statemachine>=3.2,<4"],
    # ROS 2 Jazzy (LTS) from PyPI, pinned: a robot and shary must run the same distro
    # (docs/ros2.md).  test-msgs carries the action types the simulated robot serves;
    # shary-ros-interfaces, built from ros/shary_interfaces, the RunTask action.
    "ros": ["ros-jazzy-rclpy==7.1.6", "ros-jazzy-rmw-fastrtps-cpp==8.4.3",
            "ros-jazzy-action-msgs==2.0.3", "ros-jazzy-std-msgs==5.3.6",
            "ros-jazzy-diagnostic-msgs==5.3.6", "ros-jazzy-visualization-msgs==5.3.6",
            "ros-jazzy-geometry-msgs==5.3.6", "ros-jazzy-test-msgs==2.0.3",
            f"shary-ros-interfaces @ {INTERFACES}"],
})
