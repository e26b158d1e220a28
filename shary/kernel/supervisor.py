"""The supervisor: tasks, their schemes and acts, on one loop, logged.

SHARY's execution stream (Fig. 3): "when the task is created, a communication
scheme associated to the task is instantiated according to the task, the
context and the concerned agent.  This scheme gives the first act to execute.
The recipe corresponding to that act ... is instantiated ... During Act
Execution, communication and execution monitoring is done through wait on
Expected Acts.  When a monitor is triggered ... the current act is stopped and
the answer is instantiated given the communication scheme."

:class:`Supervisor` holds the parts (recipe library, fact database, executors,
loop, task tree, agenda, context log); :class:`TaskRun` is one task being
carried out, listening to its scheme instance: entering a state with an act
creates an :class:`~shary.kernel.acttask.ActTask`, leaving it stops that act.  An act
state entered inside another act's state suspends the outer act (the person
looked away: WAIT-ATTENTION inside REALIZE-TASK), which resumes when the
inner one is left.

Nothing here knows about bottles or a particular robot: agents, tasks and
atomic tasks all come from files and from whoever fills the executor port.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import replace
from typing import Any, Protocol

from shary.kernel.acttask import ActTask, StepRun
from shary.kernel.executors import ExecutorRegistry, Outcome, Reporter, Request, record_outcome
from shary.kernel.loop import EventLoop
from shary.kernel.recipes import (
    INITIATOR_PARAM,
    ROBOT_PARAM,
    Condition,
    PlanSpec,
    Recipe,
    RecipeLibrary,
    Step,
    TaskType,
    Term,
)
from shary.kernel.tasktree import CANCELLED, DONE, FAILED, ONGOING, SUSPENDED, TASK, TaskTree
from shary.statechart.compiler import CompiledScheme, compile_scheme
from shary.statechart.conditions import ConditionRegistry
from shary.statechart.instance import Event, SchemeInstance, SchemeListener
from shary.statechart.model import Scheme, State
from userfiles.errors import FileError, Problem


class Planner(Protocol):
    """What a planner-backed recipe needs: a list of steps for a task in the current facts."""

    def plan_steps(self, spec: PlanSpec, args: dict[str, Any], facts: Any) -> list[Step]: ...

    # A planner that honours plan negotiation also takes ``assigned=`` (the steps people
    # took on: shary.dialogue.negotiation.Taken); it is passed only when there are some.


RecipeFunction = Callable[["TaskRun", Recipe], list[Step]]
"""A Python recipe: returns the steps of an act x task, given its task run."""


class Supervisor:
    """One robot's supervision: see the module's docstring."""

    def __init__(self, library: RecipeLibrary, facts: Any, *, robot: str = "robot",
                 loop: EventLoop | None = None, executors: ExecutorRegistry | None = None,
                 log: Any = None, conditions: ConditionRegistry | None = None,
                 planners: dict[str, Planner] | None = None,
                 functions: dict[str, RecipeFunction] | None = None,
                 ids: str = ""):
        self.library = library
        self.facts = facts
        self.robot = robot
        self.loop = loop or EventLoop()
        self.executors = executors or ExecutorRegistry()
        self.log = log
        self.conditions = conditions or ConditionRegistry()
        self.planners = dict(planners or {})
        self.functions = dict(functions or {})
        self.tree = TaskTree(self.record if log is not None else None, prefix=f"{ids}n")
        from shary.kernel.arbiter import BodyArbiter

        self.executors.arbiter = BodyArbiter(self.tree, self.loop, self.record)
        """One owner for the head and the arms (:mod:`shary.kernel.arbiter`)."""
        self.ids = ids
        """A prefix of node and request ids (``K-10/``): a team's robots share one log."""
        self.runs: dict[str, TaskRun] = {}
        self._by_agent: dict[str, dict[str, TaskRun]] = {}
        self._compiled: dict[int, CompiledScheme] = {}
        self._requests: dict[str, tuple[StepRun, ActTask]] = {}
        self._request_ids = itertools.count(1)
        self.reporter = Reporter(self._outcome, self.loop.call_soon, self._begun)
        self.act_listeners: list[Callable[[TaskRun, State, str], Any]] = []
        """Told when an act starts (task run, its state, the agent): what people around
        the robot see and hear it begin — simulated people answer from here."""
        self.initiative: list[Callable[[str, str, Any], bool]] = []
        """Told of an act that no task expects (agent, act, data), in order, until one
        takes it (returns True): how a person starts, cancels or changes a task
        (:mod:`shary.dialogue.initiative`)."""
        self.background: dict[str, TaskRun] = {}
        """Tasks that last as long as an interaction (sessions): they hear acts and
        facts like the others, but do not count as work left (:attr:`runs`)."""
        if log is not None and hasattr(log, "flush"):
            self.loop.idle_hooks.append(log.flush)
        from shary.dialogue import install
        from shary.kernel.agenda import TaskAgenda

        self.agenda = TaskAgenda(self)
        from shary.dialogue.speech import Speech

        self.speech = Speech(facts)
        """Makes the sentences of ``say`` steps (shary/dialogue/speech.py)."""
        self.recognizer: Any = None
        """Human action recognition, once :meth:`recognize` has loaded action models."""
        self.robot_actions: Any = None
        """The robot's actions from their models (look, act, retry, escalate)."""
        self.dialogue = install(self)
        """Person-initiated acts, questions and sessions (:mod:`shary.dialogue`)."""

    def recognize(self, models: Any, perspective: str = "robot") -> Any:
        """Follow what people do with these action models (:mod:`shary.recognition`) and
        perform the robot's modelled actions; returns the started Recognizer.

        Recognition runs inside fact delivery (it only updates its candidates and
        logs ``recognition`` rows); whoever listens to it and acts should queue
        its work on the loop, as monitors do.
        """
        from shary.recognition.execution import RobotActions
        from shary.recognition.recognizer import Recognizer

        if self.recognizer is not None:  # new models replace the old, never run beside them
            self.recognizer.stop()
        self.recognizer = Recognizer(models, self.facts, perspective=perspective,
                                     clock=self.loop.now, record=self.record)
        self.robot_actions = RobotActions(self, models)
        self.recognizer.start()
        return self.recognizer

    # -- the context log -------------------------------------------------------

    def record(self, kind: str, task: str | None = None, agent: str | None = None,
               **data: Any) -> None:
        """Time-stamp an event into the context log (None values left out)."""
        if self.log is not None:
            self.log.record(self.loop.now(), kind, task=task, agent=agent,
                            **{k: v for k, v in data.items() if v is not None})

    # -- tasks -----------------------------------------------------------------

    def start_task(self, name: str, args: dict[str, Any], *, parent: ActTask | None = None,
                   parent_node: str | None = None, step: StepRun | None = None,
                   on_finish: Callable[[TaskRun], None] | None = None,
                   scheme: Scheme | None = None, initiator: str | None = None,
                   background: bool = False) -> TaskRun:
        """Create a task and start its scheme (raise KeyError/ValueError on a bad call).

        ``scheme`` replaces the one the task would choose (the variant of a task a
        person asked for); ``initiator`` is the agent who asked, who plays the
        scheme's roles the task does not fill; a ``background`` task is kept
        apart from :attr:`runs` (see :attr:`background`)."""
        task_type = self.library.tasks[name]
        _check_nesting(name, parent)
        missing = [p for p in task_type.params if p not in args]
        extra = [a for a in args if a not in task_type.params and a != ROBOT_PARAM]
        if missing or extra:
            raise ValueError(f"task {name!r} takes {', '.join(task_type.params) or 'nothing'}; "
                             f"missing: {missing}, unknown: {extra}")
        run = TaskRun(self, task_type, dict(args), parent, parent_node, step, on_finish,
                      scheme, initiator)
        (self.background if background else self.runs)[run.node] = run
        for agent in set(run.roles.values()):
            self._by_agent.setdefault(agent, {})[run.node] = run
        run.start()
        return run

    def tasks_with(self, agent: str) -> list[TaskRun]:
        """The tasks running now in which ``agent`` plays a role (background ones too)."""
        return [run for run in self._by_agent.get(agent, {}).values() if not run.ended]

    def cancel_task(self, node: str, reason: str) -> None:
        """Cancel a running task from outside (an operator): it stops, and its parent act or
        its goal hears that it failed (raise KeyError when no such task runs)."""
        run = self.runs[node]
        run.cancel(reason)
        self.loop.call_soon(run._report)

    def forget(self, run: TaskRun) -> None:
        """Drop an ended task from the live indexes (its tree and log stay)."""
        self.runs.pop(run.node, None)
        self.background.pop(run.node, None)
        for agent in set(run.roles.values()):
            self._by_agent.get(agent, {}).pop(run.node, None)

    def compiled(self, scheme: Scheme) -> CompiledScheme:
        found = self._compiled.get(id(scheme))
        if found is None:
            found = self._compiled[id(scheme)] = compile_scheme(scheme, self.conditions)
        return found

    def holds(self, conditions: tuple[Condition, ...], env: dict[str, Any]) -> bool:
        """Whether facts satisfy conditions (the robot's perspective; ``_`` object: any).
        A condition whose subject is unbound (``$initiator`` of a task nobody asked for)
        is about no one: it fails, negated or not."""
        for condition in conditions:
            s, p, o = condition.pattern.resolve(env)
            if s is None:
                return False
            if o is None:
                found = bool(self.facts.objects(s, p))
            else:
                found = self.facts.holds(s, p, o)
            if found == condition.negated:
                return False
        return True

    def choose_scheme(self, task_type: TaskType, env: dict[str, Any]) -> Scheme:
        for choice in task_type.schemes:
            if self.holds(choice.when, env):
                return choice.scheme
        raise LookupError(f"no scheme of task {task_type.name!r} fits the context")

    def choose_recipe(self, run: TaskRun, act: str) -> Recipe | None:
        """The first recipe of (task, act) whose conditions hold, and whose events (``on``)
        include the one that entered the act: several may serve one act."""
        for recipe in self.library.recipes_for(run.type.name, act):
            if recipe.on and run.entered_on.get(act) not in recipe.on:
                continue
            if self.holds(recipe.when, run.env):
                return recipe
        return None

    def expand(self, run: TaskRun, recipe: Recipe) -> list[Step]:
        """The steps of a recipe: scripted, from a planner, or from a Python function."""
        if recipe.plan is not None:
            planner = self.planners.get(recipe.plan.domain) or self.planners.get("*")
            if planner is None:
                raise LookupError(f"recipe {recipe.name!r} needs a planner for domain "
                                  f"{recipe.plan.domain!r}; none is registered")
            args = {k: t.resolve(run.env) for k, t in recipe.plan.args.items()}
            more = {"assigned": tuple(run.assigned)} if run.assigned else {}
            try:
                steps = planner.plan_steps(recipe.plan, args, self.facts, **more)
            except RuntimeError as err:
                raise LookupError(str(err)) from err
            steps = [s if s.atomic is None or s.atomic in self.library.atomic
                     else replace(s, atomic=None, task=s.atomic) for s in steps]
            self.record("plan", task=run.node, recipe=recipe.name,
                        steps=[s.name for s in steps])
            return steps
        if recipe.function is not None:
            function = self.functions.get(recipe.function)
            if function is None:
                raise LookupError(f"recipe {recipe.name!r} names the function "
                                  f"{recipe.function!r}, which is not registered")
            return list(function(run, recipe))
        return list(recipe.steps)

    # -- acts from agents -------------------------------------------------------

    def receive_act(self, agent: str, act: str, data: Any = None,
                    task: str | None = None) -> None:
        """An agent communicated ``act`` (H-AGREE …): delivered to the tasks that expect it."""
        self.loop.call_soon(self._receive_act, agent, act, data, task)

    def _receive_act(self, agent: str, act: str, data: Any, task: str | None) -> None:
        about = data.get("task") if isinstance(data, dict) and task is None else None
        self.record("act-received", task=task, agent=agent, act=act,
                    name=about if isinstance(about, str) else None,
                    initiated=True if task is None else None)
        taken = False
        for run in list(self._by_agent.get(agent, {}).values()):
            if run.ended or run.paused or (task is not None and run.node != task):
                continue
            if run.expects(act):
                if act == "CANCEL":
                    run.stopped_by = f"cancelled by {agent}"
                run.deliver(act, {"agent": agent, "data": data})
                taken = True
        if not taken and task is None:
            taken = any(handler(agent, act, data) for handler in self.initiative)
        if not taken:
            self.record("act-unexpected", task=task, agent=agent, act=act)

    # -- executors ----------------------------------------------------------------

    def execute(self, atomic: str, args: dict[str, Any], agent: str, node: str,
                act: ActTask) -> Request:
        problem = None
        if atomic == "say":  # a generated sentence, said by the speak executor
            try:
                atomic, args = "speak", {"text": self.speech.say(args, agent)}
            except ValueError as err:
                problem = str(err)
        request = Request(f"{self.ids}r{next(self._request_ids)}", atomic, args, agent, node)
        run = next(r for r in act.steps.values() if r.node == node)
        self._requests[request.id] = (run, act)
        self.executors.dispatch(request, self.reporter, self.record, problem=problem)
        return request

    def cancel_request(self, request: Request, reason: str) -> None:
        self.record("exec-cancel", task=request.node, agent=request.agent, request=request.id,
                    reason=reason)
        executor = self.executors.get(request.atomic)
        if executor is not None:
            executor.cancel(request)

    def _begun(self, request: Request) -> None:
        found = self._requests.get(request.id)
        if found is not None:
            run, act = found
            act.begun(run)

    def _outcome(self, outcome: Outcome) -> None:
        record_outcome(self.record, outcome)
        found = self._requests.pop(outcome.request.id, None)
        if found is not None:
            run, act = found
            act.outcome(run, outcome)

    def missing_executors(self) -> list[str]:
        """Atomic tasks the library declares that no executor performs."""
        return [a for a in self.library.atomic if self.executors.get(a) is None]


