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

import copy
import random
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import yaml

from userfiles import yamlsafe

from ..humans import WALK_SPEED
from ..scenario import builtin_scenarios, load_scenario
from .drawn import Drawn, Story

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
PARTNER_DELAY = 1.0
"""Seconds a stack partner waits before acting, unless their profile says
(sim/stack/partner.py): a delay drawn equal to it is not a key."""
DECISION_WAIT = 6.0
"""Seconds the robot waits for a decision of the partner's, unless the scenario says."""
GLANCE = 1.0
"""The shortest look-away drawn: the robot's perception keeps a fact 0.5 s after it is
last seen (0.8 s with some noise drawn), so a shorter glance is not noticed at all."""
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
ASKED = {"give-bottle": ("ASK-TASK",), "clean-up-unreachable": ("ASK-HELP",), "clean-up": ()}
"""What the robot asks the person in each living-room base scenario (answers are kept for
these; in a conversation, what the person asks for decides it)."""
ACTIONS = {"give-bottle": ("pick", "navigate", "give", "move-arm"),
           "clean-up": ("pick", "navigate", "dump"),
           "clean-up-unreachable": ("pick", "navigate", "dump")}
"""The robot's actions in each living-room base scenario (the ones a fault may hit)."""
UNASKED_TAKE = 1.0
"""Seconds a person takes to take what is held out, unless their profile says
(sim/humans.py, ``Profile.takes``)."""
ROBOT_ACTIONS = ("give", "look-at", "move-arm", "give", "look-at", "move-arm", "look-at")
"""Robot actions towards a person (their name among its arguments), which a distraction
may wait for (``when: {robot-starts: …}``, sim/people.py); the repeated ones are the
likelier."""
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
    keys: tuple[Drawn, ...] = ()
    """The profile, scenario and team keys drawn (the base scenario's own are not)."""

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

    def run(self, seed: int | None = None, **options: Any) -> Any:
        """Run the variation headless (with its seed unless told) and return the
        :class:`~sim.results.RunResult`; ``options`` (``out``, ``report``, ``console``)
        go to :func:`sim.run.run_scenario`, or to the seam-welding site's run with the
        member :attr:`kill` names killed."""
        scenario = self.load()
        seed = self.seed if seed is None else seed
        if self.kill is not None:
            from ..weld.run import run_weld

            return run_weld(scenario, seed=seed, kill=self.kill, **options)
        from ..run import run_scenario

        return run_scenario(scenario, seed=seed, **options)

    def without(self, key: Drawn) -> Variation:
        """This variation with ``key`` taken away (what the person or site does without
        it: the profile's, scenario's or team's default)."""
        if key.where == (("kill",),):
            return replace(self, kill=None, keys=())
        docs = {"scenario": copy.deepcopy(self.scenario), "team": copy.deepcopy(self.team)}
        # list items from the last, so that an index still names the item drawn
        for where in sorted(key.where, key=lambda w: w[-1] if isinstance(w[-1], int) else -1,
                            reverse=True):
            *parents, last = where
            holders: list[Any] = [docs]
            for part in parents:
                holders.append(holders[-1][part])
            if isinstance(last, int) and key.rest:
                del holders[-1][last:]
            elif key.unasked is not None:
                holders[-1][last] = copy.deepcopy(key.unasked)
            else:
                del holders[-1][last]
            if isinstance(holders[-1], list) and not holders[-1]:  # no empty lists left
                del holders[-2][parents[-1]]
        return replace(self, scenario=docs["scenario"], team=docs["team"], keys=())


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


