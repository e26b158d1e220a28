"""Team files -> :class:`~shary.team.spec.TeamSpec`, with every meaning check.

The pipeline is :func:`userfiles.reader.read`'s (safe load, the JSON Schema
``shary/schemas/team.schema.json``, then the checks below), so every problem
reads ``FILE:LINE:COL: error: …``.  Meaning checks: each robot skill is a
task of the recipe files; each task's skill is some agent's (among those of
``by`` when given); ``after`` and ``respawn`` name tasks, without a cycle, and
a task respawns one it depends on; questions are consistent (choices only for
a choice question, a fallback and accepted answers a question can have);
behaviours belong to humans, services to software agents; the scoring names
known criteria, and AHP comparisons are consistent (planner/evaluation/ahp.py).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from shary.io.schema import validator
from shary.kernel.recipes import RecipeLibrary
from shary.team.resources import CRITERIA, DEFAULT_WEIGHTS
from shary.team.spec import (
    ANSWER,
    HUMAN,
    ROBOT,
    SOFTWARE,
    WATCHDOG,
    AgentSpec,
    Behaviour,
    Delay,
    HelpRequest,
    QuestionSpec,
    Reply,
    TaskSpec,
    TeamSpec,
)
from userfiles.errors import FileError
from userfiles.reader import Reader, read, spelled
from userfiles.schema import did_you_mean

TEAM_LIBRARY = Path(__file__).resolve().parent / "team-recipes.yaml"
"""The atomic tasks the team gives every robot (``ask``)."""


def load_team(path: str | os.PathLike[str], *, text: str | None = None) -> TeamSpec:
    """Read and check a team file (FileError with every problem); ``text``, when given,
    is read in place of the file's own, as if it were that file."""
    return read(path, validator("team"), lambda reader: _Meaning(reader).team(), text=text)


def robot_library(spec: TeamSpec) -> RecipeLibrary:
    """The recipe library of a team's robots: the built-in one, the team's atomic tasks
    and the team file's recipe files."""
    from shary.io.recipes import load_library

    return load_library([TEAM_LIBRARY, *spec.recipes])


