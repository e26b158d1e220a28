"""Scenario files: a scene, people with profiles, goals, faults, and the expected outcome.

A scenario (``sim/scenarios/*.yaml``, or any file) is loaded safely, checked
against ``sim/schemas/scenario.schema.json`` and then for meaning — places,
objects, furniture, profiles, tasks, acts and atomic tasks must exist — and
every problem is reported as ``FILE:LINE:COL: error: …`` at once.  Profiles
are named (``sim/profiles/NAME.yaml``) or written inline.

The ``expect`` section is read into a :class:`sim.judge.Expect`, with which
:func:`sim.judge.judge` compares what a run did.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

from shary.io.recipes import load_library
from shary.kernel.recipes import RecipeLibrary
from shary.recognition.models import builtin_models, load_action_models
from shary.statechart.acts import ActRegistry, builtin_acts
from userfiles import yamlsafe
from userfiles.errors import FileError
from userfiles.reader import Reader, read, spelled
from userfiles.schema import did_you_mean

from .humans import HUMAN_PLACES, Profile, profile_from
from .judge import Expect
from .objects import check_new_objects, is_new
from .room import BOTTLES, FOOTPRINTS, FURNITURE, PLACES
from .schemafiles import schema

HERE = Path(__file__).resolve().parent
SCENARIOS_DIR = HERE / "scenarios"
PROFILES_DIR = HERE / "profiles"
DEFAULT_TIMEOUT = 180.0
PLANNING_DOMAIN = "living-room"
"""The domain a run's planner-backed recipes plan in."""


@dataclass(frozen=True)
class Person:
    name: str
    at: str
    profile: Profile
    shirt: tuple[float, float, float]
    attributes: dict[str, Any]


@dataclass(frozen=True)
class Goal:
    task: str
    args: dict[str, Any]
    at: float
    priority: int


@dataclass(frozen=True)
class Scenario:
    """A checked scenario (see the module's docstring)."""

    name: str
    file: Path
    doc: str
    robot: str
    model: str
    robot_at: str
    people: tuple[Person, ...]
    objects: dict[str, dict[str, Any]]
    recipes: tuple[Path, ...]
    goals: tuple[Goal, ...]
    flicker: dict[str, float]
    lost: tuple[tuple[str, float, float], ...]
    hold: float
    faults: tuple[tuple[str, str, int], ...]  # action, reason, how many times
    timeout: float
    expect: Expect
    library: RecipeLibrary | None = None
    """The recipe library the scenario was checked against and runs with."""
    action_models: tuple[Path, ...] = ()
    """Action model files the robot recognizes people's actions with (shary.recognition)."""
    shared_plan: dict[str, Any] | None = None
    """A shared plan to follow with a partner (``shared-plan:``, :mod:`sim.stack`)."""


def builtin_profiles() -> list[Path]:
    return sorted(PROFILES_DIR.glob("*.yaml"))


def builtin_scenarios() -> dict[str, Path]:
    """Scenario name -> file, for the scenarios shipped in ``sim/scenarios``."""
    return {p.stem: p for p in sorted(SCENARIOS_DIR.glob("*.yaml"))}


def find_scenario(name_or_file: str) -> Path:
    """A scenario file from a path or a built-in name (KeyError naming the choices)."""
    path = Path(name_or_file)
    if path.suffix in (".yaml", ".yml") or path.exists():
        return path
    found = builtin_scenarios().get(name_or_file)
    if found is None:
        names = list(builtin_scenarios())
        raise KeyError(f"no scenario named {name_or_file!r}{did_you_mean(name_or_file, names)}"
                       f"; scenarios: {', '.join(names)}")
    return found


_TEXT_PARAMS = frozenset({"text"})
"""Task parameters whose value is words to say (the inform task's), not a thing."""
_WORD_VALUED = frozenset({"type", "color"})
"""Predicates whose object is a word (a class, a colour), not a thing of the scenario."""


@cache
def _simulated_atomic() -> frozenset[str]:
    """The atomic tasks the simulated robot performs: the built-in library's (each has
    an executor in :mod:`sim.executors`; tests/test_validation.py holds them together)."""
    return frozenset(load_library().atomic)


@cache
def _domain_attributes() -> frozenset[str]:
    """The attributes of the planning domain runs use: the run states them as facts."""
    import planner

    domain = planner.load_domain(PLANNING_DOMAIN)
    return frozenset(a for kind in domain.types.values() for a in kind.attributes)


