"""The seam-welding site as the team's world agent, at the address ``world``.

:class:`WeldWorld` builds the :class:`~sim.weld.site.WeldSite` as a scenario
says (panels mounted, seams welded, each robot and on-site person where the
team file's ``at`` puts them: a robot with a ``welding-tool`` is the humanoid,
any other the rover; a person who is not ``remote`` is an avatar) and serves
the team through the message port (:mod:`shary.team.world` is the other side):

- an ``Assignment`` from a robot is one of its atomic tasks
  (:mod:`sim.weld.executors`), whose outcome goes back as ``Progress``; an
  inspection's verdict is kept as a fact (``SEAM verdict sound|unsure``), which
  the robots' recipes choose by;
- an ``Assignment`` from a person is their work on site (``mount-panel``:
  they carry the panel and tack it, and physics has the last word; it is over
  no sooner than their behaviour's ``works`` says, when the team file gives it);
- a ``QUERY`` for ``attach``: what a question carries (for ``seam-okay``, a
  picture of the seam from the robot's camera, its path and its bytes);
- ``SUBSCRIBE``: the facts it perceives (:class:`~sim.weld.perception.SitePerception`:
  poses, panels mounted, seams welded, verdicts), shared as ``FactChange``
  messages (:mod:`shary.transport.facts`);
- K-10's ``point-light`` asks the spatial reasoning agent where the words
  point (and the speaker, when they are ambiguous), as messages too.

It runs on whatever loop it is given: the team's, in one process (``shary run``),
or its own on the team's shared clock (``shary world``, :mod:`sim.weld.agent`).
Its physics ticks are timers on that loop.
"""

from __future__ import annotations

import base64
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.kernel.executors import Outcome, Reporter, Request
from shary.team.agents import INFORM, QUERY
from shary.team.world import ATTACH, CANCEL, WORLD
from shary.transport.facts import SUBSCRIBE, FactSharing
from shary.transport.messages import PICTURE, Act, Answer, Assignment, Message, Progress, Question
from shary.transport.port import MessagePort
from shary.transport.wire import MAX_BYTES

from ..simulation import Simulation
from .executors import SiteActions
from .perception import SitePerception
from .scenario import WeldScenario
from .site import WeldSite

HUMANOID_RESOURCE = "welding-tool"
ASK_SPEAKER_FOR = 30.0
"""Seconds K-10 waits for a speaker to say which object or corner they meant."""
SEAM_QUESTION = "seam-okay"
SUITS = ((0.95, 0.95, 0.93, 1.0), (0.93, 0.55, 0.2, 1.0), (0.3, 0.55, 0.9, 1.0))
"""Suit colours, one per astronaut in turn (white, orange, blue)."""
MOUNT = "mount-panel"
"""The people's work the site performs."""

Record = Callable[..., Any]
"""The context log's ``record(kind, task=…, agent=…, **data)`` of whoever runs the world."""