class _Meaning:
    def __init__(self, reader: Reader):
        self.reader = reader
        self.problem = reader.problem

    def team(self) -> TeamSpec:
        data = self.reader.data
        library, recipes = self.library()
        self.tasks_of_robots = library.tasks if library is not None else None
        agents = {name: self.agent(name, raw, library)
                  for name, raw in data["agents"].items()}
        questions = {topic: self.question(topic, raw)
                     for topic, raw in (data.get("questions") or {}).items()}
        self.answers(agents, questions)
        tasks = {name: self.task(name, raw, agents)
                 for name, raw in data["goal"]["tasks"].items()}
        self.constraints(tasks)
        self.requests(agents)
        return TeamSpec(data["team"], agents, tasks, self.weights(), questions,
                        tuple(recipes), data.get("doc", ""), self.reader.file,
                        self.watchdog())

    # -- recipes ------------------------------------------------------------------

    def library(self) -> tuple[RecipeLibrary | None, list[Path]]:
        reader = self.reader
        files: list[Path] = []
        for index, name in enumerate(reader.data.get("recipes") or []):
            full = reader.confined_path(("recipes", index), name)
            if full is not None:
                files.append(full)
        if len(files) < len(reader.data.get("recipes") or []):
            return None, files
        from shary.io.recipes import load_library

        try:
            library = load_library([TEAM_LIBRARY, *(spelled(f, like=reader.file)
                                                    for f in files)])
        except FileError as err:
            reader.problems.extend(err.problems)
            named = {spelled(f, like=reader.file): i for i, f in enumerate(files)}
            for file in sorted({p.file for p in err.problems}):
                index = named.get(file)
                self.problem(("recipes", index) if index is not None else ("recipes",),
                             f"depends on {file}, which has errors")
            return None, files
        return library, files

    # -- agents -------------------------------------------------------------------

    def agent(self, name: str, raw: dict[str, Any], library: RecipeLibrary | None) -> AgentSpec:
        where = ("agents", name)
        kind = raw["kind"]
        skills = tuple(raw.get("skills") or ())
        if kind == ROBOT and library is not None:
            for index, skill in enumerate(skills):
                if skill not in library.tasks:
                    self.problem(where + ("skills", index),
                                 f"robot {name}'s skill {skill!r} is not a task of the recipe "
                                 f"files{did_you_mean(skill, library.tasks)} (a robot does a "
                                 "team task by running it on its supervisor)")
        for key, allowed in (("behaviour", HUMAN), ("remote", HUMAN), ("services", SOFTWARE)):
            if key in raw and kind != allowed:
                self.problem(where + (key,), f"only a {allowed} agent has '{key}' ({name} is a "
                             f"{kind})", key=True)
        if kind == SOFTWARE and skills:
            self.problem(where + ("skills",), f"a software agent offers services, not skills "
                         f"(write 'services:' for {name})", key=True)
        at = raw.get("at")
        behaviour = self.behaviour(where + ("behaviour",), raw["behaviour"], skills) \
            if "behaviour" in raw else None
        return AgentSpec(name, kind, skills, tuple(raw.get("resources") or ()),
                         tuple(raw.get("services") or ()), tuple(at) if at else None,
                         bool(raw.get("remote", False)), behaviour, raw.get("doc", ""))

    def delay(self, where: tuple, value: Any) -> Delay:
        if isinstance(value, list):
            low = self.reader.duration(where + (0,), value[0])
            high = self.reader.duration(where + (1,), value[1])
            if high < low:
                self.problem(where, f"[{value[0]}, {value[1]}]: the high end is below the "
                             "low end")
            return low, max(low, high)
        amount = self.reader.duration(where, value)
        return amount, amount

    def reply(self, where: tuple, raw: dict[str, Any] | None, allowed: tuple[str, ...],
              default: Reply) -> Reply:
        if raw is None:
            return default
        if raw["reply"] not in allowed:
            self.problem(where + ("reply",), f"{raw['reply']!r} is not a reply here (one of "
                         f"{', '.join(allowed)})")
        after = self.delay(where + ("after",), raw["after"]) if "after" in raw else default.after
        return Reply(raw["reply"], after)

    def behaviour(self, where: tuple, raw: dict[str, Any], skills: tuple[str, ...]) -> Behaviour:
        default = Behaviour()
        works_raw = raw.get("works")
        works: dict[str, Delay] = {}
        if isinstance(works_raw, dict):
            for skill, value in works_raw.items():
                if skill not in skills and skill != "*":
                    self.problem(where + ("works", skill), f"{skill!r} is not one of this "
                                 f"person's skills ({', '.join(skills) or 'none'})", key=True)
                works[skill] = self.delay(where + ("works", skill), value)
        elif works_raw is not None:
            works["*"] = self.delay(where + ("works",), works_raw)
        requests = tuple(
            HelpRequest(self.reader.duration(where + ("requests", i, "at"), r["at"]), r["ask"],
                        dict(r.get("with") or {}),
                        self.reader.duration(where + ("requests", i, "release"),
                                             r.get("release", 10)))
            for i, r in enumerate(raw.get("requests") or []))
        return Behaviour(
            self.reply(where + ("assignments",), raw.get("assignments"),
                       ("accept", "refuse", "ignore"), default.assignments),
            self.reply(where + ("questions",), raw.get("questions"),
                       (ANSWER, "refuse", "ignore"), default.questions),
            works, dict(raw.get("answers") or {}), requests)

    def requests(self, agents: dict[str, AgentSpec]) -> None:
        robot_skills = {s for a in agents.values() if a.kind == ROBOT for s in a.skills}
        for agent in agents.values():
            if agent.behaviour is None:
                continue
            for index, request in enumerate(agent.behaviour.requests):
                if request.ask not in robot_skills:
                    self.problem(("agents", agent.name, "behaviour", "requests", index, "ask"),
                                 f"no robot of the team has the skill {request.ask!r}"
                                 f"{did_you_mean(request.ask, robot_skills)}")

    # -- questions ----------------------------------------------------------------

    def question(self, topic: str, raw: dict[str, Any]) -> QuestionSpec:
        where = ("questions", topic)
        kind = raw.get("type", "yes-no")
        choices = tuple(raw.get("choices") or ())
        if kind == "choice" and not choices:
            self.problem(where + ("type",), "a choice question lists its 'choices'")
        if kind != "choice" and choices:
            self.problem(where + ("choices",), f"only a choice question has choices (this one "
                         f"is {kind})", key=True)
        possible = {"yes-no": ("yes", "no"), "choice": choices}.get(kind)
        if possible:
            for key in ("accept", "fallback"):
                values = raw.get(key)
                for index, value in enumerate(values if isinstance(values, list) else
                                              [values] if values is not None else []):
                    if value not in possible:
                        self.problem(where + ((key, index) if isinstance(values, list)
                                              else (key,)),
                                     f"{value!r} is not an answer to this question (one of "
                                     f"{', '.join(possible)})")
        priority = int(raw.get("priority", 0))
        expires = self.reader.duration(where + ("expires",), raw.get("expires", 60))
        return QuestionSpec(topic, raw["text"], kind, choices, priority, expires,
                            bool(raw.get("wait", priority >= 5)), tuple(raw.get("accept") or ()),
                            raw.get("fallback"))

    def answers(self, agents: dict[str, AgentSpec], questions: dict[str, QuestionSpec]) -> None:
        """A simulated person's answer to a declared question must be one it can have."""
        for agent in agents.values():
            for topic, value in (agent.behaviour.answers if agent.behaviour else {}).items():
                question = questions.get(topic)
                possible = (("yes", "no") if question is not None and question.type == "yes-no"
                            else question.choices if question is not None else ())
                if possible and value not in possible:
                    self.problem(("agents", agent.name, "behaviour", "answers", topic),
                                 f"{value!r} is not an answer to {question.text!r} (one of "
                                 f"{', '.join(possible)})")

    # -- the goal -----------------------------------------------------------------

    def task(self, name: str, raw: dict[str, Any], agents: dict[str, AgentSpec]) -> TaskSpec:
        where = ("goal", "tasks", name)
        skill = raw["do"]
        candidates = [agents[a] for a in raw.get("by") or () if a in agents]
        for index, agent in enumerate(raw.get("by") or ()):
            if agent not in agents:
                self.problem(where + ("by", index), f"no agent {agent!r} in the team"
                             f"{did_you_mean(agent, agents)}")
        pool = candidates or list(agents.values())
        needs = tuple(raw.get("needs") or ())
        among = f"among {', '.join(raw['by'])} " if candidates else ""
        if not any(skill in a.skills for a in pool):
            known = sorted({s for a in pool for s in a.skills})
            self.problem(where + ("do",), f"nobody {among}has the skill {skill!r}"
                         f"{did_you_mean(skill, known)}")
        elif needs and not any(skill in a.skills and set(needs) <= set(a.resources)
                               for a in pool):
            self.problem(where + ("needs",), f"nobody {among}with the skill {skill!r} has "
                         f"{', '.join(needs)} (they have: "
                         + "; ".join(f"{a.name}: {', '.join(a.resources) or 'nothing'}"
                                     for a in pool if skill in a.skills) + ")")
        robots = [a for a in pool if a.kind == ROBOT and skill in a.skills]
        if robots and self.tasks_of_robots is not None and skill in self.tasks_of_robots:
            params = self.tasks_of_robots[skill].params
            given = raw.get("with") or {}
            missing = [p for p in params if p not in given]
            for arg in given:
                if arg not in params:
                    self.problem(where + ("with", arg), f"{skill} has no parameter {arg!r}"
                                 f"{did_you_mean(arg, params)}; its parameters: "
                                 f"{', '.join(params) or 'none'}", key=True)
            if missing:
                self.problem(where + ("do",), f"{skill} needs {', '.join(missing)} "
                             "(under 'with:')")
        at = raw.get("at")
        within = self.reader.duration(where + ("reply-within",), raw.get("reply-within", 30))
        return TaskSpec(name, skill, dict(raw.get("with") or {}), tuple(raw.get("after") or ()),
                        tuple(raw.get("by") or ()), needs, tuple(at) if at else None,
                        int(raw.get("attempts", 2)), raw.get("respawn"), within or 30.0,
                        raw.get("doc", ""))

    def watchdog(self) -> float:
        """The goal's ``watchdog``: a duration above 0 (a watchdog of 0s would act at once,
        and again at once after each look, and the goal would never be left to run)."""
        raw = self.reader.data["goal"].get("watchdog")
        if raw is None:
            return WATCHDOG
        where, found = ("goal", "watchdog"), len(self.reader.problems)
        idle = self.reader.duration(where, raw)
        if len(self.reader.problems) > found:  # not a duration, or too long: said
            return WATCHDOG
        if idle <= 0:
            self.problem(where, f"a watchdog of {raw} would act at once, and again after "
                         "each look: give it more than 0s (the default is 5min)")
            return WATCHDOG
        return idle

    def constraints(self, tasks: dict[str, TaskSpec]) -> None:
        for task in tasks.values():
            for index, before in enumerate(task.after):
                if before not in tasks:
                    self.problem(("goal", "tasks", task.name, "after", index),
                                 f"no task {before!r} in the goal{did_you_mean(before, tasks)}")
                elif before == task.name:
                    self.problem(("goal", "tasks", task.name, "after", index),
                                 f"{task.name} cannot come after itself")
        cycle = _cycle(tasks)
        if cycle:
            self.problem(("goal", "tasks", cycle[0], "after"),
                         f"the tasks wait for each other in a cycle: {' -> '.join(cycle)}")
            return
        respawning = [t for t in tasks.values() if t.respawn is not None]
        before = _ancestors(tasks) if respawning else {}
        position = {name: i for i, name in enumerate(tasks)}
        for task in respawning:
            assert task.respawn is not None
            where = ("goal", "tasks", task.name, "respawn")
            if task.respawn not in tasks:
                self.problem(where, f"no task {task.respawn!r} in the goal"
                             f"{did_you_mean(task.respawn, tasks)}")
            elif not before[task.name] >> position[task.respawn] & 1:
                self.problem(where, f"{task.name} can only respawn a task it comes after "
                             f"({task.respawn} is not before it)")

    # -- scoring ------------------------------------------------------------------

    def weights(self) -> dict[str, float]:
        raw = self.reader.data.get("scoring") or {}
        if "weights" in raw and "compare" in raw:
            self.problem(("scoring", "compare"), "give either weights or comparisons", key=True)
        if "compare" in raw:
            return self.compared(raw["compare"])
        weights = dict(raw.get("weights") or DEFAULT_WEIGHTS)
        for name in weights:
            if name not in CRITERIA:
                self.problem(("scoring", "weights", name), f"unknown criterion {name!r}"
                             f"{did_you_mean(name, CRITERIA)} (known: {', '.join(CRITERIA)})",
                             key=True)
        total = sum(weights.values())
        if total <= 0:
            self.problem(("scoring", "weights"), "at least one weight must be above 0")
            return dict(DEFAULT_WEIGHTS)
        return {k: v / total for k, v in weights.items()}

    def compared(self, raw: dict[str, dict[str, float]]) -> dict[str, float]:
        from planner.evaluation.ahp import AHPError, priority_vector

        names = list(dict.fromkeys([*raw, *(o for row in raw.values() for o in row)]))
        for name in names:
            if name not in CRITERIA:
                where = ("scoring", "compare", name) if name in raw else ("scoring", "compare")
                self.problem(where, f"unknown criterion {name!r}{did_you_mean(name, CRITERIA)} "
                             f"(known: {', '.join(CRITERIA)})", key=name in raw)
        index = {n: i for i, n in enumerate(names)}
        matrix = [[1.0] * len(names) for _ in names]
        for a, row in raw.items():
            for b, value in row.items():
                if a == b:
                    self.problem(("scoring", "compare", a, b), "a criterion is not compared "
                                 "with itself", key=True)
                    continue
                if (b in raw and a in raw[b]):
                    if abs(raw[b][a] * value - 1) > 1e-6 and index[a] < index[b]:
                        self.problem(("scoring", "compare", a, b), f"{a} vs {b} is {value:g} "
                                     f"but {b} vs {a} is {raw[b][a]:g}: give one of them (the "
                                     "other is its reciprocal)", key=True)
                matrix[index[a]][index[b]] = value
                matrix[index[b]][index[a]] = 1.0 / value
        if self.reader.problems:
            return dict(DEFAULT_WEIGHTS)
        try:
            result = priority_vector(matrix)
        except AHPError as err:
            self.problem(("scoring", "compare"), f"the comparisons cannot be used: {err.message}",
                         key=True)
            return dict(DEFAULT_WEIGHTS)
        return dict(zip(names, result.weights, strict=True))