def load_profile(name: str | Path, things: set[str] = frozenset(),
                 acts: set[str] = frozenset(), atomic: set[str] = frozenset()) -> Profile:
    """A profile, by name (``sim/profiles/NAME.yaml``) or file (a path, or a string
    ending in ``.yaml``), checked; the names, acts
    and atomic tasks given (when given) are what its targets and answers may name."""
    path = Path(name) if isinstance(name, Path) or name.endswith((".yaml", ".yml")) \
        else PROFILES_DIR / f"{name}.yaml"

    def meaning(reader: Reader) -> Profile:
        _check_profile(reader, (), reader.data, things, acts, atomic)
        return profile_from(path.stem, reader.data)

    return read(path, schema("profile"), meaning)


def load_scenario(path: str | Path, *, acts: ActRegistry | None = None,
                  text: str | None = None) -> Scenario:
    """Load and check a scenario with the recipe library it names (built-in recipes plus
    its ``recipes:`` files, which must stay below its folder); raise :class:`FileError`
    listing every problem, the recipe files' own included, each once.

    ``acts`` are the acts known besides the library's (e.g. an acts file given to
    ``shary validate`` with the scenario).  ``text`` is a living-room scenario read in
    place of the file's own text, as if it were that file (``shary fuzz`` varies a
    built-in scenario in memory this way).
    """
    path = Path(path)
    if text is None and is_team_scenario(path):
        from .weld.scenario import load_weld_scenario

        return load_weld_scenario(path)  # type: ignore[return-value]
    return read(path, schema("scenario"), lambda reader: _Reading(reader, acts).scenario(),
                text=text)


def is_team_scenario(path: str | Path) -> bool:
    """Whether a scenario file runs a team on a site (``site: seam-welding``, see
    :mod:`sim.weld.scenario`) rather than one robot in the living room."""
    try:
        data = yamlsafe.load_file(path).data
    except (FileError, OSError):
        return False  # the scenario reader reports what is wrong with it
    return isinstance(data, dict) and "site" in data


