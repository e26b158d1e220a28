"""Pictures of plans, as DOT source and text.

- :mod:`~planner.display.plans` -- the decomposition tree and the per-agent streams;
- :mod:`~planner.display.policies` -- conditional plans: the policy, the explored tree,
  the streams.
"""
