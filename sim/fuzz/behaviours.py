"""Behaviours drawn at random from the documented profile and team keys, one per run.

A campaign (:mod:`sim.fuzz.campaign`) runs a family's built-in scenarios with
people who behave differently each time.  :func:`draw` turns a seed into a
:class:`Variation`: a base scenario of the family and a document made from it
in memory, whose partner (or team) behaviour is drawn from the keys the docs
describe and nothing else, so that every run is one a user could have
written:

* **stack** (docs/jahrvis.md, ``shared-plan: profile:``): the partner's name,
  the option taken or ``wait`` at each decision, the ``delay`` before acting,
  the ``decision-wait``, a ``look-away`` during any task of the robot for any
  duration (past the timeout: never back), sometimes a second one later (as
  she may be told what she missed), and one as a failing action is replanned,
  an action of their own ``before``
  a task (useful, or one that keeps the robot's cube), ``leave`` after a task;
  the scenario's perception noise (``flicker`` of holds and looks, ``hold``)
  and action ``faults``;
* **living-room** (docs/simulation.md, profiles): the answer to each act (yes,
  no, silence) and its delay (late answers included), where they look by
  default, ``distractions`` at a time or when the robot starts an action, for
  any duration or ``never``, whether they take what is held out and when,
  whether they help, their walking speed, leaving by the door (``script``),
  perception noise and action faults;
* **weld** (docs/teams.md, ``behaviour:``): each person's reply to
  assignments (accept, refuse, ignore) and to questions (answer, refuse,
  ignore) and its delay, their answers, how long they take to mount a panel
  (the site's mount lasts at least that), the quality of
  each weld the torch lays (a bad one fails its inspection), an operator
  taking control of a robot for a while (``script``), and, in one run in six,
  a member (robot or person) killed at a random time: no file key says that
  (in a file, a kill is a process stopped, ``shary team up``), so it is the
  variation's :attr:`Variation.kill`, done in process through the path a
  distributed team takes when a member's process dies
  (:meth:`shary.team.Team.kill`).

The document is checked by the same readers as a file (schema and meaning),
read as if it were the base scenario (:func:`sim.scenario.load_scenario`'s
``text``), so a drawn behaviour that a user could not write is refused, not
run.  The seed alone decides everything: the same seed draws the same
behaviour and runs it with the same seed.
"""

from __future__ import annotations

import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from userfiles import yamlsafe

from ..scenario import builtin_scenarios, load_scenario

__all__ = ["FAMILIES", "Variation", "draw", "stack_partner"]

FAMILIES = ("stack", "living-room", "weld", "dialogue")

PARTNERS = ("alice", "bob", "carol", "dana")
"""Names a stack partner may have (the plan's human takes the name)."""
ROBOT_TASKS = ("Pick(pr2, red_cube_1)", "Place(pr2, red_cube_1", "Pick(pr2, stick)",
               "PlaceStick(pr2", "Pick(pr2, blue_cube", "Place(pr2, blue_cube",
               "Pick(pr2, green_cube)", "Place(pr2, green_cube", "Wait(pr2)", "Pick(pr2",
               "Place(pr2")
"""Beginnings of the robot's task labels in the stack plans (any branch): a look-away
starts when the first task so labelled starts."""
HUMAN_TASKS = ("Pick({h}, red_cube_2)", "Place({h}, red_cube_2", "Pick({h}, stick)",
               "PlaceStick({h}", "Pick({h}, blue_cube_2)", "Place({h}, blue_cube_2")
"""Beginnings of the partner's task labels ({h}: their name): leave after one."""
BEFORE = (
    # the documented unexpected but useful action: her blue cube on the green one
    {"Place(pr2, green_cube, blue_cube_2)": [["Pick", "blue_cube_1"],
                                             ["Place", "blue_cube_1", "green_cube"]]},
    # she does the robot's next step herself
    {"Pick(pr2, green_cube)": [["Pick", "green_cube"], ["Place", "green_cube", "blue_cube_2"]]},
    # she picks the robot's cube and keeps it
    {"Pick(pr2, green_cube)": [["Pick", "green_cube"]]},
)
LIVING_BASES = ("give-bottle", "give-bottle", "clean-up-unreachable", "clean-up")
ROBOT_ACTIONS = ("navigate", "pick", "move-arm", "give", "put-back", "dump", "look-at")
LOOKS = ("phone", "away", "store-table")
KILL_CHANCE = 1 / 6
"""How often a weld run has a member killed (robot or person, at 1–60 s)."""
DIALOGUE_BASES = ("person-asks-for-bottle", "person-cancels", "person-modifies-plan",
                  "session-greeting-farewell", "request-ambiguous-cube",
                  "request-unknown-object", "inform-after-look-back", "give-bottle",
                  "serve-drink-initiative")