class _Reading:
    """The meaning checks of one scenario (the pipeline's third step)."""

    def __init__(self, reader: Reader, acts: ActRegistry | None):
        self.reader = reader
        self.problem = reader.problem
        self.extra_acts = acts
        self.profiles: dict[str, Profile | None] = {}
        """Named profiles read so far: fifty people naming one profile read it once."""

    def library(self) -> tuple[RecipeLibrary | None, list[Path]]:
        """The recipe library the scenario runs with, or None when a file of it is bad
        (its problems are reported, and the scenario's line that names it)."""
        reader = self.reader
        files = []
        named = {}
        for i, name in enumerate(reader.data.get("recipes") or []):
            full = reader.confined_path(("recipes", i), name)
            if full is not None:
                files.append(full)
                named[spelled(full, like=reader.file)] = i
        if len(files) < len(reader.data.get("recipes") or []):
            return None, files  # a refused file: its tasks and acts are unknown, not wrong
        try:
            library = load_library([spelled(f, like=reader.file) for f in files],
                                   acts=self.extra_acts)
        except FileError as err:
            reader.problems.extend(err.problems)
            for file in sorted({p.file for p in err.problems}):
                index = named.get(file)
                where = ("recipes", index) if index is not None else ("recipes",)
                self.problem(where, f"depends on {file}, which has errors")
            return None, files
        performs = _simulated_atomic()
        for name in sorted(set(library.atomic) - performs):
            self.problem(("recipes",), f"the atomic task {name!r} that the recipe files declare "
                         "has no executor in the simulation, so a run would fail at it (the "
                         f"simulated robot performs: {', '.join(sorted(performs))})", key=True)
        return library, files

    def scenario(self) -> Scenario:
        reader, problem = self.reader, self.problem
        data = reader.data
        library, recipes = self.library()
        known_tasks = ({n: t for n, t in library.tasks.items()} if library is not None
                       else None)
        # Without its library (a named file is bad), the acts it declares are unknown:
        # the checks that need them wait until it is fixed.
        acts = (set(library.acts.vocabulary()) if library is not None
                else set() if data.get("recipes")
                else set((self.extra_acts or builtin_acts()).vocabulary()))
        atomic = set(library.atomic) if library is not None else set()
        predicates = set(library.predicates) if library is not None else set()
        robot = data.get("robot") or {}
        robot_name = robot.get("name", "jido")
        people_spec = data.get("people") or {}
        everyone = {robot_name, *people_spec}
        objects_spec = data.get("objects") or {}
        objects_known = set(BOTTLES) | set(objects_spec)
        things = everyone | objects_known | set(FURNITURE)
        if data.get("shared-plan") is not None:  # the stack table's objects (sim/stack)
            from .stack.table import LAYOUT

            things |= set(LAYOUT)
        robot_at = robot.get("at", "base")
        if robot_at not in PLACES:
            problem(("robot", "at"), f"unknown place {robot_at!r}"
                    f"{did_you_mean(robot_at, PLACES)}; places: {', '.join(PLACES)}")
        people = [self.person(name, spec, robot_name, things, acts, atomic)
                  for name, spec in people_spec.items()]
        names = {p.name for p in people if p is not None}
        check_new_objects(objects_spec, everyone | set(BOTTLES) | set(FURNITURE) | set(PLACES),
                          problem)
        objects = {obj: self.thing(obj, spec, names) for obj, spec in objects_spec.items()}
        goals = [self.goal(i, spec, known_tasks, everyone, things)
                 for i, spec in enumerate(data.get("goals") or [])]
        timeout = reader.duration(("timeout",), data.get("timeout", DEFAULT_TIMEOUT))
        for i, goal in enumerate(goals):
            if goal.at >= timeout > 0:
                problem(("goals", i, "at"), f"the goal at {goal.at:g}s comes after the run's "
                        f"timeout ({timeout:g}s): it would never be pursued")
        noise = data.get("noise") or {}
        lost = []
        for i, e in enumerate(noise.get("lost") or []):
            where = ("noise", "lost", i)
            start, end = (reader.duration(where + ("from",), e["from"]),
                          reader.duration(where + ("to",), e["to"]))
            if e["entity"] not in things:
                problem(where + ("entity",), f"unknown entity {e['entity']!r}"
                        f"{did_you_mean(e['entity'], things)}")
            if end < start:
                problem(where + ("to",), f"'to' ({end:g}s) comes before 'from' ({start:g}s)")
            lost.append((e["entity"], start, end))
        for predicate in noise.get("flicker") or {}:
            if predicates and predicate not in predicates:
                problem(("noise", "flicker", predicate), f"unknown predicate {predicate!r}"
                        f"{did_you_mean(predicate, predicates)}", key=True)
        raw_expect = data["expect"]
        if library is not None:
            self.facts(raw_expect, set(library.predicates), things | set(PLACES),
                       {key for spec in people_spec.values() for key in spec.get("kind") or {}})
        for key in ("acts", "no-acts"):
            for i, act in enumerate(raw_expect.get(key) or []):
                if acts and act not in acts:
                    problem(("expect", key, i), f"unknown act {act!r}"
                            f"{did_you_mean(act, acts)}; declare it under 'acts:' in a "
                            "recipe file the scenario names, or in the scheme of its task")
        faults = []
        for i, spec in enumerate(data.get("faults") or []):
            if atomic and spec["action"] not in atomic:
                problem(("faults", i, "action"), f"unknown atomic task {spec['action']!r}"
                        f"{did_you_mean(spec['action'], atomic)}")
            faults.append((spec["action"], spec.get("reason", "an injected fault"),
                           int(spec.get("times", 1))))
        for key in ("actions", "no-actions", "failed-actions"):
            for i, name in enumerate(raw_expect.get(key) or []):
                if atomic and name not in atomic:
                    problem(("expect", key, i), f"unknown atomic task {name!r}"
                            f"{did_you_mean(name, atomic)}")
        if known_tasks is not None:
            for task in raw_expect.get("tasks") or {}:
                if task not in known_tasks:
                    problem(("expect", "tasks", task), f"unknown task {task!r}"
                            f"{did_you_mean(task, known_tasks)}", key=True)
        within = (reader.duration(("expect", "within"), raw_expect["within"])
                  if "within" in raw_expect else None)
        expect = Expect(
            tuple(raw_expect.get("acts") or ()), tuple(raw_expect.get("no-acts") or ()),
            tuple(raw_expect.get("actions") or ()), tuple(raw_expect.get("no-actions") or ()),
            tuple(raw_expect.get("failed-actions") or ()),
            tuple(tuple(f) for f in raw_expect.get("facts") or ()),
            tuple(tuple(f) for f in raw_expect.get("no-facts") or ()),
            dict(raw_expect.get("tasks") or {}), within,
            tuple(raw_expect.get("plan") or ()), tuple(raw_expect.get("said") or ()),
            tuple(tuple(t) for t in raw_expect.get("task-states") or ()),
            tuple(tuple(t) for t in raw_expect.get("recognized") or ()))
        shared = data.get("shared-plan")
        if shared is not None:  # a shared plan of the stack domain (sim/stack)
            from planner import builtin_problems  # (only then: the planner loads numpy)

            shared = dict(shared)
            if shared.get("partner") not in {p.name for p in people if p is not None}:
                problem(("shared-plan", "partner"), f"the partner {shared.get('partner')!r} "
                        "is not one of the scenario's people")
            if not data.get("action-models"):
                problem(("shared-plan",), "a shared plan needs action-models (e.g. [stack])")
            stack = sorted(p.stem for p in builtin_problems() if p.stem.startswith("stack"))
            name = str(shared.get("problem"))
            if name not in stack and not (Path(reader.file).parent / name).is_file():
                problem(("shared-plan", "problem"), f"no planner problem {name!r}"
                        f"{did_you_mean(name, stack)}: a file next to this one, or one of "
                        f"{', '.join(stack)}")
            elif name not in stack:
                full = reader.confined_path(("shared-plan", "problem"), name)
                if full is not None:
                    shared["problem"] = str(full)
            away = (shared.get("profile") or {}).get("look-away")
            aways = away if isinstance(away, list) else [] if away is None else [away]
            for i, each in enumerate(aways):
                if ("during" in each) == ("at" in each):
                    where = ("shared-plan", "profile", "look-away")
                    problem(where + ((i,) if isinstance(away, list) else ()),
                            "look-away needs when: during (a robot task's label) or at "
                            "(seconds after the start), one of them")
            shared["decision-wait"] = reader.duration(("shared-plan", "decision-wait"),
                                                      shared.get("decision-wait", 6.0))
        return Scenario(
            data["scenario"], Path(reader.file), str(data.get("doc", "")).strip(), robot_name,
            robot.get("model", "jido"), robot_at, tuple(p for p in people if p is not None),
            objects, tuple(recipes), tuple(goals), dict(noise.get("flicker") or {}),
            tuple(lost), reader.duration(("noise", "hold"), noise.get("hold", 0.5)),
            tuple(faults), timeout,
            expect, library, self.action_models(library), shared)

    def action_models(self, library: RecipeLibrary | None) -> tuple[Path, ...]:
        """The action model files named (built-in sets by name), checked together."""
        reader, files = self.reader, []
        for i, name in enumerate(reader.data.get("action-models") or []):
            if name.endswith((".yaml", ".yml")):
                full = reader.confined_path(("action-models", i), name)
            else:
                try:
                    full = builtin_models(name)
                except FileNotFoundError as err:
                    reader.problem(("action-models", i), str(err).strip("'\""))
                    full = None
            if full is not None:
                files.append(full)
        if files and len(files) == len(reader.data.get("action-models") or []):
            try:
                load_action_models(files, atomic=None if library is None else library.atomic)
            except FileError as err:
                reader.problems.extend(err.problems)
                reader.problem(("action-models",), "depends on action models with errors")
        return tuple(files)

    def facts(self, expect: dict[str, Any], predicates: set[str], names: set[str],
              attributes: set[str]) -> None:
        """Expected facts name what exists: a known predicate (the library's, or an
        attribute the run sets from the planning domain or the people's ``kind``), a
        subject of the scenario and, for a relation, an object of the scenario."""
        domain: set[str] | None = None
        for key in ("facts", "no-facts"):
            for i, (subject, predicate, value) in enumerate(expect.get(key) or []):
                where = ("expect", key, i)
                if predicate not in predicates | attributes:
                    if domain is None:
                        domain = _domain_attributes()
                    if predicate not in domain:
                        known = predicates | attributes | domain
                        self.problem(where + (1,), f"unknown predicate {predicate!r}"
                                     f"{did_you_mean(str(predicate), known)}")
                if subject not in names:
                    self.problem(where + (0,), f"{subject!r} names nothing in this scenario"
                                 f"{did_you_mean(str(subject), names)}")
                if predicate in predicates - _WORD_VALUED and isinstance(value, str) \
                        and value not in names:
                    self.problem(where + (2,), f"{value!r} names nothing in this scenario"
                                 f"{did_you_mean(value, names)}")

    def person(self, name: str, spec: dict[str, Any], robot: str, things: set[str],
               acts: set[str], atomic: set[str]) -> Person | None:
        problem = self.problem
        if name in BOTTLES or name in FURNITURE or name == robot:
            problem(("people", name), f"{name!r} already names something in the room",
                    key=True)
        if spec["at"] not in HUMAN_PLACES:
            problem(("people", name, "at"), f"unknown place for a person {spec['at']!r}"
                    f"{did_you_mean(spec['at'], HUMAN_PLACES)}; places: "
                    f"{', '.join(HUMAN_PLACES)}")
        raw = spec.get("profile", "cooperative")
        if isinstance(raw, str):
            source: str | Path = raw
            if raw.endswith((".yaml", ".yml")):  # a file of the user's, like recipes:
                full = self.reader.confined_path(("people", name, "profile"), raw)
                if full is None:
                    return None
                source = spelled(full, like=self.reader.file)
            else:
                names = sorted(p.stem for p in PROFILES_DIR.glob("*.yaml"))
                if raw not in names:
                    problem(("people", name, "profile"), f"unknown profile {raw!r}"
                            f"{did_you_mean(raw, names)}; profiles: {', '.join(names)} "
                            "(or a profile file of your own: NAME.yaml)")
                    return None
            if raw not in self.profiles:
                try:
                    self.profiles[raw] = load_profile(source, things, acts, atomic)
                except FileError as err:
                    self.reader.problems.extend(err.problems)
                    if source != raw:  # the user's file: point at the line naming it
                        problem(("people", name, "profile"), f"depends on {source}, "
                                "which has errors")
                    self.profiles[raw] = None
            profile = self.profiles[raw]
            if profile is None:
                return None
        else:
            _check_profile(self.reader, ("people", name, "profile"), raw, things, acts, atomic)
            profile = profile_from(f"{name}'s profile", raw)
        shirt = tuple(spec.get("shirt", (0.2, 0.35, 0.7)))
        return Person(name, spec["at"], profile, shirt, dict(spec.get("kind") or {}))

    def thing(self, obj: str, spec: dict[str, Any], names: set[str]) -> dict[str, Any]:
        problem = self.problem
        if obj not in BOTTLES and not is_new(spec):
            problem(("objects", obj), f"unknown object {obj!r}{did_you_mean(obj, BOTTLES)}; "
                    f"objects: {', '.join(BOTTLES)}", key=True)
        if "on" in spec and spec["on"] not in FURNITURE:
            problem(("objects", obj, "on"), f"unknown furniture {spec['on']!r}"
                    f"{did_you_mean(spec['on'], FURNITURE)}")
        if "held-by" in spec and spec["held-by"] not in names:
            problem(("objects", obj, "held-by"), f"{spec['held-by']!r} is not a person of "
                    f"this scenario")
        if "held-by" in spec and ("on" in spec or "at" in spec):
            problem(("objects", obj), "an object held by someone is not also on furniture "
                    "(give 'held-by' or 'on'/'at')", key=True)
        elif "at" in spec and spec.get("on", "coffee-table") in FURNITURE:
            furniture = spec.get("on", "coffee-table")
            x, y = spec["at"]
            if not FOOTPRINTS[furniture].contains(x, y, -0.03):
                problem(("objects", obj, "at"), f"({x}, {y}) is not on the {furniture}")
        return dict(spec)

    def goal(self, i: int, spec: dict[str, Any], known_tasks: dict[str, Any] | None,
             agents: set[str], things: set[str]) -> Goal:
        """A goal; its task must exist, and its arguments name who and what exist: an
        argument that plays a role of the task's scheme is a person or the robot."""
        problem = self.problem
        where = ("goals", i)
        args = dict(spec.get("with") or {})
        task = known_tasks.get(spec["task"]) if known_tasks is not None else None
        if known_tasks is not None and task is None:
            problem(where + ("task",), f"unknown task {spec['task']!r}"
                    f"{did_you_mean(spec['task'], known_tasks)}")
        if task is not None:
            wrong = sorted(set(args) ^ set(task.params))
            if wrong:
                problem(where + ("with",), f"task {spec['task']!r} takes "
                        f"{', '.join(task.params) or 'nothing'}; wrong: {', '.join(wrong)}")
            roles = {term.value for term in task.roles.values() if term.kind == "param"}
            for param, value in args.items():
                if not isinstance(value, str) or param not in task.params \
                        or param in _TEXT_PARAMS:
                    continue
                if param in roles and value not in agents:
                    problem(where + ("with", param), f"{param} {value!r} is not a person of "
                            f"this scenario{did_you_mean(value, agents)}; people: "
                            f"{', '.join(sorted(agents))}")
                elif param not in roles and value not in things | set(PLACES):
                    problem(where + ("with", param), f"{param} {value!r} names nothing in "
                            f"this scenario{did_you_mean(value, things | set(PLACES))}")
        return Goal(spec["task"], args, self.reader.duration(where + ("at",), spec.get("at", 0)),
                    int(spec.get("priority", 0)))


