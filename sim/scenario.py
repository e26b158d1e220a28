"""Scenario files: a scene, people with profiles, goals, faults, and the expected outcome.

A scenario (``sim/scenarios/*.yaml``, or any file) is loaded safely, checked
against ``sim/schemas/scenario.schema.json`` and then for meaning — places,
objects, furniture, profiles, tasks, acts and atomic tasks must exist — and
every problem is reported as ``FILE:LINE:COL: error: …`` at once.  Profiles
are named (``sim/profiles/NAME.yaml``) or written inline.

:func:`judge` compares what a run did (its context log, its final facts and
task outcomes) with the scenario's ``expect`` section and lists every
difference in words.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from userfiles import yamlsafe
from userfiles.errors import FileError
from userfiles.schema import check, did_you_mean, validator

from .humans import HUMAN_PLACES, Profile, profile_from, seconds
from .objects import check_new_objects, is_new
from .world import BOTTLES, FOOTPRINTS, FURNITURE, PLACES

HERE = Path(__file__).resolve().parent
SCENARIOS_DIR = HERE / "scenarios"
PROFILES_DIR = HERE / "profiles"
SCHEMAS_DIR = HERE / "schemas"
DEFAULT_TIMEOUT = 180.0


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
class Expect:
    acts: tuple[str, ...] = ()
    no_acts: tuple[str, ...] = ()
    actions: tuple[str, ...] = ()
    no_actions: tuple[str, ...] = ()
    failed_actions: tuple[str, ...] = ()
    facts: tuple[tuple[Any, Any, Any], ...] = ()
    no_facts: tuple[tuple[Any, Any, Any], ...] = ()
    tasks: dict[str, str] = field(default_factory=dict)
    within: float | None = None


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


def recipe_files(path: str | Path) -> list[Path]:
    """The extra recipe files a scenario names that exist (read before checking it whole,
    so its goals can be checked against the tasks they define)."""
    path = Path(path)
    data = yamlsafe.load_file(path).data
    files = data.get("recipes") if isinstance(data, dict) else None
    if not isinstance(files, list):
        return []
    return [(path.parent / f).resolve() for f in files
            if isinstance(f, str) and (path.parent / f).is_file()]


def load_profile(name: str | Path, things: set[str] = frozenset(),
                 acts: set[str] = frozenset(), atomic: set[str] = frozenset()) -> Profile:
    """A profile, by name (``sim/profiles/NAME.yaml``) or file, checked; the names, acts
    and atomic tasks given (when given) are what its targets and answers may name."""
    path = Path(name) if isinstance(name, Path) else PROFILES_DIR / f"{name}.yaml"
    located = yamlsafe.load_file(path)
    problems = check(located, validator(SCHEMAS_DIR, "profile"))
    if not problems:
        _check_profile(lambda where, message, key=False: problems.append(
            located.problem(where, message, key=key)), (), located.data, things, acts, atomic)
    if problems:
        raise FileError(problems)
    return profile_from(path.stem, located.data)


def load_scenario(path: str | Path, *, known_tasks: dict[str, tuple[str, ...]] | None = None,
                  known_acts: Iterable[str] = (), known_atomic: Iterable[str] = (),
                  known_predicates: Iterable[str] = ()) -> Scenario:
    """Load and check a scenario; raise :class:`FileError` listing every problem.

    ``known_tasks`` (task -> parameters), ``known_acts`` and ``known_atomic``
    come from the recipe library the run will use; when given, goals and
    expectations are checked against them.
    """
    path = Path(path)
    located = yamlsafe.load_file(path)
    problems = check(located, validator(SCHEMAS_DIR, "scenario"))
    if problems:
        raise FileError(problems)
    data = located.data
    problems = []

    def problem(where: tuple, message: str, key: bool = False) -> None:
        problems.append(located.problem(where, message, key=key))

    acts = set(known_acts)
    atomic = set(known_atomic)
    robot = data.get("robot") or {}
    everyone = {robot.get("name", "jido"), *(data.get("people") or {})}
    things = everyone | set(BOTTLES) | set(FURNITURE) | set(data.get("objects") or {})
    robot_at = robot.get("at", "base")
    if robot_at not in PLACES:
        problem(("robot", "at"), f"unknown place {robot_at!r}{did_you_mean(robot_at, PLACES)}; "
                f"places: {', '.join(PLACES)}")
    people = []
    for name, spec in (data.get("people") or {}).items():
        if name in BOTTLES or name in FURNITURE or name == robot.get("name", "jido"):
            problem(("people", name), f"{name!r} already names something in the room", True)
        if spec["at"] not in HUMAN_PLACES:
            problem(("people", name, "at"), f"unknown place for a person {spec['at']!r}"
                    f"{did_you_mean(spec['at'], HUMAN_PLACES)}; places: {', '.join(HUMAN_PLACES)}")
        raw = spec.get("profile", "cooperative")
        if isinstance(raw, str):
            if not (PROFILES_DIR / f"{raw}.yaml").exists():
                names = [p.stem for p in PROFILES_DIR.glob("*.yaml")]
                problem(("people", name, "profile"), f"unknown profile {raw!r}"
                        f"{did_you_mean(raw, names)}; profiles: {', '.join(sorted(names))}")
                continue
            try:
                profile = load_profile(raw, things, acts, atomic)
            except FileError as err:
                problems.extend(err.problems)
                continue
        else:
            profile = profile_from(f"{name}'s profile", raw)
            _check_profile(problem, ("people", name, "profile"), raw, things, acts, atomic)
        shirt = tuple(spec.get("shirt", (0.2, 0.35, 0.7)))
        people.append(Person(name, spec["at"], profile, shirt, dict(spec.get("kind") or {})))
    names = {p.name for p in people}
    objects = {}
    check_new_objects(data.get("objects") or {},
                      everyone | set(BOTTLES) | set(FURNITURE) | set(PLACES), problem)
    for obj, spec in (data.get("objects") or {}).items():
        if obj not in BOTTLES and not is_new(spec):
            problem(("objects", obj), f"unknown object {obj!r}{did_you_mean(obj, BOTTLES)}; "
                    f"objects: {', '.join(BOTTLES)}", True)
        if "on" in spec and spec["on"] not in FURNITURE:
            problem(("objects", obj, "on"), f"unknown furniture {spec['on']!r}"
                    f"{did_you_mean(spec['on'], FURNITURE)}")
        if "held-by" in spec and spec["held-by"] not in names:
            problem(("objects", obj, "held-by"), f"{spec['held-by']!r} is not a person of "
                    f"this scenario")
        if "held-by" in spec and ("on" in spec or "at" in spec):
            problem(("objects", obj), "an object held by someone is not also on furniture "
                    "(give 'held-by' or 'on'/'at')", True)
        elif "at" in spec and spec.get("on", "coffee-table") in FURNITURE:
            furniture = spec.get("on", "coffee-table")
            x, y = spec["at"]
            if not FOOTPRINTS[furniture].contains(x, y, -0.03):
                problem(("objects", obj, "at"), f"({x}, {y}) is not on the {furniture}")
        objects[obj] = dict(spec)
    recipes = []
    for i, file in enumerate(data.get("recipes") or []):
        full = (path.parent / file).resolve()
        if not full.is_file():
            problem(("recipes", i), f"no recipe file {file!r} next to the scenario")
        recipes.append(full)
    goals = []
    for i, spec in enumerate(data.get("goals") or []):
        args = dict(spec.get("with") or {})
        if known_tasks is not None:
            if spec["task"] not in known_tasks:
                problem(("goals", i, "task"), f"unknown task {spec['task']!r}"
                        f"{did_you_mean(spec['task'], known_tasks)}")
            else:
                params = known_tasks[spec["task"]]
                wrong = sorted(set(args) ^ set(params))
                if wrong:
                    problem(("goals", i, "with"), f"task {spec['task']!r} takes "
                            f"{', '.join(params) or 'nothing'}; wrong: {', '.join(wrong)}")
        goals.append(Goal(spec["task"], args, seconds(spec.get("at", 0)),
                          int(spec.get("priority", 0))))
    noise = data.get("noise") or {}
    lost = tuple((e["entity"], seconds(e["from"]), seconds(e["to"]))
                 for e in noise.get("lost") or [])
    for i, (entity, start, end) in enumerate(lost):
        if entity not in things:
            problem(("noise", "lost", i, "entity"), f"unknown entity {entity!r}"
                    f"{did_you_mean(entity, things)}")
        if end < start:
            problem(("noise", "lost", i, "to"), f"'to' ({end:g}s) comes before 'from' "
                    f"({start:g}s)")
    predicates = set(known_predicates)
    for predicate in noise.get("flicker") or {}:
        if predicates and predicate not in predicates:
            problem(("noise", "flicker", predicate), f"unknown predicate {predicate!r}"
                    f"{did_you_mean(predicate, predicates)}", True)
    raw_expect = data["expect"]
    for key in ("acts", "no-acts"):
        for i, act in enumerate(raw_expect.get(key) or []):
            if acts and act not in acts:
                problem(("expect", key, i), f"unknown act {act!r}{did_you_mean(act, acts)}")
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
                        f"{did_you_mean(task, known_tasks)}", True)
    if problems:
        raise FileError(problems)
    expect = Expect(
        tuple(raw_expect.get("acts") or ()), tuple(raw_expect.get("no-acts") or ()),
        tuple(raw_expect.get("actions") or ()), tuple(raw_expect.get("no-actions") or ()),
        tuple(raw_expect.get("failed-actions") or ()),
        tuple(tuple(f) for f in raw_expect.get("facts") or ()),
        tuple(tuple(f) for f in raw_expect.get("no-facts") or ()),
        dict(raw_expect.get("tasks") or {}),
        seconds(raw_expect["within"]) if "within" in raw_expect else None)
    return Scenario(
        data["scenario"], path, str(data.get("doc", "")).strip(), robot.get("name", "jido"),
        robot.get("model", "jido"), robot_at, tuple(people), objects, tuple(recipes),
        tuple(goals), dict(noise.get("flicker") or {}), lost,
        seconds(noise.get("hold", 0.5)), tuple(faults),
        seconds(data.get("timeout", DEFAULT_TIMEOUT)), expect)


def _check_profile(problem: Any, where: tuple, raw: dict[str, Any], things: set[str],
                   acts: set[str], atomic: set[str]) -> None:
    """What a profile names must exist: acts it answers, targets it looks at, actions."""
    looks = things | {"robot", "phone", "away"}
    attention = raw.get("attention", "robot")
    if things and attention not in looks:
        problem(where + ("attention",), f"nothing called {attention!r} to look at"
                f"{did_you_mean(attention, looks)}")
    for act, answer in (raw.get("answers") or {}).items():
        if acts and act not in acts:
            problem(where + ("answers", act), f"unknown act {act!r}{did_you_mean(act, acts)}",
                    True)
        reply = answer.get("reply")
        if acts and reply is not None and reply not in acts:
            problem(where + ("answers", act, "reply"), f"unknown act {reply!r}"
                    f"{did_you_mean(reply, acts)}")
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


# --------------------------------------------------------------------- judging

@dataclass(frozen=True)
class Happened:
    """What a run did, as the judge needs it."""

    acts: list[tuple[float, str, str]]          # time, agent, act
    actions: list[tuple[float, str, str, str]]  # time, agent, atomic, status ("started" …)
    tasks: dict[str, list[str]]                 # task name -> outcomes of its runs
    facts: set[tuple[str, str, str]]
    end: float


def _in_order(wanted: Iterable[str], seen: list[str]) -> str | None:
    """The first wanted item not found after the previous ones, or None."""
    position = 0
    for item in wanted:
        try:
            position = seen.index(item, position) + 1
        except ValueError:
            return item
    return None


def judge(expect: Expect, happened: Happened) -> list[str]:
    """Every way the run differs from what the scenario expects, in words."""
    out = []
    acts = [act for _, _, act in happened.acts]
    missing = _in_order(expect.acts, acts)
    if missing is not None:
        out.append(f"expected the act {missing} (in the order {', '.join(expect.acts)}); "
                   f"acts were: {', '.join(acts) or 'none'}")
    for act in expect.no_acts:
        when = [f"{t:.1f}s" for t, _, a in happened.acts if a == act]
        if when:
            out.append(f"the act {act} must not happen; it did at {', '.join(when)}")
    done = [atomic for _, _, atomic, status in happened.actions if status == "done"]
    missing = _in_order(expect.actions, done)
    if missing is not None:
        out.append(f"expected the action {missing} done (in the order "
                   f"{', '.join(expect.actions)}); done were: {', '.join(done) or 'none'}")
    for atomic in expect.no_actions:
        when = [f"{t:.1f}s" for t, _, a, s in happened.actions if a == atomic and s == "started"]
        if when:
            out.append(f"the action {atomic} must not start; it did at {', '.join(when)}")
    failed = [atomic for _, _, atomic, status in happened.actions if status == "failed"]
    for atomic in expect.failed_actions:
        if atomic not in failed:
            out.append(f"expected the action {atomic} to fail; it did not")
    for fact in expect.facts:
        key = tuple(str(v) for v in fact)
        if key not in happened.facts:
            out.append(f"expected the fact {' '.join(key)} at the end; it does not hold")
    for fact in expect.no_facts:
        key = tuple(str(v) for v in fact)
        if key in happened.facts:
            out.append(f"the fact {' '.join(key)} must not hold at the end; it does")
    for task, outcome in expect.tasks.items():
        outcomes = happened.tasks.get(task, [])
        if outcome not in outcomes:
            out.append(f"expected task {task} to end {outcome}; "
                       f"{'it ended ' + ', '.join(outcomes) if outcomes else 'it never ended'}")
    if expect.within is not None and happened.end > expect.within + 1e-9:
        out.append(f"expected the run to be over within {expect.within:g}s; "
                   f"it took {happened.end:.1f}s")
    return out