def _upper(span: list[str]) -> float:
    """The upper bound of a drawn span, in seconds."""
    return float(span[-1].rstrip("s"))


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
    story = Story(partner)
    profile_at = ("scenario", "shared-plan", "profile")
    choices = []
    for _ in range(rng.randint(0, 4)):
        choices.append(rng.choice(["placement_1", "placement_2", "wait", "Pick", "Place"]))
    for i, choice in enumerate(choices):  # the i-th decision's answer, and those after
        # the plan's first option is what she takes anyway: such a word only keeps the
        # place of the later ones (her first decision is where to put her red cube,
        # the later ones whether to fetch a blue cube or wait)
        if choice == "wait" or (i == 0 and choice == "placement_2"):
            story(f"decision {i + 1}: {choice}", (*profile_at, "choices", i), rest=True,
                  cue=("decided", partner, i + 1))
    profile: dict[str, Any] = {"choices": choices, "delay": _seconds(rng, 0, 4)}
    if profile["delay"] != PARTNER_DELAY:
        story(f"delay {profile['delay']:g}s", (*profile_at, "delay"), cue=("acted", partner))
    aways: list[tuple[dict[str, Any], str]] = []
    if rng.random() < 0.6:
        during = rng.choice(ROBOT_TASKS)
        seconds = rng.choice([max(GLANCE, _seconds(rng, 0.2, 8)), _seconds(rng, 8, 30), 600])
        aways.append(({"during": during, "for": seconds},
                      f"looks away during {during}… for {seconds:g}s"))
        if seconds < 600 and rng.random() < 0.35:
            # again, as she may be told what she missed (an inform under way) or later
            at, more = _seconds(rng, 2, 40), max(GLANCE, _seconds(rng, 0.2, 8))
            aways.append(({"at": at, "for": more}, f"looks away at {at:g}s for {more:g}s"))
    if rng.random() < 0.15:
        before = rng.choice(BEFORE)
        profile["before"] = before
        (task, actions), = before.items()
        story(f"before {task}: {' '.join('+'.join(a) for a in actions)}",
              (*profile_at, "before"), cue=("due-for", task, profile["delay"], partner))
    if rng.random() < 0.1:
        after = rng.choice(HUMAN_TASKS).format(h=partner)
        profile["leave"] = {"after": after}
        story(f"leaves after {after}…", (*profile_at, "leave"), cue=("done", after))
    faults = None
    if rng.random() < 0.2:
        action, times = rng.choice(["pick", "place"]), rng.randint(1, 3)
        faults = [{"action": action, "reason": f"the {action} slipped", "times": times}]
        story(f"{action} fails {times}x", ("scenario", "faults"), cue=("exec", action))
        if times >= 2 and rng.random() < 0.5:  # away while it fails and is replanned
            seconds = _seconds(rng, 1, 12)
            aways.append(({"during": f"{action.capitalize()}(pr2", "for": seconds},
                          f"looks away as the {action} fails, for {seconds:g}s"))
    moments = tuple((a.get("during", a.get("at")), a["for"]) for a, _ in aways)
    for i, (away, says) in enumerate(aways):
        cue = ("away", i, moments, partner, "pr2")
        if len(aways) == 1:
            profile["look-away"] = away
            story(says, (*profile_at, "look-away"), cue=cue)
        else:
            profile.setdefault("look-away", []).append(away)
            story(says, (*profile_at, "look-away", i), cue=cue)
    decide = _seconds(rng, 2, 8)
    if decide != DECISION_WAIT:
        story(f"decides within {decide:g}s", ("scenario", "shared-plan", "decision-wait"),
              cue=("undecided", partner))
    data = stack_partner(partner, profile, decide)
    _noise(rng, data, story, ("isHolding", "looksAt"))
    if faults:
        data["faults"] = faults
    return _finish("stack", seed, "stack-nominal", data, story)


def _noise(rng: random.Random, data: dict[str, Any], story: Story,
           predicates: tuple[str, ...]) -> None:
    if rng.random() < 0.25:
        predicate = rng.choice(predicates)
        p = round(rng.uniform(0.05, 0.35), 2)
        # below the perception's own hold (0.5 s), which would filter most flicker out
        hold = rng.choice([0, 0.3, 0.2, 0.4])
        data["noise"] = {"hold": f"{hold:g}s", "flicker": {predicate: p}}
        story(f"{predicate} flickers {p:g} (hold {hold:g}s)", ("scenario", "noise"),
              cue=("blink", predicate))


def _finish(family: str, seed: int, base: str, data: dict[str, Any], story: Story,
            team: dict[str, Any] | None = None,
            kill: tuple[str, float] | None = None) -> Variation:
    told = "; ".join(story.parts)
    data["scenario"] = f"{base}-fuzz-{seed}"
    data["doc"] = f"shary fuzz {family} --seed {seed}: " + told
    data["expect"] = {}  # a campaign checks its invariants, not a scenario's outcome
    return Variation(family, seed, base, data, team, told, kill, tuple(story.keys))


# ------------------------------------------------------------------------ living room