"""The conversations varied: requests, cancels, plan changes, sessions, informs."""
REQUESTS = (("give-object", "Jido, could you give me the yellow bottle?"),
            ("clean-up", "Jido, could you clean up the orange bottle?"))
"""What a person may ask for on their own (a sentence the robot reads)."""
BYSTANDER_AT = ("sofa-end", "store-side", "coffee-east")
WELD_BASES = ("weld-nominal", "weld-human-refuses", "weld-human-supports-robot",
              "weld-question-expires")


@dataclass(frozen=True)
class Variation:
    """One run of a campaign: its seed, the scenario varied, the document drawn."""

    family: str
    seed: int
    base: str
    """The built-in scenario the document was made from."""
    scenario: dict[str, Any]
    team: dict[str, Any] | None
    """A weld scenario's team document (drawn behaviours), read as if it were its file."""
    story: str
    """The behaviour drawn, in a few words (for the tables)."""
    kill: tuple[str, float] | None = None
    """A weld team member killed, and when (seconds into the run), or None."""

    @property
    def path(self) -> Path:
        return builtin_scenarios()[self.base]

    def text(self) -> str:
        """The scenario document, as a file would hold it."""
        return yaml.safe_dump(self.scenario, sort_keys=False, width=100)

    def team_text(self) -> str | None:
        return None if self.team is None else yaml.safe_dump(self.team, sort_keys=False,
                                                             width=100)

    def load(self) -> Any:
        """The scenario, checked like a file (a :class:`~userfiles.errors.FileError` if a
        drawn behaviour is one no user could write: a bug of this module)."""
        if self.team is not None:
            from ..weld.scenario import load_weld_scenario

            return load_weld_scenario(self.path, text=self.text(), team_text=self.team_text())
        return load_scenario(self.path, text=self.text())


def draw(family: str, seed: int) -> Variation:
    """The behaviour of run ``seed`` of a campaign on ``family`` (see the module)."""
    rng = random.Random(f"{family}:{seed}")
    if family == "stack":
        return _stack(rng, seed)
    if family == "living-room":
        return _living_room(rng, seed)
    if family == "weld":
        return _weld(rng, seed)
    if family == "dialogue":
        return _dialogue(rng, seed)
    raise KeyError(family)


def _base(name: str) -> dict[str, Any]:
    return dict(yamlsafe.load_file(builtin_scenarios()[name]).data)


def _seconds(rng: random.Random, low: float, high: float) -> float:
    return round(rng.uniform(low, high), 1)


def _span(rng: random.Random, low: float, high: float) -> list[str]:
    a = _seconds(rng, low, high)
    return [f"{a:g}s", f"{a + _seconds(rng, 0, 2):g}s"]


# ------------------------------------------------------------------------------ stack

def stack_partner(partner: str, profile: dict[str, Any], decision_wait: float = 6.0
                  ) -> dict[str, Any]:
    """``stack-nominal`` with another partner, following the plan as ``profile`` says
    (the keys of ``shared-plan: profile:``, docs/jahrvis.md)."""
    data = _base("stack-nominal")
    data["people"] = {partner: {"at": "coffee-north", "profile": "cooperative"}}
    data["shared-plan"] = {"problem": "stack", "partner": partner,
                           "decision-wait": f"{decision_wait:g}s", "profile": profile}
    data["timeout"] = "300s"
    data["expect"] = {}
    return data


