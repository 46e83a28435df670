"""Navigation scenarios: goal sets per world and the office's unmapped boxes.

`GOALS` holds at least two goal sets for each navigation world; `with_boxes`
adds square boxes to a world (the simulator drives in that world while the
robot plans and localizes on the plain map); `office_with_boxes` is the
office with the two unmapped boxes of the navigation tests and bench.

Imports the world layer only.
"""

from __future__ import annotations

import numpy as np

from ..world import World, load_world

__all__ = ["GOALS", "OFFICE_BOXES", "with_boxes", "office_with_boxes"]

GOALS = {
    "office": {
        "south": [(2.5, 3.0), (12.5, 3.0), (7.5, 5.2), (17.5, 3.0), (10.0, 7.5)],
        "north": [(3.0, 10.0), (9.0, 12.0), (14.0, 11.5), (18.0, 10.5), (17.5, 7.5)],
    },
    "maze": {
        "corners": [(11.75, 8.75), (11.75, 1.25), (1.25, 8.75), (5.75, 5.75)],
        "inner": [(4.25, 4.25), (8.75, 7.25), (10.25, 4.25), (2.75, 2.75)],
    },
}
"""Goal sets, m: ``GOALS[world][set]`` is a list of ``(x, y)``, each free in
the world's configuration space and reachable from its start."""

OFFICE_BOXES = [(6.0, 7.1, 0.5), (13.5, 3.5, 0.6)]
"""The office's unmapped boxes: centre ``(x, y)`` and side, m (one in the
corridor, one in a south room)."""


def with_boxes(world: World, boxes, name: str | None = None) -> World:
    """Return ``world`` with axis-aligned square boxes added as walls.

    Parameters
    ----------
    world : World
        The world.
    boxes : sequence of (x, y, side)
        Box centres and sides, m.
    name : str, optional
        The new world's name (default: the old one with ``"+boxes"``).
    """
    segs = [world.segments]
    for x, y, side in boxes:
        h = side / 2
        c = [(x - h, y - h), (x + h, y - h), (x + h, y + h), (x - h, y + h)]
        segs.append(np.array([[*c[k], *c[(k + 1) % 4]] for k in range(4)]))
    return World(
        np.concatenate(segs),
        bounds=world.bounds,
        start=world.start,
        points=world.points,
        name=name or f"{world.name}+boxes",
    )


def office_with_boxes() -> World:
    """Return the office with `OFFICE_BOXES` (for the simulator, not for the map)."""
    return with_boxes(load_world("office"), OFFICE_BOXES)