def _check_profile(reader: Reader, where: tuple, raw: dict[str, Any], things: set[str],
                   acts: set[str], atomic: set[str]) -> None:
    """What a profile names must exist: acts it answers, targets it looks at, actions."""
    def problem(at: tuple, message: str, key: bool = False) -> None:
        reader.problem(at, message, key=key)

    looks = things | {"robot", "phone", "away"}
    attention = raw.get("attention", "robot")
    if things and attention not in looks:
        problem(where + ("attention",), f"nothing called {attention!r} to look at"
                f"{did_you_mean(attention, looks)}")
    for act, given in (raw.get("answers") or {}).items():
        if acts and act not in acts:
            alone = "" if where or did_you_mean(act, acts) else (
                " (declared by a scheme or acts file of yours? check them together: "
                "shary validate SCHEME.yaml PROFILE.yaml)")
            problem(where + ("answers", act),
                    f"unknown act {act!r}{did_you_mean(act, acts)}{alone}", True)
        listed = isinstance(given, list)
        for i, answer in enumerate(given if listed else [given]):
            at = where + ("answers", act) + ((i,) if listed else ())
            reply = answer.get("reply")
            if acts and reply is not None and reply not in acts:
                problem(at + ("reply",), f"unknown act {reply!r}{did_you_mean(reply, acts)}")
            if "choose" in answer and "say" in answer:
                problem(at, "an answer either says words ('say') or points at the thing "
                        "meant ('choose'), not both", True)
    for i, distraction in enumerate(raw.get("distractions") or []):
        look = distraction.get("look", "away")
        if things and look not in looks:
            problem(where + ("distractions", i, "look"), f"nothing called {look!r} to look at"
                    f"{did_you_mean(look, looks)}")
        started = (distraction.get("when") or {}).get("robot-starts")
        if atomic and started is not None and started not in atomic:
            problem(where + ("distractions", i, "when", "robot-starts"),
                    f"unknown atomic task {started!r}{did_you_mean(started, atomic)}")
    for i, step in enumerate(raw.get("script") or []):
        _check_step(problem, where + ("script", i), step)
        if acts and "act" in step and step["act"] not in acts:
            problem(where + ("script", i, "act"), f"unknown act {step['act']!r}"
                    f"{did_you_mean(step['act'], acts)}")
        if ("task" in step or "with" in step) and "act" not in step:
            problem(where + ("script", i), "'task' and 'with' say what an act is about: "
                    "give the act too (act: ASK-TASK)", True)
        if things and "look" in step and step["look"] not in looks:
            problem(where + ("script", i, "look"), f"nothing called {step['look']!r} to look "
                    f"at{did_you_mean(step['look'], looks)}")


def _check_step(problem: Any, where: tuple, step: dict[str, Any]) -> None:
    if "walk" in step and step["walk"] not in HUMAN_PLACES:
        problem(where + ("walk",), f"unknown place for a person {step['walk']!r}"
                f"{did_you_mean(step['walk'], HUMAN_PLACES)}; places: {', '.join(HUMAN_PLACES)}")
    for key in ("put", "take"):
        if key in step and step[key] not in BOTTLES:
            problem(where + (key,), f"unknown object {step[key]!r}"
                    f"{did_you_mean(step[key], BOTTLES)}")
    if "on" in step and step["on"] not in FURNITURE:
        problem(where + ("on",), f"unknown furniture {step['on']!r}"
                f"{did_you_mean(step['on'], FURNITURE)}")
