"""The PyBullet world that fills shary's ports.

``shary`` defines the ports a world must fill (executors for atomic tasks, a
perception feed into the fact database, a clock) and never imports PyBullet.
This package is one such world: the living room of the SHARY paper (Clodic et
al. 2009, Fig. 8) with a Jido-like robot, simulated headless by default so whole
human-robot scenarios run as tests.  A real robot would fill the same ports.

The parts:

- :mod:`sim.world` -- :class:`~sim.world.LivingRoom`: the room, its furniture,
  the coloured bottles, the robots, the places of the roadmap, camera snapshots.
- :mod:`sim.kinematics` -- iterated inverse kinematics (``reach``) and direct
  arm placement (``set_arm``).
- :mod:`sim.motion` -- kinematic activities (drive, joints, waits, sequences)
  advanced over simulated time, so physics runs only where contact matters.
- :mod:`sim.room` -- the room's static data (furniture, bottles, places), without PyBullet;
- :mod:`sim.humans` -- behaviour profiles and where people go; :mod:`sim.avatar` -- their bodies;
  :mod:`sim.people` plays a profile out (answers, attention, taking, helping).
- :mod:`sim.simulation` -- ticks on the supervisor's loop, carried objects,
  letting go under physics, people's paths.
- :mod:`sim.executors` -- the robot's atomic tasks (the executor port).
- :mod:`sim.perception` -- facts into the robot's perspective, with noise and
  a hold filter.
- :mod:`sim.scenario` and :mod:`sim.run` -- scenario files, running and
  judging them (``shary run``); ``sim/scenarios``, ``sim/profiles``,
  ``sim/schemas``.
- :mod:`sim.quiet` -- file-descriptor-level silencing of PyBullet's C output.
- :mod:`sim.png` -- a stdlib-only PNG writer and reader for snapshots.
- ``sim/models/`` -- hand-written URDF robots (``jido.urdf``, ``pr2like.urdf``).

The world, kinematics, motion and avatars import nothing from ``shary``;
people's behaviour and the runner are where the world meets the supervisor,
through its ports (executors, facts, act listeners, ``receive_act``).
"""
