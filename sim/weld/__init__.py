"""The seam-welding case of HRI/OS (paper 002, Section 4) in PyBullet: the site, its
robots and astronauts, their executors, and the runs of the ``weld-*`` scenarios."""
