"""``shary ros interfaces SRC…`` builds a robot's own interface packages from their
sources into the environment, in the order they need each other, and refuses, before
building anything, a package that names one neither among the sources nor installed.
The build test writes two small packages (one needing the other and geometry_msgs) and
builds them into a virtual environment of its own (about a minute)."""

from __future__ import annotations

import re
import subprocess
import sys
import venv
from pathlib import Path

from conftest import problems
from rosfixtures import needs_ros

from shary.ros.interfaces import GENERATORS

MANIFEST = """\
<?xml version="1.0"?>
<package format="3">
  <name>{name}</name>
  <version>0.2.0</version>
  <description>A test's interface package.</description>
  <maintainer email="tests@shary.invalid">tests</maintainer>
  <license>Apache-2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def sources(root: Path) -> tuple[Path, Path]:
    """Two packages: robot_test_msgs (a message, an action over geometry_msgs) and
    robot_test_more_msgs (a message over robot_test_msgs and std_msgs)."""
    base, more = root / "robot_test_msgs", root / "robot_test_more_msgs"
    for folder in (base / "msg", base / "action", more / "msg"):
        folder.mkdir(parents=True)
    (base / "package.xml").write_text(MANIFEST.format(name="robot_test_msgs"))
    (more / "package.xml").write_text(MANIFEST.format(name="robot_test_more_msgs"))
    (base / "msg" / "Spot.msg").write_text("float64 x\nfloat64 y\n")
    (base / "action" / "GoTo.action").write_text(
        "# go somewhere\ngeometry_msgs/PoseStamped pose\nstring place\n---\n"
        "string error_msg\n---\nfloat32 distance_remaining\n")
    (more / "msg" / "Mark.msg").write_text("std_msgs/Header header\n"
                                           "robot_test_msgs/Spot spot  # where\n")
    return base, more


def test_the_generators_are_those_shary_interfaces_is_built_with():
    pyproject = Path(__file__).parent.parent / "ros" / "shary_interfaces" / "pyproject.toml"
    block = pyproject.read_text().split("requires = [", 1)[1].split("]", 1)[0]
    wanted = re.findall(r'^\s*"([^"]+)"', block, re.MULTILINE)
    assert sorted(GENERATORS) == sorted(wanted)


def test_a_package_needed_that_is_neither_given_nor_installed_is_an_error(shary, tmp_path):
    _, more = sources(tmp_path)
    status, _, err = shary("ros", "interfaces", str(more))
    assert status == 2
    [found] = problems(err)
    assert (found["file"], found["line"], found["col"]) == (
        str(more / "msg" / "Mark.msg"), "2", "1")
    assert found["message"] == (
        "robot_test_more_msgs needs robot_test_msgs, which is neither among the sources "
        "given nor installed here: give its source folder too (shary ros interfaces "
        "…/robot_test_msgs …/robot_test_more_msgs)")


def test_a_folder_that_is_no_package_is_an_error(shary, tmp_path):
    status, _, err = shary("ros", "interfaces", str(tmp_path))
    assert status == 2
    assert "not an interface package's source: it has no package.xml" in err


@needs_ros
def test_packages_are_built_in_order_and_a_binding_naming_them_validates(tmp_path):
    base, more = sources(tmp_path / "src")
    env_dir = tmp_path / "venv"
    venv.create(env_dir, system_site_packages=True, with_pip=True)
    python = str(env_dir / "bin" / "python")
    here = str(Path(__file__).parent.parent)
    env = {"PYTHONPATH": here, "PATH": "/usr/bin:/bin"}
    done = subprocess.run([python, "-m", "shary", "ros", "interfaces", str(more), str(base)],
                          capture_output=True, text=True, env=env, timeout=900)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "building robot_test_msgs, robot_test_more_msgs (in this order)" in done.stdout
    # rclpy's way in: the generated types, their type supports beside the ROS wheels'
    code = ("from shary.ros.env import ros_environment; import subprocess, sys; "
            "sys.exit(subprocess.run([sys.executable, '-c', 'import rclpy; "
            "from robot_test_more_msgs.msg import Mark; "
            "from robot_test_msgs.action import GoTo; "
            "from rclpy.serialization import serialize_message as s; "
            "m = Mark(); m.spot.x = 2.5; print(len(s(m)), GoTo.Goal().pose.header)'], "
            "env=ros_environment()).returncode)")
    used = subprocess.run([python, "-c", code], capture_output=True, text=True, env=env,
                          timeout=120)
    assert used.returncode == 0, used.stdout + used.stderr
    assert "std_msgs.msg.Header(" in used.stdout
    binding = tmp_path / "robot.yaml"
    binding.write_text("binding: built\nrobot: jido\ntasks:\n  navigate:\n    action: /go\n"
                       "    type: robot_test_msgs/action/GoTo\n"
                       "    goal: {place: \"{place}\", pose.header.frame_id: map}\n")
    checked = subprocess.run([python, "-m", "shary", "validate", str(binding)],
                             capture_output=True, text=True, env=env, timeout=120)
    assert checked.returncode == 0 and "note" not in checked.stderr, checked.stderr
    assert sys.prefix not in done.stdout  # into the test's environment, not this one
