"""HRI/OS on shary's kernel: a team of robots, people and software agents as peers.

The parts (docs/teams.md):

- :mod:`shary.team.spec` and :mod:`shary.team.teamfile`: the team file
  (agents, skills, behaviours, questions, scoring, the goal's tasks);
- :mod:`shary.transport.messages`: the typed messages and the message port;
- :mod:`shary.team.agents` (what every member has; software agents),
  :mod:`shary.team.robot` (robot agents: a supervisor each; breakpoints,
  association, control authority), :mod:`shary.team.proxy` (human proxies);
- :mod:`shary.team.tasks`: the Task Manager;
- :mod:`shary.team.resources`: the Resource Manager and its criteria;
- :mod:`shary.team.interaction`: the Interaction Manager (questions, help);
- :mod:`shary.team.context`: the Context Manager (summaries of the log);
- :mod:`shary.team.team`: :class:`Team`, which builds and runs all of them.
"""

from shary.team.agents import Agent, SoftwareAgent
from shary.team.proxy import HumanProxy
from shary.team.robot import RobotAgent
from shary.team.spec import QuestionSpec, TeamSpec
from shary.team.team import AgentLog, Team
from shary.team.teamfile import load_team, robot_library

__all__ = ["Agent", "AgentLog", "HumanProxy", "QuestionSpec", "RobotAgent", "SoftwareAgent",
           "Team", "TeamSpec", "load_team", "robot_library"]