def _living_room(rng: random.Random, seed: int) -> Variation:
    base = rng.choice(LIVING_BASES)
    data = _base(base)
    story = Story()
    at = ("scenario", "people", "alice", "profile")
    unasked = _profile(data["people"]["alice"]).get("answers") or {}
    asked = ASKED[base]
    answers = {act: _answers(rng, act, story, "alice", unasked.get(act), act in asked)
               for act in ("ASK-TASK", "ASK-HELP")}
    profile: dict[str, Any] = {"answers": {act: a for act, a in answers.items() if a}}
    if rng.random() < 0.1:
        profile["attention"] = rng.choice(LOOKS[1:])
        story(f"looks at {profile['attention']}", (*at, "attention"))
    distractions = []
    for i in range(rng.choices([0, 1, 2], [0.4, 0.45, 0.15])[0]):
        when = ({"robot-starts": rng.choice(ROBOT_ACTIONS)} if rng.random() < 0.6
                else {"at": f"{_seconds(rng, 0, 40):g}s"})
        seconds = rng.choice([f"{_seconds(rng, 0.5, 8):g}s", f"{_seconds(rng, 8, 40):g}s",
                              "never"])
        look = rng.choice(LOOKS)
        distractions.append({"when": when, "after": f"{_seconds(rng, 0, 1):g}s",
                             "look": look, "for": seconds})
        cue = (f"when {when['robot-starts']} starts" if "robot-starts" in when
               else f"at {when['at']}")
        story(f"looks at {look} for {seconds} {cue}", (*at, "distractions", i),
              cue=_when(when, "alice"))
    if distractions:
        profile["distractions"] = distractions
    takes = None if rng.random() < 0.1 else {"after": _span(rng, 0.2, 3)}
    if rng.random() >= 0.85 and "ASK-HELP" in asked:  # helping is what a person does unasked
        profile["helps"] = False
        story("does not help", (*at, "helps"), cue=("agreed", "ASK-HELP", "alice"))
    speed = round(rng.uniform(0.5, 1.3), 2)
    if rng.random() < 0.1:  # she walks only to leave: her pace is drawn for that walk
        leave = _seconds(rng, 1, 40)
        profile["script"] = [{"at": f"{leave:g}s", "leave": True}]
        story(f"leaves at {leave:g}s", (*at, "script"), cue=("at", leave))
        if speed != WALK_SPEED:  # the pace they walk at unless their profile says
            profile["speed"] = speed
            story(f"walks at {speed:g} m/s", (*at, "speed"), cue=("at", leave))
    if "give" in ACTIONS[base]:  # what is held out to her, taken or not (before she leaves)
        profile["takes"] = takes
        soonest = min(float(takes["after"][0].rstrip("s")), UNASKED_TAKE) if takes \
            else UNASKED_TAKE  # when the earlier of her take and the default one comes
        story(f"takes after {'-'.join(takes['after'])}" if takes else "never takes",
              (*at, "takes"), cue=("offered", "alice", soonest,
                                   leave if "script" in profile else None))
    data["people"] = {"alice": {"at": "sofa-seat", "profile": profile}}
    _noise(rng, data, story, ("looksAt", "isHolding"))
    if rng.random() < 0.2:
        action, times = rng.choice(ACTIONS[base]), rng.randint(1, 2)
        data["faults"] = [{"action": action, "reason": f"the {action} went wrong",
                           "times": times}]
        story(f"{action} fails {times}x", ("scenario", "faults"), cue=("exec", action))
    data["timeout"] = "300s"
    return _finish("living-room", seed, base, data, story)


def _when(when: dict[str, Any], person: str) -> tuple[Any, ...]:
    """The cue of a distraction's ``when``: a robot action towards ``person``, or a time."""
    if "robot-starts" in when:
        return ("starts", when["robot-starts"], person)
    return ("at", float(str(when["at"]).rstrip("s")))


