"""Conditional plans: the humans' choices as branches, and the robot's policy over them.

- :mod:`~planner.conditional.exploration` -- the tree of the robot's choices and the
  humans' (:func:`explore`);
- :mod:`~planner.conditional.policy` -- the robot's best answer to every human choice
  (:func:`select`, :class:`Policy`);
- :mod:`~planner.conditional.sharedplan` -- a policy as the supervisor reads it:
  JAHRVIS's abstract and primitive tasks (:func:`to_dict`);
- :mod:`~planner.conditional.agendas` -- reading the keys of conditional problems (open
  variables, agendas, AgentX names).
"""
