"""The searches: from a problem to a plan.

- :mod:`~planner.search.portfolio` -- :func:`plan`, the planner's one entry, and the IPC
  mode's searches run one after the other within one budget;
- :mod:`~planner.search.branchbound` -- the SHOP2-style anytime branch-and-bound search
  of the planner's YAML domains (:class:`Search`, :class:`Result`), with
  :mod:`~planner.search.step` (an action's step compiled once) and
  :mod:`~planner.search.bound` (the admissible lower bound it prunes with);
- :mod:`~planner.search.depthfirst` -- depth-first total-order decomposition to the
  first plan, with :mod:`~planner.search.checks` (threats, goals out of reach);
- :mod:`~planner.search.progression` -- greedy best-first progression guided by the goal,
  and :mod:`~planner.search.restarts` -- its restarts in other orders;
- :mod:`~planner.search.binding` and :mod:`~planner.search.late` -- binding a method's
  variables from the state's facts, now or when first needed.
"""