MAX_TASK_DEPTH = 64
"""Tasks one task may be nested in.  A recipe that starts its own task first, whatever its
``when:`` (the facts are the same at the same instant), nests it without end: the run
stops at this depth, at the recipe's line, rather than at Python's stack limit."""


def _check_nesting(name: str, parent: ActTask | None) -> None:
    """Refuse a subtask :data:`MAX_TASK_DEPTH` tasks deep (:class:`FileError` at the recipe)."""
    depth, act = 1, parent
    while act is not None and depth <= MAX_TASK_DEPTH:
        depth, act = depth + 1, act.run.parent
    recipe = parent.recipe if parent is not None else None
    if depth > MAX_TASK_DEPTH and recipe is not None:
        raise FileError([Problem(recipe.file, *recipe.mark, f"task {name!r} is nested more "
                                 f"than {MAX_TASK_DEPTH} tasks deep by recipe {recipe.name!r}: "
                                 "a recipe that starts its own task again before anything "
                                 "ends it never stops (the run was stopped)")])


class TaskRun(SchemeListener):
    """One task being carried out: its scheme instance and its act x task nodes."""

    def __init__(self, sup: Supervisor, task_type: TaskType, args: dict[str, Any],
                 parent: ActTask | None, parent_node: str | None, step: StepRun | None,
                 on_finish: Callable[[TaskRun], None] | None, scheme: Scheme | None = None,
                 initiator: str | None = None):
        self.sup = sup
        self.type = task_type
        self.robot = str(args.get(ROBOT_PARAM, sup.robot))
        self.env: dict[str, Any] = {ROBOT_PARAM: self.robot, **args}
        self.parent = parent
        self.step = step
        self.on_finish = on_finish
        if step is not None:
            # the step's own node becomes the task's: one node per subtask in the tree
            self.node = step.node
            sup.tree.node(self.node)["args"] = args or None
        else:
            self.node = sup.tree.add(TASK, task_type.name, parent_node, args=args or None)
        self.scheme = scheme or sup.choose_scheme(task_type, self.env)
        self.initiator = initiator
        if initiator is not None:  # recipes may name the person who asked ($initiator)
            self.env.setdefault(INITIATOR_PARAM, initiator)
        self.roles = {role: _role_agent(role, task_type.roles.get(role), self.env)
                      for role in self.scheme.roles}
        if initiator is not None:  # the asker plays the human roles no parameter fills
            self.roles.update({role: initiator for role, kind in self.scheme.roles.items()
                               if kind == "human" and self.roles[role] == role})
        self.compiled = sup.compiled(self.scheme)
        self.acts: dict[str, ActTask] = {}
        self.entered_on: dict[str, str | None] = {}
        """Act -> the event (as the scheme writes it) that last entered a state carrying it."""
        self.entered_data: dict[str, Any] = {}
        """Act -> the data of that event (what a person's answer said)."""
        self.assigned: list[Any] = []
        """Steps people took on in negotiating this task's plan
        (:class:`shary.dialogue.negotiation.Taken`): its planner-backed recipes plan with them."""
        self.instance: SchemeInstance | None = None
        self.ended = False
        self.paused = False
        self.outcome: str | None = None
        self.stopped_by: str | None = None
        """Who asked it to stop (a person's CANCEL, which its scheme answers): the reason
        its goal gives when it then ends undone."""

    def __repr__(self) -> str:
        return f"<TaskRun {self.type.name} {self.node} {self.outcome or 'running'}>"

    def start(self) -> None:
        self.sup.tree.set_state(self.node, ONGOING)
        self.sup.record("task-start", task=self.node, agent=self.robot, name=self.type.name,
                        scheme=self.scheme.name, roles=self.roles, initiator=self.initiator)
        self.instance = self.compiled.start(clock=self.sup.loop.clock, listener=self,
                                            context=self)

    @property
    def configuration(self) -> tuple[str, ...]:
        return self.instance.configuration if self.instance is not None else ()

    def expects(self, event: str) -> bool:
        """Whether some active state of the scheme has a transition on ``event``."""
        return self.instance is not None and self.compiled.expects(self.instance.state, event)

    # -- events into the scheme --------------------------------------------------

    def deliver(self, event: str, data: Any = None) -> None:
        if self.ended or self.paused or self.instance is None:
            return
        self.sup.record("event", task=self.node, event=event)
        self.instance.send(event, data)

    def deliver_soon(self, event: str, data: Any = None, act: ActTask | None = None) -> None:
        """Deliver ``event`` once the current one is handled; an event of ``act``'s (its
        step's emit, its end, a monitor's) is dropped if the act has been left by then:
        a step whose emit took the scheme elsewhere must not also end the act there."""
        self.sup.loop.call_soon(self._deliver_of, event, data, act)

    def _deliver_of(self, event: str, data: Any, act: ActTask | None) -> None:
        if act is None or self.acts.get(act.state.name) is act:
            self.deliver(event, data)

    # -- the scheme's listener -----------------------------------------------------

    def entered(self, instance: SchemeInstance, state: State, event: Event | None) -> None:
        self.sup.record("enter", task=self.node, state=state.name,
                        event=event.name if event else None)
        if state.act is None:
            return
        agent = self.roles.get(state.by or "", self.robot)
        self.entered_on[state.act] = event.name.split("@")[0] if event else None
        self.entered_data[state.act] = event.data if event else None
        self.sup.record("act", task=self.node, agent=agent, act=state.act,
                        act_type=state.act_type.name if state.act_type else None)
        for listener in self.sup.act_listeners:
            listener(self, state, agent)
        outer = self._enclosing_act(state)
        if outer is not None:
            outer.suspend(f"{state.act} entered")
        act = ActTask(self, state, agent)
        self.acts[state.name] = act
        if not self.paused:
            act.start()

    def exited(self, instance: SchemeInstance, state: State, event: Event | None) -> None:
        self.sup.record("exit", task=self.node, state=state.name,
                        event=event.name if event else None)
        act = self.acts.pop(state.name, None)
        if act is not None:
            act.stop(f"left {state.name}" + (f" on {event.name}" if event else ""))
            self.sup.loop.call_soon(self._resume_enclosing)

    def finished(self, instance: SchemeInstance, state: State) -> None:
        self.ended = True
        self.outcome = state.outcome
        self.sup.tree.set_state(self.node, DONE if state.outcome == "done" else FAILED,
                                f"ended in {state.name}")
        self.sup.record("task-end", task=self.node, name=self.type.name, outcome=state.outcome,
                        state=state.name)
        self.sup.loop.call_soon(self._report)

    def _report(self) -> None:
        self.sup.forget(self)
        if self.parent is not None and self.step is not None:
            self.parent.step_finished(self.step, DONE if self.outcome == "done" else FAILED,
                                      f"task {self.type.name} {self.outcome}")
        if self.on_finish is not None:
            self.on_finish(self)

    def _enclosing_act(self, state: State) -> ActTask | None:
        ancestor = state.parent
        while ancestor is not None:
            act = self.acts.get(ancestor.name)
            if act is not None:
                return act
            ancestor = ancestor.parent
        return None

    def _has_inner_act(self, act: ActTask) -> bool:
        return any(other.state.is_descendant_of(act.state) for other in self.acts.values())

    def _resume_enclosing(self) -> None:
        if self.ended or self.paused:
            return
        for act in list(self.acts.values()):
            if act.suspended and not self._has_inner_act(act):
                act.resume("inner act over")

    # -- the agenda's control -------------------------------------------------------

    def suspend(self, reason: str) -> None:
        """Suspend the whole task: its acts stop acting, its scheme hears nothing."""
        if self.ended or self.paused:
            return
        self.paused = True
        self.sup.tree.set_state(self.node, SUSPENDED, reason)
        if self.instance is not None:
            self.instance.freeze()
        for act in self.acts.values():
            act.suspend(reason)

    def resume(self, reason: str) -> None:
        if self.ended or not self.paused:
            return
        self.paused = False
        self.sup.tree.set_state(self.node, ONGOING, reason)
        if self.instance is not None:
            self.instance.thaw()
        for act in list(self.acts.values()):
            if self._has_inner_act(act):
                continue
            if not act.started:
                act.start()
            else:
                act.resume(reason)

    def cancel(self, reason: str) -> None:
        """Stop the task for good (its parent's act was stopped)."""
        if self.ended:
            return
        for act in list(self.acts.values()):
            act.stop(reason)
        self.acts.clear()
        self.ended = True
        self.outcome = "cancelled"
        if self.instance is not None:  # its timers too: a give-up due in 30 s must not come
            self.instance.cancel()
        self.sup.record("task-end", task=self.node, name=self.type.name, outcome="cancelled",
                        reason=reason)
        self.sup.forget(self)
        if self.node in self.sup.tree:
            self.sup.tree.set_state(self.node, CANCELLED, reason)


def _role_agent(role: str, term: Term | None, env: dict[str, Any]) -> str:
    if term is not None:
        value = term.resolve(env)
        if value is not None:
            return str(value)
    if role in env:
        return str(env[role])
    return str(env[ROBOT_PARAM]) if role == ROBOT_PARAM else role