def _cycle(tasks: dict[str, TaskSpec]) -> list[str]:
    """One cycle of ``after`` constraints (first and last the same), or [] (iterative)."""
    state: dict[str, int] = {}
    for root in tasks:
        if root in state:
            continue
        stack = [(root, iter(tasks[root].after))]
        path = [root]
        state[root] = 1
        while stack:
            node, children = stack[-1]
            child = next((c for c in children if c in tasks), None)
            if child is None:
                state[node] = 2
                stack.pop()
                path.pop()
            elif state.get(child) == 1:
                return [*path[path.index(child):], child]
            elif child not in state:
                state[child] = 1
                stack.append((child, iter(tasks[child].after)))
                path.append(child)
    return []


def _ancestors(tasks: dict[str, TaskSpec]) -> dict[str, int]:
    """Task -> the tasks it comes after, directly or not, as a bit set over the tasks'
    order (an int): linear in the constraints, so ten thousand tasks that each respawn
    the first one cost milliseconds, not a walk of the chain each.  No cycle allowed."""
    bit = {name: 1 << i for i, name in enumerate(tasks)}
    found: dict[str, int] = {}
    for root in tasks:
        stack = [root]
        while stack:
            name = stack[-1]
            if name in found:
                stack.pop()
                continue
            pending = [b for b in tasks[name].after if b in tasks and b not in found]
            if pending:
                stack.extend(pending)
                continue
            stack.pop()
            total = 0
            for b in tasks[name].after:
                if b in tasks:
                    total |= found[b] | bit[b]
            found[name] = total
    return found