def _answers(rng: random.Random, act: str, story: Story, person: str,
             unasked: dict[str, Any] | None, asked: bool = True) -> list[dict[str, Any]]:
    """One to three answers of ``person`` to ``act`` (the first time, the second …; the
    last repeats); ``unasked`` is their base profile's answer to it, what they do
    without one drawn; none are kept where the robot does not ask it (``asked`` false:
    drawn all the same, so that a seed keeps its stream).

    A silence that is what they do anyway (the first, where their profile has no answer;
    a later one after a silence, the last answer repeating) is no key: it only keeps
    the place of the answers after it."""
    at = ("scenario", "people", person, "profile", "answers")
    out: list[dict[str, Any]] = []
    for i in range(rng.choices([1, 2, 3], [0.7, 0.2, 0.1])[0]):
        reply = rng.choices(["H-AGREE", "H-DISAGREE", None], [0.65, 0.15, 0.2])[0]
        late = rng.random() < 0.15
        after = _span(rng, 10, 40) if late else _span(rng, 0.3, 3)
        if not asked:
            continue
        out.append({"reply": reply, "after": after})
        says = f"{act} -> {reply or 'silence'}{' late' if late else ''}"
        # a late answer may come after the robot stopped asking: its moment is its coming
        cue = ("answered", act, person, i + 1, reply) if late and reply else \
            ("asked", act, person, i + 1)
        if i > 0 and (reply is not None or out[-2]["reply"] is not None):
            story(says, (*at, act, i), rest=True, cue=cue)
        elif i == 0 and (reply is not None or unasked is not None):  # without it: their
            # profile's own answer
            story(says, (*at, act), cue=cue, unasked=unasked)
        else:
            story(says)
    return out


# ------------------------------------------------------------------------------- weld