class WeldWorld:
    """The site, its executors, perception and avatars, serving the team (see the module)."""

    def __init__(self, scenario: WeldScenario, site: WeldSite, port: MessagePort,
                 facts: Any, record: Record, out_dir: Path | None = None):
        self.scenario = scenario
        self.site = site
        self.port = port
        self.loop = port.loop
        self.facts = facts
        self.record = record
        spec = scenario.team
        for panel in scenario.mounted:
            site.mount(panel)
        for seam, quality in scenario.welded.items():
            site.lay_bead(seam, quality)
        for robot in spec.of_kind("robot"):
            model = "pr2like" if HUMANOID_RESOURCE in robot.resources else "k10"
            x, y = robot.at[:2] if robot.at else (0.0, -3.0)
            site.add_robot(robot.name, model, (x, y, math.pi / 2))
        self.sim = Simulation(site, self.loop, next(iter(site.robots), ""))
        self.actions = SiteActions(site, self.sim, qualities=scenario.welds,
                                   snapshot_dir=out_dir, tell=self._told)
        for i, person in enumerate(p for p in spec.of_kind("human") if not p.remote):
            x, y = person.at[:2] if person.at else (5.0 + i, -3.4)
            self.actions.add_person(person.name, x, y, math.pi / 2, SUITS[i % len(SUITS)])
        self.light = _Light(self)
        self.running: dict[str, Request] = {}
        """Request id -> the robot's atomic task being performed (to cancel it)."""
        self.work: dict[str, tuple[Assignment, int, str, list[str]]] = {}
        """Request id -> a person's work under way: the assignment, its activity, the
        panel and its carriers (to stop it when one of them leaves)."""
        self.gone: set[str] = set()
        """People who left the site (:meth:`left`): no work is theirs any more."""
        self.sharing = FactSharing(facts, port, WORLD)
        facts.log_changes(record)  # the site as perceived, in the log (the Facts panel)
        self.perception = SitePerception(site, self.actions.people, facts)
        self.perception.a_priori()
        self.perception.update()
        self.sim.observers.append(self.perception.update)
        port.subscribe(WORLD, self.handle)

    def _told(self, who: str, kind: str, text: str) -> None:
        self.record("site", agent=who, what=kind, text=text)

    # -- messages ----------------------------------------------------------------------

    def handle(self, message: Message) -> None:
        if isinstance(message, Assignment):
            if message.skill == MOUNT and message.sender in self.actions.people:
                self._mount(message)
            else:
                self._perform(message)
        elif isinstance(message, Act) and message.act == CANCEL:
            request = self.running.pop(message.id, None)
            if request is not None:
                self._executor(request.atomic).cancel(request)
        elif isinstance(message, Act) and message.act == QUERY:
            self._serve(message)
        elif isinstance(message, Act) and message.act == SUBSCRIBE:
            self.sharing.subscribe(message.sender)
        elif not self.light.heard(message):
            self.record("message-ignored", agent=WORLD, type=message.kind)

    def _reply(self, to: Message, status: str, reason: str = "",
               data: dict[str, Any] | None = None) -> None:
        self.port.send(Progress(WORLD, to.sender, id=to.id, task=getattr(to, "task", ""),
                                status=status, reason=reason, data=data or {}))

    def _executor(self, atomic: str) -> Any:
        if atomic == "point-light":
            return self.light
        if atomic == "inspect":
            return _Verdicts(self.actions, self.facts)
        return self.actions

    def _perform(self, message: Assignment) -> None:
        """A robot's atomic task: performed on the site, its outcome sent back."""
        request = Request(message.id, message.skill, dict(message.args), message.sender,
                          message.task)
        odd = [k for k, v in request.args.items() if not isinstance(v, (str, int, float))]
        if odd:  # the recipes' arguments are names and numbers; anything else is refused
            self._reply(message, "failed", f"{request.atomic}: argument {odd[0]!r} is "
                        "neither a name nor a number")
            return
        self.running[request.id] = request

        def over(outcome: Outcome) -> None:
            if self.running.pop(request.id, None) is not None:
                self._reply(message, outcome.status, outcome.reason, outcome.result)

        try:
            self._executor(request.atomic).start(request, Reporter(over, self.loop.call_soon))
        except (KeyError, TypeError, ValueError) as err:  # arguments of the wrong kind:
            self.running.pop(request.id, None)             # refused, the world goes on
            self._reply(message, "failed", f"{request.atomic} cannot be done with "
                        f"{json.dumps(request.args)[:120]}: {err}")

    def _mount(self, message: Assignment) -> None:
        """A person's ``mount-panel``: they (and their helper) carry the panel and tack it."""
        panel = str(message.args.get("panel", ""))
        carriers = [message.sender, *[h for h in [message.args.get("helper")] if h]]
        gone = [c for c in carriers if c in self.gone]
        if gone:
            self._reply(message, "failed", f"{gone[0]} has left the site: nobody to carry "
                        f"{panel} with")
            return

        start, works = self.loop.now(), self._works(message.sender, MOUNT)

        def over() -> None:
            if message.id not in self.work:
                return  # stopped: one of them left
            more = start + works - self.loop.now()
            if more > 0 and self.site.mounted(panel):
                # tacked; they go on working on it as long as their behaviour says
                self.loop.call_later(more, over)
                return
            self.work.pop(message.id, None)
            if self.site.mounted(panel):
                self._reply(message, "done")
            else:  # physics had the last word: something stood in the way
                self._reply(message, "failed", f"{panel} did not reach its place on the "
                            "frame")

        try:
            self.work[message.id] = (message, self.actions.mount(panel, carriers, over),
                                     panel, carriers)
        except KeyError as err:
            self._reply(message, "failed", str(err.args[0]))
        except TypeError:
            self._reply(message, "failed", f"no such helper: {message.args.get('helper')!r}")

    def _works(self, person: str, skill: str) -> float:
        """How long ``person`` takes over a task of ``skill`` by their behaviour's
        ``works`` (drawn on the loop's seeded generator), or 0: the physics alone
        decides (carrying and tacking take what they take)."""
        agent = self.scenario.team.agents.get(person)
        behaviour = agent.behaviour if agent is not None else None
        if behaviour is None:
            return 0.0
        delay = behaviour.works.get(skill) or behaviour.works.get("*")
        if delay is None:
            return 0.0
        low, high = delay
        return low if high <= low else self.loop.random.uniform(low, high)

    def left(self, name: str) -> None:
        """``name`` left the site (their process died): the work they took part in stops
        where it is, and the panel it carried is put down on the ground, as a person
        leaving would put it down rather than walk off holding it; whoever else asked
        for that work is told it failed, and the panel waits there for the next carrier."""
        self.gone.add(name)
        for request_id, (message, handle, panel, carriers) in list(self.work.items()):
            if name not in carriers:
                continue
            del self.work[request_id]
            self.sim.stop(handle)
            put_down = self.actions.set_down(panel, carriers)
            if put_down:
                x, y, _ = self.site.position(panel)
                self.record("put-down", agent=name, panel=panel, at=[round(x, 2), round(y, 2)],
                            carriers=carriers, why=f"{name} left")
                self.perception.update()
            if message.sender != name:
                self._reply(message, "failed", f"{name} left"
                            + (f": {panel} was put down" if put_down else ""))

    def _serve(self, message: Act) -> None:
        service = message.data.get("service")
        if service == ATTACH:
            task = message.data.get("team-task")
            try:
                data = self.attachment(str(message.data.get("topic")),
                                       str(message.data.get("robot") or message.sender),
                                       None if task is None else str(task))
            except KeyError as err:  # no such robot: nothing to take a picture with
                data = {"error": f"no picture: {err}"}
        else:
            data = {"error": f"the world offers no service {service!r} (it offers {ATTACH})"}
        self.port.send(Act(WORLD, message.sender, id=message.id, act=INFORM,
                           data={"service": service, **data}, task=message.task))

    # -- what questions carry -------------------------------------------------------------

    def attachment(self, topic: str, robot: str, task: str | None) -> dict[str, Any]:
        """What a question of ``topic`` carries: for ``seam-okay``, a picture of the seam
        from the robot's camera (its head still aimed at it), and which seam.

        The picture travels in the question (base64 PNG, :data:`PICTURE`), taken whether
        or not the run keeps files (so a run judges the same either way), besides its path
        when it does: whoever answers may be on another machine, where a path means nothing.
        A 480x360 picture is 12-25 kB, far inside a message's 1 MiB; a larger one
        would go as its path only."""
        if topic != SEAM_QUESTION:
            return {}
        found = self.scenario.team.tasks.get(task or "")
        seam = str(found.args.get("seam")) if found is not None else None
        picture = self.actions.picture(robot, f"{robot}: is this seam okay? ({seam})")
        image = self.actions.keep(robot, f"question-{seam or 'seam'}", picture)
        data: dict[str, Any] = {k: v for k, v in (("image", image), ("seam", seam)) if v}
        png = base64.b64encode(picture).decode("ascii")
        if len(png) < MAX_BYTES // 2:
            data[PICTURE] = png
        return data