def _stack(rng: random.Random, seed: int) -> Variation:
    partner = rng.choice(PARTNERS)
    told = [partner]
    choices = []
    for _ in range(rng.randint(0, 4)):
        choices.append(rng.choice(["placement_1", "placement_2", "wait", "Pick", "Place"]))
    profile: dict[str, Any] = {"choices": choices, "delay": _seconds(rng, 0, 4)}
    told.append(f"choices {'/'.join(choices) or 'default'}, delay {profile['delay']:g}s")
    aways: list[dict[str, Any]] = []
    if rng.random() < 0.6:
        during = rng.choice(ROBOT_TASKS)
        seconds = rng.choice([_seconds(rng, 0.2, 8), _seconds(rng, 8, 30), 600])
        aways.append({"during": during, "for": seconds})
        told.append(f"looks away during {during}… for {seconds:g}s")
        if seconds < 600 and rng.random() < 0.35:
            # again, as she may be told what she missed (an inform under way) or later
            at, more = _seconds(rng, 2, 40), _seconds(rng, 0.2, 8)
            aways.append({"at": at, "for": more})
            told.append(f"looks away at {at:g}s for {more:g}s")
    if rng.random() < 0.15:
        before = rng.choice(BEFORE)
        profile["before"] = before
        (task, actions), = before.items()
        told.append(f"before {task}: {' '.join('+'.join(a) for a in actions)}")
    if rng.random() < 0.1:
        after = rng.choice(HUMAN_TASKS).format(h=partner)
        profile["leave"] = {"after": after}
        told.append(f"leaves after {after}…")
    faults = None
    if rng.random() < 0.2:
        action, times = rng.choice(["pick", "place"]), rng.randint(1, 3)
        faults = [{"action": action, "reason": f"the {action} slipped", "times": times}]
        told.append(f"{action} fails {times}x")
        if times >= 2 and rng.random() < 0.5:  # away while it fails and is replanned
            seconds = _seconds(rng, 1, 12)
            aways.append({"during": f"{action.capitalize()}(pr2", "for": seconds})
            told.append(f"looks away as the {action} fails, for {seconds:g}s")
    if aways:
        profile["look-away"] = aways[0] if len(aways) == 1 else aways
    data = stack_partner(partner, profile, _seconds(rng, 2, 8))
    _noise(rng, data, told, ("isHolding", "looksAt"))
    if faults:
        data["faults"] = faults
    return _finish("stack", seed, "stack-nominal", data, told)


def _noise(rng: random.Random, data: dict[str, Any], told: list[str],
           predicates: tuple[str, ...]) -> None:
    if rng.random() < 0.25:
        predicate = rng.choice(predicates)
        p = round(rng.uniform(0.05, 0.35), 2)
        hold = rng.choice([0, 0.3, 0.5, 0.8])
        data["noise"] = {"hold": f"{hold:g}s", "flicker": {predicate: p}}
        told.append(f"{predicate} flickers {p:g} (hold {hold:g}s)")


def _finish(family: str, seed: int, base: str, data: dict[str, Any], told: list[str],
            team: dict[str, Any] | None = None,
            kill: tuple[str, float] | None = None) -> Variation:
    data["scenario"] = f"{base}-fuzz-{seed}"
    data["doc"] = f"shary fuzz {family} --seed {seed}: " + "; ".join(told)
    data["expect"] = {}  # a campaign checks its invariants, not a scenario's outcome
    return Variation(family, seed, base, data, team, "; ".join(told), kill)


# ------------------------------------------------------------------------ living room

def _living_room(rng: random.Random, seed: int) -> Variation:
    base = rng.choice(LIVING_BASES)
    data = _base(base)
    told: list[str] = []
    profile: dict[str, Any] = {"answers": {act: _answers(rng, act, told)
                                           for act in ("ASK-TASK", "ASK-HELP")}}
    if rng.random() < 0.1:
        profile["attention"] = rng.choice(LOOKS[1:])
        told.append(f"looks at {profile['attention']}")
    distractions = []
    for _ in range(rng.choices([0, 1, 2], [0.4, 0.45, 0.15])[0]):
        when = ({"robot-starts": rng.choice(ROBOT_ACTIONS)} if rng.random() < 0.6
                else {"at": f"{_seconds(rng, 0, 40):g}s"})
        seconds = rng.choice([f"{_seconds(rng, 0.5, 8):g}s", f"{_seconds(rng, 8, 40):g}s",
                              "never"])
        look = rng.choice(LOOKS)
        distractions.append({"when": when, "after": f"{_seconds(rng, 0, 1):g}s",
                             "look": look, "for": seconds})
        cue = (f"when {when['robot-starts']} starts" if "robot-starts" in when
               else f"at {when['at']}")
        told.append(f"looks at {look} for {seconds} {cue}")
    if distractions:
        profile["distractions"] = distractions
    if rng.random() < 0.1:
        profile["takes"] = None
        told.append("never takes")
    else:
        profile["takes"] = {"after": _span(rng, 0.2, 3)}
    profile["helps"] = rng.random() < 0.85
    if not profile["helps"]:
        told.append("does not help")
    profile["speed"] = round(rng.uniform(0.5, 1.3), 2)
    if rng.random() < 0.1:
        at = _seconds(rng, 1, 40)
        profile["script"] = [{"at": f"{at:g}s", "leave": True}]
        told.append(f"leaves at {at:g}s")
    data["people"] = {"alice": {"at": "sofa-seat", "profile": profile}}
    _noise(rng, data, told, ("looksAt", "isHolding"))
    if rng.random() < 0.2:
        action, times = rng.choice(["pick", "navigate", "give", "dump", "move-arm"]), \
            rng.randint(1, 2)
        data["faults"] = [{"action": action, "reason": f"the {action} went wrong",
                           "times": times}]
        told.append(f"{action} fails {times}x")
    data["timeout"] = "300s"
    return _finish("living-room", seed, base, data, told)