def _weld(rng: random.Random, seed: int) -> Variation:
    base = rng.choice(WELD_BASES)
    data = _base(base)
    team_path = builtin_scenarios()[base].parent / data["team"]
    team = dict(yamlsafe.load_file(team_path).data)
    story = Story()
    agents = {name: dict(spec) for name, spec in team["agents"].items()}
    for name, spec in agents.items():
        if spec.get("kind") != "human":
            continue
        at = ("team", "agents", name, "behaviour")
        behaviour: dict[str, Any] = {}
        if not spec.get("remote"):
            reply = rng.choices(["accept", "refuse", "ignore"], [0.7, 0.15, 0.15])[0]
            behaviour["assignments"] = {"reply": reply, "after": _span(rng, 0.5, 8)}
            if rng.random() < 0.3:  # longer than the site's own mount (about 15 s), which
                # a person's pace can slow but not hasten
                behaviour["works"] = {"mount-panel": _span(rng, 20, 90)}
                works = behaviour["works"]["mount-panel"]
                story(f"{name} mounts in {'-'.join(works)}", (*at, "works"),
                      cue=("row", "message", name, {"to": "world", "skill": "mount-panel"},
                           (name, _upper(works))))
            story(f"{name} {reply}s assignments", (*at, "assignments"),
                  cue=("row", "message", "tasks", {"to": name, "type": "assignment"},
                       (name, _upper(behaviour["assignments"]["after"]))))
        reply = rng.choices(["answer", "refuse", "ignore"], [0.7, 0.15, 0.15])[0]
        behaviour["questions"] = {"reply": reply, "after": _span(rng, 1, 30)}
        asked = ("row", "message", None, {"to": name, "type": "question"},
                 (name, _upper(behaviour["questions"]["after"])))
        story(f"{name} {reply}s questions", (*at, "questions"), cue=asked)
        if "answer" in spec.get("skills", ()):
            answer = rng.choice(["yes", "no"])
            if answer == "no":  # yes is what a person answers unasked (shary/team/proxy.py)
                behaviour["answers"] = {"seam-okay": answer}
                story(f"{name} answers {answer}", (*at, "answers"),
                      cue=("row", "answer", name, {}))
        spec["behaviour"] = behaviour
    team["agents"] = agents
    welds = {}
    welded = {str(spec.get("with", {}).get("seam")) for spec in
              (team.get("goal") or {}).get("tasks", {}).values() if spec.get("do") == "weld-seam"}
    for seam in ("P1-P2", "P2-P3", "P3-P4"):
        if rng.random() < 0.4:
            beads = [round(rng.uniform(0.3, 1.0), 2) for _ in range(rng.randint(1, 3))]
            if seam not in welded:  # drawn all the same, so that a seed keeps its stream
                continue
            welds[seam] = beads
            story(f"{seam} welds {'/'.join(f'{q:g}' for q in welds[seam])}",
                  ("scenario", "welds", seam),
                  cue=("row", "exec-request", None, {"atomic": "weld", "args": {"seam": seam}}))
    if welds:
        data["welds"] = {**(data.get("welds") or {}), **welds}
    if "IVA" in agents and rng.random() < 0.2:
        at_ = _seconds(rng, 1, 30)
        back = round(at_ + _seconds(rng, 1, 30), 1)
        data["script"] = [{"at": f"{at_:g}s", "by": "IVA", "take-control": "K-10"},
                          {"at": f"{back:g}s", "by": "IVA", "hand-back": "K-10"}]
        story(f"IVA holds K-10 {at_:g}-{back:g}s", ("scenario", "script"), cue=("at", at_))
    data["timeout"] = "8min"
    kill = None
    if rng.random() < KILL_CHANCE:
        members = [n for n, spec in agents.items() if spec.get("kind") in ("robot", "human")]
        kill = (rng.choice(members), _seconds(rng, 1, 60))
        story(f"{kill[0]} killed at {kill[1]:g}s", ("kill",), cue=("at", kill[1]))
    return _finish("weld", seed, base, data, story, team, kill)


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
    at = ("scenario", "people", name, "profile")
    profile = _profile(people[name])
    story = Story(base)
    answers = dict(profile.get("answers") or {})
    for act in ("ASK-TASK", "ASK-HELP"):
        if rng.random() < 0.6:
            answers[act] = _answers(rng, act, story, name, answers.get(act))
    profile["answers"] = answers
    base_script = list(profile.get("script") or [])
    asked = [str(step["task"]) for step in base_script if step.get("task")]
    asked += [str(goal["task"]) for goal in data.get("goals") or []]
    added: list[tuple[float, list[dict[str, Any]], list[tuple[str, slice, float]]]] = []
    """Steps drawn, each group at its time with what the story says of its steps (a
    step's ``at`` is absolute: they are kept in the order of their times, after what the
    base scenario's person does)."""
    if rng.random() < 0.3:
        task, words = rng.choice(REQUESTS)
        when = _seconds(rng, 0.5, 30)
        added.append((when, [{"at": f"{when:g}s", "say": words}],
                      [(f"asks {task} at {when:g}s", slice(0, 1), when)]))
        asked.append(task)
    if asked and rng.random() < 0.35:
        when = _seconds(rng, 0.5, 45)  # any phase: asking, fetching, handing over, after
        added.append((when, [{"at": f"{when:g}s", "act": "CANCEL", "task": rng.choice(asked),
                              "say": "Actually, never mind."}],
                      [(f"cancels at {when:g}s", slice(0, 1), when)]))
    if rng.random() < 0.2:
        when = _seconds(rng, 1, 30)
        added.append((when, [{"at": f"{when:g}s", "say": "I'll take the orange bottle myself."}],
                      [(f"takes a step on at {when:g}s", slice(0, 1), when)]))
    if rng.random() < 0.2:
        when = _seconds(rng, 1, 40)
        group: list[dict[str, Any]] = [{"at": f"{when:g}s", "leave": True}]
        says = [(f"leaves at {when:g}s", slice(0, 3), when)]
        if rng.random() < 0.5:
            back = _seconds(rng, 2, 20)
            group += [{"after": f"{back:g}s", "walk": "sofa-end"},
                      {"after": "0.5s", "look": "robot"}]
            says.append((f"comes back {back:g}s later", slice(1, 3), when + back))
        added.append((when, group, says))
    script = list(base_script)
    for _, group, says in sorted(added, key=lambda g: g[0]):
        steps = range(len(script), len(script) + len(group))
        for text, part, moment in says:
            story(text, *((*at, "script", i) for i in steps[part]), cue=("at", moment))
        script += group
    if rng.random() < 0.3:
        when = ({"robot-starts": rng.choice(ROBOT_ACTIONS)} if rng.random() < 0.6
                else {"at": f"{_seconds(rng, 0, 40):g}s"})
        seconds = rng.choice([f"{_seconds(rng, 0.5, 8):g}s", f"{_seconds(rng, 8, 40):g}s",
                              "never"])
        profile["distractions"] = [{"when": when, "look": "phone", "for": seconds}]
        story(f"phone call for {seconds}", (*at, "distractions"), cue=_when(when, name))
    if script:
        profile["script"] = script
    people[name] = {**people[name], "profile": profile}
    if rng.random() < 0.3:
        where = rng.choice(BYSTANDER_AT)
        people["dana"] = {"at": where, "profile": {"attention": "robot"}}
        story(f"dana looks at the robot from {where}", ("scenario", "people", "dana"))
    data["people"] = people
    _noise(rng, data, story, ("looksAt",))
    data["timeout"] = "300s"
    return _finish("dialogue", seed, base, data, story)
