"""shary on ROS 2: a node that drives a robot's actions, reads its perception and
people, and shows its state to ROS tools (docs/ros2.md).

Only this package imports rclpy (the ``ros`` extra: ``pip install '.[ros]'``);
the engine, the planner and the simulator never do.  Its modules, one per
concept: :mod:`~shary.ros.env` (the wheels' libraries, traffic kept on this
host), :mod:`~shary.ros.binding` (the robot binding file), :mod:`~shary.ros.node`
(the one node, spun by the engine's loop), :mod:`~shary.ros.executors`
(atomic tasks as actions, services and topics), :mod:`~shary.ros.resources` (one
goal per part of the robot and per server), :mod:`~shary.ros.perception` (topics into
facts and person acts), :mod:`~shary.ros.qos` (quality of service per topic, and
publishers that do not match), :mod:`~shary.ros.views` (state for ROS tools),
:mod:`~shary.ros.clock` (the engine on ROS time), :mod:`~shary.ros.stop` (stopping
without leaving the robot moving), :mod:`~shary.ros.lifeline` (child processes that die
with their parent), :mod:`~shary.ros.interfaces` (a robot's interface packages built
from their sources).
"""
