"""The estimates that guide the goal-guided searches (heuristics).

- :mod:`~planner.heuristics.grounding` -- the grounded model of an HDDL problem, what a
  relaxed analysis of it can reach;
- :mod:`~planner.heuristics.relaxed` -- the relaxed-composition heuristic: how much a task
  stack still costs through the hierarchy;
- :mod:`~planner.heuristics.subgoals` -- the facts a task stack still needs and what
  reaching them costs (h_add and relaxed plans per fact);
- :mod:`~planner.heuristics.support` -- goal facts with no support left (a relaxed
  regression);
- :mod:`~planner.heuristics.landmarks` -- chains of facts a goal needs in order;
- :mod:`~planner.heuristics.reach` -- which goal facts a task stack may still make true.
"""