class _Verdicts:
    """The site's executors, with what an inspection read kept as a fact (``SEAM verdict
    sound|unsure``), which the recipes choose by (ask a person when unsure)."""

    def __init__(self, actions: SiteActions, facts: Any):
        self.actions = actions
        self.facts = facts

    def start(self, request: Request, reporter: Reporter) -> None:
        self.actions.start(request, _Noting(reporter, self.facts))

    def cancel(self, request: Request) -> None:
        self.actions.cancel(request)


class _Noting:
    """A reporter that notes an inspection's verdict as a fact before passing it on."""

    def __init__(self, reporter: Reporter, facts: Any):
        self.reporter = reporter
        self.facts = facts

    def done(self, request: Request, **result: Any) -> None:
        self.facts.set(request.args["seam"], "verdict", str(result.get("verdict")))
        self.reporter.done(request, **result)

    def failed(self, request: Request, reason: str) -> None:
        self.facts.remove(request.args["seam"], "verdict", "unsure")
        self.reporter.failed(request, reason)

    def cancelled(self, request: Request, reason: str = "cancelled") -> None:
        self.reporter.cancelled(request, reason)


class _Light:
    """K-10's ``point-light``: the words go to the spatial reasoning agent (a ``QUERY``
    through the message port); its point is where the head turns.  An ambiguous reference
    comes back as a question, which K-10 puts to the speaker (a multiple-choice
    ``Question`` message, answered through the person's proxy): a chosen corner is
    lit, a chosen object is resolved again; no answer within :data:`ASK_SPEAKER_FOR`
    seconds, or a question without choices, fails the step with the question."""

    def __init__(self, world: WeldWorld):
        self.world = world
        self.agents = world.scenario.team.agents
        self.waiting: dict[str, tuple[Request, Reporter]] = {}
        """Query or question id -> the step waiting for it."""
        self.meanings: dict[str, dict[str, Any]] = {}
        """Question id -> what each of its choices means (a point, an object's name)."""
        self.timers: dict[str, Any] = {}

    def start(self, request: Request, reporter: Reporter, referent: str | None = None) -> None:
        reasoner = next((a.name for a in self.agents.values() if "spatial" in a.services),
                        None)
        if reasoner is None:
            reporter.failed(request, "no agent of the team offers spatial reasoning")
            return
        port = self.world.port
        qid = port.new_id("s")
        self.waiting[qid] = (request, reporter)
        port.send(Act(WORLD, reasoner, id=qid, act=QUERY, data={
            "service": "spatial", "words": request.args.get("words", ""),
            "speaker": request.args.get("speaker", ""), "addressee": request.agent,
            **({"referent": referent} if referent else {})}))

    def heard(self, message: Message) -> bool:
        """A reply to one of its queries or questions (False: not one)."""
        key = message.id if isinstance(message, Act) else getattr(message, "question", "")
        found = self.waiting.pop(key, None)
        if found is None:
            return False
        request, reporter = found
        if isinstance(message, Answer):
            self._answered(message, request, reporter)
        elif isinstance(message, Act) and message.act == INFORM:
            self._informed(message.data, request, reporter)
        return True

    def _informed(self, data: dict[str, Any], request: Request, reporter: Reporter) -> None:
        world = self.world
        world.record("spatial", agent=request.agent, **{
            k: v for k, v in data.items() if k not in ("service", "answers")})
        point = data.get("point")
        if point:
            self._aim(point, request, reporter)
            return
        speaker = str(data.get("to") or request.args.get("speaker", ""))
        choices = tuple(data.get("choices") or ())
        if not choices or speaker not in self.agents:
            reporter.failed(request, f"ambiguous: {data.get('question') or data.get('error')}")
            return
        qid = world.port.new_id("q")
        self.waiting[qid] = (request, reporter)
        self.meanings[qid] = dict(data.get("answers") or {})
        world.record("question", task=request.node, agent=request.agent, question=qid,
                     text=data.get("question"), question_type="multiple-choice",
                     choices=list(choices), to=speaker, expires=ASK_SPEAKER_FOR)
        world.port.send(Question(WORLD, speaker, id=qid, text=str(data.get("question")),
                                 type="multiple-choice", choices=choices,
                                 expires=ASK_SPEAKER_FOR, topic="spatial", task=request.node))
        self.timers[qid] = world.loop.call_later(ASK_SPEAKER_FOR, self._unanswered, qid)

    def _answered(self, answer: Answer, request: Request, reporter: Reporter) -> None:
        meaning = self.meanings.pop(answer.question, {}).get(str(answer.value))
        timer = self.timers.pop(answer.question, None)
        if timer is not None:
            timer.cancel()
        self.world.record("answer", task=request.node, agent=answer.sender,
                          question=answer.question, asker=request.agent, value=answer.value)
        if isinstance(meaning, list):
            self._aim(meaning, request, reporter)
        elif isinstance(meaning, str):
            self.start(request, reporter, referent=meaning)
        else:
            reporter.failed(request, f"{answer.sender} answered {answer.value!r}, not one of "
                                     "the choices")

    def _unanswered(self, qid: str) -> None:
        self.timers.pop(qid, None)
        found = self.waiting.pop(qid, None)
        self.meanings.pop(qid, None)
        if found is not None:
            request, reporter = found
            reporter.failed(request, f"nobody said which within {ASK_SPEAKER_FOR:g}s")

    def _aim(self, point: list[float], request: Request, reporter: Reporter) -> None:
        x, y, z = (float(v) for v in point)
        aim = Request(request.id, "point-light", {"x": x, "y": y, "z": z}, request.agent,
                      request.node)
        self.world.actions.start(aim, reporter)

    def cancel(self, request: Request) -> None:
        for qid, (waiting, _) in list(self.waiting.items()):
            if waiting.id == request.id:
                del self.waiting[qid]
                self.meanings.pop(qid, None)
        self.world.actions.cancel(request)
