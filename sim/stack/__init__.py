"""The StackBuildingTask of JAHRVIS (Fig. 3) on the simulated PR2-like robot.

* :mod:`sim.stack.table`: the layout on the coffee table (two placements for
  the red base cubes, the stick, blue, green and yellow cubes on each side)
  and what the robot knows of it a priori;
* :mod:`sim.stack.world`: stacking for the executors (place on a cube) and
  the perception (``isOn`` a cube or a placement);
* :mod:`sim.stack.partner`: the human partner who follows the shared plan as
  their profile says (does their part, waits, takes the robot's turn, looks
  away, fumbles, leaves);
* :mod:`sim.stack.planning`: the shared plan from the planner, and the replan
  port (a problem written from what the robot now believes).
"""
