"""The PyBullet world that fills shary's ports.

``shary`` defines the ports a world must fill (executors for atomic tasks, a
perception feed into the fact database, a clock) and never imports PyBullet.
This package is one such world: the living room of the SHARY paper (Clodic et
al. 2009, Fig. 8) with a Jido-like robot, simulated headless by default so whole
human-robot scenarios run as tests.  A real robot would fill the same ports.

What is here so far is the groundwork:

- :mod:`sim.world` -- :class:`~sim.world.LivingRoom`: the room, its furniture,
  the coloured bottles, the robots, the places of the roadmap, camera snapshots.
- :mod:`sim.kinematics` -- iterated inverse kinematics (``reach``) and direct
  arm placement (``set_arm``).
- :mod:`sim.quiet` -- file-descriptor-level silencing of PyBullet's C output,
  which would otherwise pollute machine-read standard output.
- :mod:`sim.png` -- a stdlib-only PNG writer and reader for snapshots.
- ``sim/models/`` -- hand-written URDF robots (``jido.urdf``, ``pr2like.urdf``).

Nothing here imports ``shary``: the dependency goes the other way round only
through the ports, which keeps the engine testable with small fakes.
"""