def _answers(rng: random.Random, act: str, told: list[str]) -> list[dict[str, Any]]:
    """One to three answers to ``act`` (the first time, the second …)."""
    out = []
    for _ in range(rng.choices([1, 2, 3], [0.7, 0.2, 0.1])[0]):
        reply = rng.choices(["H-AGREE", "H-DISAGREE", None], [0.65, 0.15, 0.2])[0]
        late = rng.random() < 0.15
        after = _span(rng, 10, 40) if late else _span(rng, 0.3, 3)
        out.append({"reply": reply, "after": after})
        told.append(f"{act} -> {reply or 'silence'}{' late' if late else ''}")
    return out


# ------------------------------------------------------------------------------- weld

def _weld(rng: random.Random, seed: int) -> Variation:
    base = rng.choice(WELD_BASES)
    data = _base(base)
    team_path = builtin_scenarios()[base].parent / data["team"]
    team = dict(yamlsafe.load_file(team_path).data)
    told: list[str] = []
    agents = {name: dict(spec) for name, spec in team["agents"].items()}
    for name, spec in agents.items():
        if spec.get("kind") != "human":
            continue
        behaviour: dict[str, Any] = {}
        if not spec.get("remote"):
            reply = rng.choices(["accept", "refuse", "ignore"], [0.7, 0.15, 0.15])[0]
            behaviour["assignments"] = {"reply": reply, "after": _span(rng, 0.5, 8)}
            if rng.random() < 0.3:  # a mount's physics takes about 15 s: longer, or not
                behaviour["works"] = {"mount-panel": _span(rng, 5, 90)}
                told.append(f"{name} mounts in {'-'.join(behaviour['works']['mount-panel'])}")
            told.append(f"{name} {reply}s assignments")
        reply = rng.choices(["answer", "refuse", "ignore"], [0.7, 0.15, 0.15])[0]
        behaviour["questions"] = {"reply": reply, "after": _span(rng, 1, 30)}
        if "answer" in spec.get("skills", ()):
            answer = rng.choice(["yes", "no"])
            behaviour["answers"] = {"seam-okay": answer}
            told.append(f"{name} {reply}s questions ({answer})")
        spec["behaviour"] = behaviour
    team["agents"] = agents
    welds = {}
    for seam in ("P1-P2", "P2-P3", "P3-P4"):
        if rng.random() < 0.4:
            welds[seam] = [round(rng.uniform(0.3, 1.0), 2) for _ in range(rng.randint(1, 3))]
            told.append(f"{seam} welds {'/'.join(f'{q:g}' for q in welds[seam])}")
    if welds:
        data["welds"] = {**(data.get("welds") or {}), **welds}
    if "IVA" in agents and rng.random() < 0.2:
        at = _seconds(rng, 1, 30)
        back = round(at + _seconds(rng, 1, 30), 1)
        data["script"] = [{"at": f"{at:g}s", "by": "IVA", "take-control": "K-10"},
                          {"at": f"{back:g}s", "by": "IVA", "hand-back": "K-10"}]
        told.append(f"IVA holds K-10 {at:g}-{back:g}s")
    data["timeout"] = "8min"
    kill = None
    if rng.random() < KILL_CHANCE:
        members = [n for n, spec in agents.items() if spec.get("kind") in ("robot", "human")]
        kill = (rng.choice(members), _seconds(rng, 1, 60))
        told.append(f"{kill[0]} killed at {kill[1]:g}s")
    return _finish("weld", seed, base, data, told, team, kill)


