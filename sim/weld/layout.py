"""The seam-welding site's layout, without PyBullet: where the frame, panels, seams and
robot spots are (HRI/OS, paper 002 Fig. 6).  Scenario files are checked against it
before any world is built."""

from __future__ import annotations

import math

PANELS = ("P1", "P2", "P3", "P4")
PANEL_WIDTH, PANEL_HEIGHT, PANEL_THICKNESS = 1.0, 1.0, 0.03
PANEL_MASS = 15.0
PANEL_Z = 1.05
"""Height of a mounted panel's centre (its bottom edge is at 0.55 m)."""
PANEL_Y = -0.07
"""A mounted panel's centre: just south of the frame's beams."""
FACING_SOUTH = -math.pi / 2
"""Where a mounted panel's front (and the work side of the site) faces."""
PALLET = (6.0, -2.5)
PALLET_TOP = 0.15
SEAM_BEAD = 0.012
"""Half the width of a weld bead, in metres."""


def panel_x(panel: str) -> float:
    """Where panel P1…P4 is mounted along the frame."""
    return PANELS.index(panel) + 0.5


def seam_panels(seam: str) -> tuple[str, str]:
    """``"P2-P3"`` -> ("P2", "P3"), checked (ValueError for a seam the frame does not have)."""
    left, _, right = seam.partition("-")
    if left not in PANELS or right not in PANELS or PANELS.index(right) != PANELS.index(left) + 1:
        raise ValueError(f"no seam {seam!r} on the frame (seams: {', '.join(SEAMS)})")
    return left, right


SEAMS = tuple(f"{a}-{b}" for a, b in zip(PANELS, PANELS[1:], strict=False))


def seam_x(seam: str) -> float:
    left, _ = seam_panels(seam)
    return panel_x(left) + PANEL_WIDTH / 2


def robot_places() -> dict[str, tuple[float, float, float]]:
    """Where the robots stand, by name: home spots, a welding spot and an inspection spot
    for each seam (facing the frame)."""
    places = {"robonaut-home": (-1.5, -1.6, 0.0), "k10-home": (-1.5, -3.2, 0.0)}
    for seam in SEAMS:
        x = seam_x(seam)
        places[f"weld-{seam}"] = (x + 0.25, -0.72, math.pi / 2)
        # west of the seam, so the welder (on its east side) does not hide it
        places[f"inspect-{seam}"] = (x - 1.0, -2.2, math.pi / 2)
    return places