# --------------------------------------------------------------------------- dialogue

def _profile(spec: dict[str, Any]) -> dict[str, Any]:
    """A person's profile as a document (a shipped profile's name read from its file)."""
    profile = spec.get("profile") or {}
    if isinstance(profile, str):
        path = builtin_scenarios()["give-bottle"].parent.parent / "profiles" / f"{profile}.yaml"
        profile = {k: v for k, v in yamlsafe.load_file(path).data.items()
                   if k not in ("profile", "doc")}
    return dict(profile)


def _dialogue(rng: random.Random, seed: int) -> Variation:
    """A conversation scenario with its person's behaviour drawn (docs/communication.md,
    docs/simulation.md): what they ask and when, their answers (yes, no, silence, late),
    a CANCEL or a change of plan at any moment of the task, phone calls, leaving and
    coming back (sessions close and open), a bystander who looks at the robot, flicker."""
    base = rng.choice(DIALOGUE_BASES)
    data = _base(base)
    people = {name: dict(spec) for name, spec in data["people"].items()}
    name = next(iter(people))
    profile = _profile(people[name])
    told: list[str] = [base]
    answers = dict(profile.get("answers") or {})
    for act in ("ASK-TASK", "ASK-HELP"):
        if rng.random() < 0.6:
            answers[act] = _answers(rng, act, told)
    profile["answers"] = answers
    base_script = list(profile.get("script") or [])
    asked = [str(step["task"]) for step in base_script if step.get("task")]
    asked += [str(goal["task"]) for goal in data.get("goals") or []]
    added: list[tuple[float, list[dict[str, Any]]]] = []
    """Steps drawn, each group at its time (a step's ``at`` is absolute: they are kept in
    the order of their times, after what the base scenario's person does)."""
    if rng.random() < 0.3:
        task, words = rng.choice(REQUESTS)
        at = _seconds(rng, 0.5, 30)
        added.append((at, [{"at": f"{at:g}s", "say": words}]))
        asked.append(task)
        told.append(f"asks {task} at {at:g}s")
    if asked and rng.random() < 0.35:
        at = _seconds(rng, 0.5, 45)  # any phase: asking, fetching, handing over, after
        added.append((at, [{"at": f"{at:g}s", "act": "CANCEL", "task": rng.choice(asked),
                            "say": "Actually, never mind."}]))
        told.append(f"cancels at {at:g}s")
    if rng.random() < 0.2:
        at = _seconds(rng, 1, 30)
        added.append((at, [{"at": f"{at:g}s", "say": "I'll take the orange bottle myself."}]))
        told.append(f"takes a step on at {at:g}s")
    if rng.random() < 0.2:
        at = _seconds(rng, 1, 40)
        group: list[dict[str, Any]] = [{"at": f"{at:g}s", "leave": True}]
        told.append(f"leaves at {at:g}s")
        if rng.random() < 0.5:
            back = _seconds(rng, 2, 20)
            group += [{"after": f"{back:g}s", "walk": "sofa-end"},
                      {"after": "0.5s", "look": "robot"}]
            told.append(f"comes back {back:g}s later")
        added.append((at, group))
    if rng.random() < 0.3:
        when = ({"robot-starts": rng.choice(ROBOT_ACTIONS)} if rng.random() < 0.6
                else {"at": f"{_seconds(rng, 0, 40):g}s"})
        seconds = rng.choice([f"{_seconds(rng, 0.5, 8):g}s", f"{_seconds(rng, 8, 40):g}s",
                              "never"])
        profile["distractions"] = [{"when": when, "look": "phone", "for": seconds}]
        told.append(f"phone call for {seconds}")
    script = base_script + [step for _, group in sorted(added, key=lambda g: g[0])
                            for step in group]
    if script:
        profile["script"] = script
    people[name] = {**people[name], "profile": profile}
    if rng.random() < 0.3:
        at = rng.choice(BYSTANDER_AT)
        people["dana"] = {"at": at, "profile": {"attention": "robot"}}
        told.append(f"dana looks at the robot from {at}")
    data["people"] = people
    _noise(rng, data, told, ("looksAt",))
    data["timeout"] = "300s"
    return _finish("dialogue", seed, base, data, told)
