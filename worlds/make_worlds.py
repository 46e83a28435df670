"""Generate the shipped worlds in this folder.

Run ``python worlds/make_worlds.py`` from the repository root to rewrite
``corridor.wld``, ``corridor_periodic.wld``, ``corridor2.wld``, ``maze.wld``,
``arena.wld``, the avoidance worlds (``clutter``, ``doorway``, ``utrap``,
``alcoves``, each with a ``.pairs.json``), ``loop.wld``, ``office.map`` and
``building.map``. The files
themselves are committed; this script documents how they were made and
regenerates them identically (the maze and the clutter use fixed seeds).

All coordinates here are whole millimetres, as in the files.

- ``corridor``: the paper's aliased corridor. A 28 m x 2 m corridor with seven
  1 m doors on each side into closed rooms. In the middle (16 m) the doors
  face each other every 4 m, so places there look alike to eight sonars, and
  a single scan near either end looks like one near the other end turned
  round. It is not symmetric (no half turn or mirror maps it onto itself),
  and the door sequence a robot meets driving east from the start (a south
  door, a north door 2 m on, the first facing pair 3 m further) is found
  nowhere else in the corridor, either way round: a filter can tell where it
  is after about 8 m. The north-west corner is chamfered, and an alcove opens
  off the north wall near the east end.
- ``corridor_periodic``: the teaching counter-example, the corridor as first
  drawn: doors every 4 m on both sides from the west end for 14 m. Driving
  east from the start, every scan for the first ~12 m is repeated exactly
  4 m further on (and by the half-turned corridor), so no filter can localize
  there by step 25; the first differences (a north door shifted by 0.5 m at
  15 m, the east end's alcove) come later.
- ``corridor2``: a second aliased corridor, 1.8 m wide, 19 m long with 0.9 m
  doors every 3 m (3.5 m on the north side), then an L bend north for 10 m
  with three more rooms; for testing MCL on a corridor it was not tuned on.
- ``maze``: an 8 x 6 maze of 1.5 m cells (a seeded depth-first maze with a
  few extra openings, so there are loops).
- ``arena``: an open 10 m x 10 m arena with six box obstacles.
- ``clutter``: the obstacle-avoidance arena, 10 m x 8 m with 10 seeded boxes
  (0.3 to 0.8 m sides) in its middle, at least 0.9 m apart; start/goal pairs
  from the west strip to the east strip.
- ``doorway``: two 5.5 m x 6 m rooms joined by one 0.8 m door off the middle
  of the wall between them; pairs from the west room to the east room.
- ``utrap``: a 12 m x 8 m hall with a U-shaped trap (3 m wide, 2 m deep, open
  to the west) between the start strip and the goal strip, the goal straight
  behind the trap's bottom: the trap that catches potential fields.
- ``alcoves``: a 16 m x 2 m corridor with 1 m alcoves on both sides; pairs
  from the west end to the east end.
- The avoidance worlds each have a sidecar ``NAME.pairs.json``: the regions
  that seeded start/goal pairs are drawn from
  (`robotlib.avoidance.start_goal_pairs`).
- ``loop``: a 20 m x 15 m building whose 2 m corridors run in a loop around
  eight rooms (open doors onto the corridor, different north and south),
  with pilasters on the outer walls; one lap is about 62 m, enough for
  odometry alone to miss closing the loop by a metre or more (mapping, SLAM).
- ``office``: a 20 m x 15 m office in MobileSim ``2D-Map`` form: a corridor,
  seven rooms, a table and a shelf as DATA points, a ``Sim.BoxObstacle``, a
  ``Dock`` before the ``RobotHome`` (the home wins) and a ``ForbiddenArea``.
- ``building``: a 17 m x 31 m office building in MobileSim ``2D-Map`` form,
  the size and wall count (244 walls, 32 points) of MobileSim's sample
  ``AMROffice.map`` but our own seeded geometry: offices on two corridors,
  meeting rooms and an open hall with columns, racks and crates
  (`building`). The real-building part of the paper's experiment (Lab 3's
  kidnapping section) runs here, since AMROffice itself is GPL and not ours.

Not shipped, made on demand: ``python worlds/make_worlds.py --large FILE``
writes `large_map`, a 24 m x 52 m floor drawn as about 60,000 DATA points
(the size and point count of MobileSim's sample ``columbia.map``), which
``robotlib bench large-map`` times.
"""

from __future__ import annotations

import itertools
import json
import math
import random
from pathlib import Path

from robotlib.world import World, write_wld

HERE = Path(__file__).resolve().parent

Segment = tuple[int, int, int, int]


def wall_with_doors(a: int, b: int, doors, at: int, vertical: bool) -> list[Segment]:
    """Wall from ``a`` to ``b`` along one axis at ``at``, with door gaps.

    ``doors`` are ``(lo, hi)`` openings along the wall, sorted.
    """
    pieces, pos = [], a
    for lo, hi in sorted(doors):
        if lo > pos:
            pieces.append((pos, lo))
        pos = hi
    if pos < b:
        pieces.append((pos, b))
    if vertical:
        return [(at, lo, at, hi) for lo, hi in pieces]
    return [(lo, at, hi, at) for lo, hi in pieces]


def rooms(
    at: int, partitions: list[int], doors, depth: int, vertical: bool = False
) -> list[Segment]:
    """Build a row of closed rooms along a corridor wall.

    The corridor wall lies at ``at`` (a y for a horizontal row, an x for a
    vertical one) from the first to the last partition, with ``doors``; the
    rooms reach ``depth`` (signed) away from it, separated by ``partitions``
    (which include both end walls).
    """
    a, b = partitions[0], partitions[-1]
    back = at + depth
    segs = wall_with_doors(a, b, doors, at, vertical)
    segs += wall_with_doors(a, b, [], back, vertical)
    for p in partitions:
        segs.append((at, p, back, p) if vertical else (p, at, p, back))
    return segs


def box(x: int, y: int, w: int, h: int) -> list[Segment]:
    """Four walls of an axis-aligned rectangle with corner ``(x, y)``."""
    return [
        (x, y, x + w, y),
        (x + w, y, x + w, y + h),
        (x + w, y + h, x, y + h),
        (x, y + h, x, y),
    ]


def to_world(
    segments: list[Segment], size: tuple[int, int], start: tuple[int, int, float]
) -> World:
    """Make a World (metres, radians) from millimetre walls, size and start (deg)."""
    return World(
        segments=[[v / 1000 for v in s] for s in segments],
        bounds=(0.0, 0.0, size[0] / 1000, size[1] / 1000),
        start=(start[0] / 1000, start[1] / 1000, math.radians(start[2])),
    )


CORRIDOR_ENDS = [
    (500, 3000, 500, 4500),  # west end, chamfered at the north corner
    (500, 4500, 1000, 5000),
    (28500, 3000, 28500, 5000),  # east end, flat
    # the north wall beyond the last room, with an alcove 1 m x 0.6 m
    (27000, 5000, 27300, 5000),
    (27300, 5000, 27300, 5600),
    (27300, 5600, 28300, 5600),
    (28300, 5600, 28300, 5000),
    (28300, 5000, 28500, 5000),
    (27000, 7500, 28500, 7500),  # close the solid block behind the alcove
    (28500, 5000, 28500, 7500),
]
"""The two 28 m corridors' end walls and east alcove, mm."""


def corridor() -> World:
    """Build the paper's long aliased corridor (28 m x 2 m).

    Door centres (m): south 2.6, 7.6, 11.6, 15.6, 19.6, 23.6, 27.0; north 4.6,
    7.6, 11.6, 15.6, 19.6, 23.6, 25.7. From 7.6 to 23.6 the doors face each
    other every 4 m (rooms 4 m wide, centred on their doors): a stretch where
    every scan repeats 4 m along, and 2.2 m along the other way round. The
    west end opens a south door, 2 m later a north one, 3 m later the first
    pair; the east end, the other way round, a north door then a south door
    1.3 m apart and an alcove. Those two door sequences, met from either end,
    are found nowhere else.
    """
    south = rooms(
        3000,
        [500, 5600, 9600, 13600, 17600, 21600, 25600, 28500],
        [
            (2100, 3100),
            (7100, 8100),
            (11100, 12100),
            (15100, 16100),
            (19100, 20100),
            (23100, 24100),
            (26500, 27500),
        ],
        -2500,
    )
    north = rooms(
        5000,
        [500, 5600, 9600, 13600, 17600, 21600, 24600, 27000],
        [
            (4100, 5100),
            (7100, 8100),
            (11100, 12100),
            (15100, 16100),
            (19100, 20100),
            (23100, 24100),
            (25200, 26200),
        ],
        2500,
    )
    return to_world(south + north + CORRIDOR_ENDS, (29000, 8000), (1500, 4000, 0.0))


def corridor_periodic() -> World:
    """Build the teaching corridor whose doors repeat every 4 m (28 m x 2 m)."""
    south = rooms(
        3000,
        [500, 5000, 9000, 13000, 17000, 21000, 25000, 28500],
        [
            (2500, 3500),
            (6500, 7500),
            (10500, 11500),
            (14500, 15500),
            (18500, 19500),
            (22500, 23500),
            (26000, 27000),  # 3.5 m after the previous door, not 4 m
        ],
        -2500,
    )
    north = rooms(
        5000,
        [500, 5000, 9000, 13000, 17000, 21000, 25000, 27000],
        [
            (2500, 3500),
            (6500, 7500),
            (10500, 11500),
            (15000, 16000),  # shifted by 0.5 m
            (18500, 19500),
            (22500, 23500),
            (25500, 26500),
        ],
        2500,
    )
    return to_world(south + north + CORRIDOR_ENDS, (29000, 8000), (1500, 4000, 0.0))


def corridor2() -> World:
    """Build a second aliased corridor: 1.8 m wide, 19 m, then an L bend north."""
    south = rooms(
        2500,
        [500, 3500, 6500, 9500, 12500, 15500, 19800],
        [
            (1500, 2400),
            (4500, 5400),
            (7500, 8400),
            (10500, 11400),
            (13500, 14400),
            (16800, 17700),
        ],
        -2000,
    )
    north = rooms(
        4300,
        [500, 4000, 7500, 11000, 14500, 18000],
        [(2000, 2900), (5500, 6400), (9000, 9900), (12500, 13400), (15500, 16400)],
        2000,
    )
    # the vertical leg's west rooms: x 16000..18000, y 6300..14000
    west = rooms(
        18000,
        [6300, 9300, 12300, 14000],
        [(7300, 8200), (10300, 11200), (12800, 13700)],
        -2000,
        vertical=True,
    )
    rest = [
        (500, 2500, 500, 4300),  # west end of the corridor
        (19800, 2500, 19800, 14000),  # east wall of the L
        (18000, 14000, 19800, 14000),  # north end of the L
    ]
    return to_world(south + north + west + rest, (20500, 14500), (1500, 3400, 0.0))


def loop() -> World:
    """Build the loop building: a 2 m corridor ring around eight rooms (20 x 15 m)."""
    segs = box(500, 500, 20000, 15000)
    partitions = [2500, 6500, 10500, 14500, 18500]
    segs += rooms(
        2500,
        partitions,
        [(4000, 5000), (8500, 9500), (12000, 13000), (16000, 17000)],
        5500,
    )
    north = rooms(
        13500,
        partitions,
        [(3500, 4500), (7500, 8500), (12500, 13500), (15500, 16500)],
        -5500,
    )
    segs += [s for s in north if s not in segs]
    # pilasters (0.3 m deep, 0.4 m long) on the outer walls
    segs += box(500, 4500, 300, 400) + box(500, 9500, 300, 400)
    segs += box(20200, 6000, 300, 400) + box(20200, 11000, 300, 400)
    segs += box(7000, 500, 400, 300) + box(13500, 500, 400, 300)
    segs += box(5500, 15200, 400, 300) + box(11000, 15200, 400, 300)
    segs += box(16500, 15200, 400, 300)
    return to_world(segs, (21000, 16000), (1500, 1500, 0.0))


def maze(cols: int = 8, rows: int = 6, cell: int = 1500, seed: int = 7) -> World:
    """Build a seeded depth-first maze of ``cols`` x ``rows`` cells of ``cell`` mm."""
    rnd = random.Random(seed)
    x0 = y0 = 500
    # open[(c, r, dc, dr)]: the wall between cell (c, r) and (c + dc, r + dr) is open
    opened: set[tuple[int, int, int, int]] = set()
    seen = {(0, 0)}
    stack = [(0, 0)]
    while stack:
        c, r = stack[-1]
        nbrs = [
            (c + dc, r + dr)
            for dc, dr in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= c + dc < cols
            and 0 <= r + dr < rows
            and (c + dc, r + dr) not in seen
        ]
        if not nbrs:
            stack.pop()
            continue
        nc, nr = rnd.choice(nbrs)
        a, b = min((c, r), (nc, nr)), max((c, r), (nc, nr))
        opened.add((a[0], a[1], b[0] - a[0], b[1] - a[1]))
        seen.add((nc, nr))
        stack.append((nc, nr))
    # a few extra openings make loops
    walls = [
        (c, r, dc, dr)
        for c in range(cols)
        for r in range(rows)
        for dc, dr in ((1, 0), (0, 1))
        if c + dc < cols and r + dr < rows and (c, r, dc, dr) not in opened
    ]
    for w in rnd.sample(walls, 4):
        opened.add(w)
    segs: list[Segment] = []
    # horizontal walls: between rows r-1 and r (r = 0 and rows are the outside)
    for r in range(rows + 1):
        y = y0 + r * cell
        run = None
        for c in range(cols + 1):
            closed = c < cols and (r in (0, rows) or (c, r - 1, 0, 1) not in opened)
            if closed and run is None:
                run = c
            elif not closed and run is not None:
                segs.append((x0 + run * cell, y, x0 + c * cell, y))
                run = None
    for c in range(cols + 1):
        x = x0 + c * cell
        run = None
        for r in range(rows + 1):
            closed = r < rows and (c in (0, cols) or (c - 1, r, 1, 0) not in opened)
            if closed and run is None:
                run = r
            elif not closed and run is not None:
                segs.append((x, y0 + run * cell, x, y0 + r * cell))
                run = None
    size = (2 * x0 + cols * cell, 2 * y0 + rows * cell)
    return to_world(segs, size, (x0 + cell // 2, y0 + cell // 2, 0.0))


def arena() -> World:
    """Build an open 10 m x 10 m arena with six boxes."""
    segs = box(500, 500, 10000, 10000)
    for b in [
        (2500, 2500, 1000, 1000),
        (6500, 2000, 1500, 800),
        (4500, 5500, 800, 1600),
        (7500, 7000, 1200, 1200),
        (2000, 7500, 600, 1400),
        (8500, 4500, 700, 700),
    ]:
        segs += box(*b)
    return to_world(segs, (11000, 11000), (1500, 1500, 45.0))


def clutter(seed: int = 11, n_boxes: int = 10) -> World:
    """Build the cluttered arena: 10 m x 8 m, seeded boxes in its middle.

    Boxes are dropped at random, each at least 0.9 m (edge to edge, along
    either axis) from the others; a layout that gets stuck starts over.
    """
    rnd = random.Random(seed)
    segs = box(500, 500, 10000, 8000)
    placed: list[tuple[int, int, int, int]] = []
    tries = 0
    while len(placed) < n_boxes:
        tries += 1
        if tries > 2000:  # stuck: start the layout over
            placed, tries = [], 0
        w, h = rnd.randrange(300, 801, 50), rnd.randrange(300, 801, 50)
        x, y = rnd.randrange(2800, 8200 - w, 50), rnd.randrange(1300, 7700 - h, 50)
        if all(
            x > bx + bw + 900
            or bx > x + w + 900
            or y > by + bh + 900
            or by > y + h + 900
            for bx, by, bw, bh in placed
        ):
            placed.append((x, y, w, h))
    for b in placed:
        segs += box(*b)
    return to_world(segs, (11000, 9000), (1500, 4500, 0.0))


def doorway() -> World:
    """Build two rooms joined by one 0.8 m door (centre 3.1 m from the south)."""
    segs = box(500, 500, 11000, 6000)
    segs += wall_with_doors(500, 6500, [(3200, 4000)], 6000, vertical=True)
    return to_world(segs, (12000, 7000), (1500, 3500, 0.0))


def utrap() -> World:
    """Build a hall with a U-shaped trap open towards the start (west)."""
    segs = box(500, 500, 12000, 8000)
    segs += [
        (5000, 3000, 7000, 3000),  # south arm
        (7000, 3000, 7000, 6000),  # bottom
        (7000, 6000, 5000, 6000),  # north arm
    ]
    return to_world(segs, (13000, 9000), (2000, 4500, 0.0))


def alcoves() -> World:
    """Build a 16 m x 2 m corridor with 1 m x 0.8 m alcoves on both sides."""
    south = [(3000, 4000), (7500, 8500), (12000, 13000)]
    north = [(5000, 6000), (9500, 10500), (14000, 15000)]
    segs = wall_with_doors(500, 16500, south, 1000, vertical=False)
    segs += wall_with_doors(500, 16500, north, 3000, vertical=False)
    for lo, hi in south:
        segs += [(lo, 1000, lo, 200), (lo, 200, hi, 200), (hi, 200, hi, 1000)]
    for lo, hi in north:
        segs += [(lo, 3000, lo, 3800), (lo, 3800, hi, 3800), (hi, 3800, hi, 3000)]
    segs += [(500, 1000, 500, 3000), (16500, 1000, 16500, 3000)]
    return to_world(segs, (17000, 4000), (1200, 2000, 0.0))


PAIRS = {
    "clutter": {"start": [1.2, 1.2, 2.2, 7.8], "goal": [8.8, 1.2, 9.8, 7.8]},
    "doorway": {"start": [1.2, 1.2, 5.0, 5.8], "goal": [7.0, 1.2, 10.8, 5.8]},
    "utrap": {"start": [1.5, 3.5, 3.0, 5.5], "goal": [8.5, 3.5, 10.0, 5.5]},
    "alcoves": {"start": [0.9, 1.6, 1.8, 2.4], "goal": [15.2, 1.6, 16.1, 2.4]},
}
"""Per avoidance world: regions ``[xmin, ymin, xmax, ymax]`` (m) of starts, goals."""


def write_pairs(name: str) -> None:
    """Write ``NAME.pairs.json``: where seeded start/goal pairs are drawn."""
    doc = {
        "world": name,
        "start_region": PAIRS[name]["start"],
        "goal_region": PAIRS[name]["goal"],
        "clearance": 0.7,
        "heading": "towards the goal, +-45 deg",
        "units": "m",
    }
    text = json.dumps(doc, indent=1) + "\n"
    (HERE / f"{name}.pairs.json").write_text(text, encoding="ascii")


def office_map() -> str:
    """Return the text of ``office.map`` (20 m x 15 m)."""
    segs = box(0, 0, 20000, 15000)
    # corridor y 6500..8500 across the building; rooms south and north
    segs += wall_with_doors(
        0,
        20000,
        [(2000, 3000), (7000, 8000), (11500, 12500), (16500, 17500)],
        6500,
        False,
    )
    segs += wall_with_doors(
        0, 20000, [(2500, 3500), (8500, 9500), (14500, 15500)], 8500, False
    )
    segs += [(x, 0, x, 6500) for x in (5000, 10000, 15000)]
    segs += [(x, 8500, x, 15000) for x in (6000, 12000)]
    segs += [(16000, 8500, 16000, 12500)]  # a half wall in the north-east room
    points = []
    for k in range(24):  # a round table, 0.6 m radius, in the north-west room
        a = 2 * math.pi * k / 24
        points.append(
            (3000 + round(600 * math.cos(a)), 12000 + round(600 * math.sin(a)))
        )
    points += [(x, 14700) for x in range(6500, 11501, 250)]  # a shelf, north wall
    lines = [
        "2D-Map-Ex2",
        "Sources: robotlib",
        "MinPos: -500 -500",
        "MaxPos: 20500 15500",
        f"NumPoints: {len(points)}",
        "PointsAreSorted: false",
        "LineMinPos: 0 0",
        "LineMaxPos: 20000 15000",
        f"NumLines: {len(segs)}",
        "LinesAreSorted: false",
        "Resolution: 100",
        'MapInfo: ObjectType Name=Sim.BoxObstacle "Label=Box" Shape=Rectangle',
        'Cairn: Dock 18500 7500 180.000000 "" ICON "dock"',
        'Cairn: RobotHome 1500 7500 0.000000 "" ICON "home"',
        'Cairn: Goal 17500 12000 0.000000 "" ICON "lab"',
        'Cairn: Sim.BoxObstacle 7500 3000 0.000000 "" ICON "crate" 7000 2500 8000 3500',
        'Cairn: ForbiddenArea 0 0 0.000000 "" ICON "stairs" 17000 13000 19500 14500',
        "LINES",
        *(" ".join(str(v) for v in s) for s in segs),
        "DATA",
        *(f"{x} {y}" for x, y in points),
    ]
    return "\n".join(lines) + "\n"


def _furnish(rnd: random.Random, room: tuple[int, int, int, int], door: str):
    """Return a desk against the back wall and a cabinet in a back corner, mm.

    ``room`` is ``(x0, y0, x1, y1)``; ``door`` the side its door is on
    (``"S"``, ``"N"``, ``"W"``, ``"E"``), so the furniture stands against the
    opposite wall, 0.1 m off it, and leaves the door's half free.
    """
    x0, y0, x1, y1 = room
    dw, dd = rnd.choice([(1400, 700), (1600, 800), (1200, 600)])  # desk
    cw, cd = 500, rnd.choice([800, 900, 1000])  # cabinet: depth, length
    gap = 100
    boxes = []
    if door in ("S", "N"):  # furniture along the north / south wall
        back = y1 - gap - dd if door == "S" else y0 + gap
        lo = rnd.randrange(x0 + 300, max(x0 + 301, x1 - dw - 300 - cd - 200), 50)
        boxes.append((lo, back, dw, dd))
        cy = y1 - gap - cw if door == "S" else y0 + gap
        boxes.append((x1 - gap - cd, cy, cd, cw))
    else:  # furniture along the west / east wall
        back = x1 - gap - dd if door == "W" else x0 + gap
        lo = rnd.randrange(y0 + 300, max(y0 + 301, y1 - dw - 300 - cd - 200), 50)
        boxes.append((back, lo, dd, dw))
        cx = x1 - gap - cw if door == "W" else x0 + gap
        boxes.append((cx, y1 - gap - cd, cw, cd))
    return boxes


def building(seed: int = 17) -> tuple[list[Segment], list[tuple[int, int]]]:
    """Return the walls and DATA points (mm) of ``building.map`` (17 m x 31 m).

    An office building of our own drawing, in the spirit of MobileSim's
    sample ``AMROffice.map`` (a 17 m x 31 m floor of offices beside a large
    open hall) but none of its geometry:

    - an office wing in the south, y 0-11 m: a 2 m east-west corridor at
      y 4.5-6.5 m with a row of offices on each side, seeded widths (about 3.4 m)
      and door places (1 m doors);
    - a 2 m north-south corridor at x 7.5-9.5 m from there to the hall, with
      two seeded meeting rooms on each side (doors onto it, and a second door
      into the hall from the west and east ones next to it);
    - an open hall in the north, y 17-31 m: pilasters on its outer walls,
      four columns, shelving racks, seeded crates and two round tables
      (DATA points), and two small offices in its north-east corner.

    Every office and meeting room has a desk and a cabinet (boxes) against
    the wall opposite its door.
    """
    rnd = random.Random(seed)
    W, H = 17000, 31000
    segs: list[Segment] = []
    furniture: list[tuple[int, int, int, int]] = []

    def partitions(a: int, b: int, n: int) -> list[int]:
        """Cut ``a``-``b`` into ``n`` rooms: equal widths, cuts moved up to 0.4 m."""
        inner = [
            a + (b - a) * k // n + rnd.randrange(-400, 401, 100) for k in range(1, n)
        ]
        return [a, *(100 * round(c / 100) for c in inner), b]

    def doors_in(cuts: list[int]) -> list[tuple[int, int]]:
        """One seeded 1 m door per room, 0.3 m or more from its partitions."""
        out = []
        for p, q in itertools.pairwise(cuts):
            lo = rnd.randrange(p + 300, q - 1300 + 1, 100)
            out.append((lo, lo + 1000))
        return out

    # outline, with a 0.6 m entrance recess at corridor A's west end
    segs += [
        (0, 0, W, 0),
        (W, 0, W, H),
        (W, H, 0, H),
        (0, H, 0, 6000),
        (0, 6000, -600, 6000),
        (-600, 6000, -600, 5000),
        (-600, 5000, 0, 5000),
        (0, 5000, 0, 0),
    ]
    # the office wing: corridor A at y 4.5-6.5 m
    south = partitions(0, W, 5)
    sdoors = doors_in(south)
    segs += wall_with_doors(0, W, sdoors, 4500, vertical=False)
    segs += [(x, 0, x, 4500) for x in south[1:-1]]
    for p, q in itertools.pairwise(south):
        furniture += _furnish(rnd, (p, 0, q, 4500), "N")
    west = partitions(0, 7500, 2)
    east = partitions(9500, W, 2)
    ndoors = doors_in(west) + doors_in(east)
    segs += wall_with_doors(0, W, [*ndoors, (7500, 9500)], 6500, vertical=False)
    segs += [(x, 6500, x, 11000) for x in (*west[1:-1], *east[1:-1])]
    for cuts in (west, east):
        for p, q in itertools.pairwise(cuts):
            furniture += _furnish(rnd, (p, 6500, q, 11000), "S")
    segs += [(0, 11000, 7500, 11000), (9500, 11000, W, 11000)]
    # corridor B, x 7.5-9.5 m, y 6.5-17 m, with meeting rooms on both sides
    mid = {side: rnd.randrange(13300, 14800, 100) for side in "WE"}
    w0, e0 = 11500 + rnd.randrange(0, 800, 100), 11800 + rnd.randrange(0, 600, 100)
    wdoors = [(w0, w0 + 1000), (mid["W"] + 500, mid["W"] + 1500)]
    edoors = [(e0, e0 + 1000), (mid["E"] + 700, mid["E"] + 1700)]
    segs += wall_with_doors(6500, 17000, wdoors, 7500, vertical=True)
    segs += wall_with_doors(6500, 17000, edoors, 9500, vertical=True)
    segs += [(0, mid["W"], 7500, mid["W"]), (9500, mid["E"], W, mid["E"])]
    furniture += _furnish(rnd, (0, 11000, 7500, mid["W"]), "E")
    furniture += _furnish(rnd, (0, mid["W"], 7500, 17000), "E")
    furniture += _furnish(rnd, (9500, 11000, W, mid["E"]), "W")
    furniture += _furnish(rnd, (9500, mid["E"], W, 17000), "W")
    # the hall's south wall: corridor B opens into it, and a door from the
    # north meeting room on each side
    hall_doors = [(3000, 4000), (7500, 9500), (12500, 13500)]
    segs += wall_with_doors(0, W, hall_doors, 17000, vertical=False)
    # two small offices in the hall's north-east corner, doors to the west
    segs += wall_with_doors(25000, H, [(26000, 27000), (29000, 30000)], 13000, True)
    segs += [(13000, 25000, W, 25000), (13000, 28200, W, 28200)]
    furniture += _furnish(rnd, (13000, 25000, W, 28200), "W")
    furniture += _furnish(rnd, (13000, 28200, W, H), "W")
    # pilasters (0.4 m x 0.3 m) on the hall's outer walls, three walls each
    for y in range(19000, H - 1000, 3500):
        segs += [(0, y, 300, y), (300, y, 300, y + 400), (300, y + 400, 0, y + 400)]
    for y in range(19000, 24000, 3500):
        segs += [(W, y, W - 300, y), (W - 300, y, W - 300, y + 400)]
        segs += [(W - 300, y + 400, W, y + 400)]
    for x in range(2500, 12000, 4000):
        segs += [(x, H, x, H - 300), (x, H - 300, x + 400, H - 300)]
        segs += [(x + 400, H - 300, x + 400, H)]
    # four 0.4 m columns, and shelving racks along the hall's west side
    for x, y in ((5000, 21500), (10500, 21500), (5000, 26500), (10500, 26500)):
        furniture.append((x - 200, y - 200, 400, 400))
    furniture += [(1500, 19000 + k * 3500, 600, 2500) for k in range(3)]
    # seeded crates (0.4-1.0 m sides) in the hall, 1.5 m from anything else
    tables = ((3500, 23500), (9000, 29000))
    taken = [(x - 1300, y - 1300, 2600, 2600) for x, y in tables]
    taken += [b for b in furniture if b[1] >= 17000]
    crates: list[tuple[int, int, int, int]] = []
    while len(crates) < 6:
        w, h = rnd.randrange(400, 1001, 100), rnd.randrange(400, 1001, 100)
        x, y = rnd.randrange(3000, 12000 - w, 50), rnd.randrange(18500, 29500 - h, 50)
        if all(
            x > bx + bw + 1500
            or bx > x + w + 1500
            or y > by + bh + 1500
            or by > y + h + 1500
            for bx, by, bw, bh in taken + crates
        ):
            crates.append((x, y, w, h))
    furniture += crates
    for b in furniture:
        segs += box(*b)
    # two round tables (0.5 m radius) in the hall, as DATA points
    points = []
    for cx, cy in tables:
        for k in range(16):
            a = 2 * math.pi * k / 16
            points.append(
                (cx + round(500 * math.cos(a)), cy + round(500 * math.sin(a)))
            )
    return segs, points


def building_map(seed: int = 17) -> str:
    """Return the text of ``building.map`` (`building`, MobileSim ``2D-Map``).

    ``seed`` 17 is the shipped building; another seed draws another.
    """
    segs, points = building(seed)
    xs = [v for s in segs for v in s[0::2]]
    ys = [v for s in segs for v in s[1::2]]
    lines = [
        "2D-Map-Ex2",
        "Sources: robotlib building",
        f"MinPos: {min(xs) - 500} {min(ys) - 500}",
        f"MaxPos: {max(xs) + 500} {max(ys) + 500}",
        f"NumPoints: {len(points)}",
        "PointsAreSorted: false",
        f"LineMinPos: {min(xs)} {min(ys)}",
        f"LineMaxPos: {max(xs)} {max(ys)}",
        f"NumLines: {len(segs)}",
        "LinesAreSorted: false",
        "Resolution: 100",
        'Cairn: RobotHome 1000 5500 0.000000 "" ICON "home"',
        'Cairn: Goal 8500 24000 0.000000 "" ICON "hall"',
        "LINES",
        *(" ".join(str(v) for v in s) for s in segs),
        "DATA",
        *(f"{x} {y}" for x, y in points),
    ]
    return "\n".join(lines) + "\n"


def large_map(seed: int = 0, spacing: int = 8) -> str:
    """Return the text of a large scanned-looking map (24 m x 52 m, ~60k points).

    A building like MobileSim's ``columbia.map``: a 2.4 m corridor down the
    middle with 4 m rooms on both sides (1 m doors), every wall drawn as DATA
    points ``spacing`` mm apart with 5 mm of seeded jitter, as a laser
    scanner leaves them, plus a few pillars and the outline as LINES.
    """
    rng = random.Random(seed)
    w, h, cx0, cx1 = 24000, 52000, 10800, 13200
    walls: list[Segment] = [(0, 0, w, 0), (w, 0, w, h), (w, h, 0, h), (0, h, 0, 0)]
    doors_w = [(y + 1500, y + 2500) for y in range(0, h, 4000)]
    doors_e = [(y + 2500, y + 3500) for y in range(0, h, 4000)]
    walls += wall_with_doors(0, h, doors_w, cx0, True)
    walls += wall_with_doors(0, h, doors_e, cx1, True)
    for y in range(4000, h, 4000):
        walls += [(0, y, cx0, y), (cx1, y, w, y)]
    points = []
    for x1, y1, x2, y2 in walls:
        n = max(1, round(math.hypot(x2 - x1, y2 - y1) / spacing))
        for k in range(n + 1):
            points.append(
                (
                    round(x1 + (x2 - x1) * k / n + rng.uniform(-5, 5)),
                    round(y1 + (y2 - y1) * k / n + rng.uniform(-5, 5)),
                )
            )
    pillars = [(x, y) for x in (cx0 - 600, cx1 + 600) for y in range(2000, h, 8000)]
    lines = list(walls[:4])
    for px, py in pillars:
        lines += box(px - 150, py - 150, 300, 300)
    out = [
        "2D-Map-Ex2",
        "Sources: robotlib large_map",
        "MinPos: -200 -200",
        f"MaxPos: {w + 200} {h + 200}",
        f"NumPoints: {len(points)}",
        f"NumLines: {len(lines)}",
        f'Cairn: RobotHome {(cx0 + cx1) // 2} 2000 90.000000 "" ICON "home"',
        "LINES",
        *(" ".join(str(v) for v in s) for s in lines),
        "DATA",
        *(f"{x} {y}" for x, y in points),
    ]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> None:
    """Write every world into this folder (or, with ``--large FILE``, `large_map`)."""
    import sys

    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--large"] and len(argv) == 2:
        Path(argv[1]).write_text(large_map(), encoding="ascii")
        return
    notes = {
        "corridor": "The paper's aliased corridor: 28 m x 2 m, doors on both sides.",
        "corridor_periodic": (
            "A 28 m x 2 m corridor whose doors repeat every 4 m from the west end."
        ),
        "corridor2": "A second aliased corridor with an L bend.",
        "maze": "An 8 x 6 maze of 1.5 m cells.",
        "arena": "An open 10 m x 10 m arena with six boxes.",
        "clutter": "Obstacle avoidance: a 10 m x 8 m arena with 10 seeded boxes.",
        "doorway": "Obstacle avoidance: two rooms joined by a 0.8 m door.",
        "utrap": "Obstacle avoidance: a hall with a U-shaped trap open to the west.",
        "alcoves": "Obstacle avoidance: a 16 m x 2 m corridor with alcoves.",
        "loop": "A 20 m x 15 m building: a loop of 2 m corridors around 8 rooms.",
    }
    makers = {
        "corridor": corridor,
        "corridor_periodic": corridor_periodic,
        "corridor2": corridor2,
        "maze": maze,
        "arena": arena,
        "clutter": clutter,
        "doorway": doorway,
        "utrap": utrap,
        "alcoves": alcoves,
        "loop": loop,
    }
    for name, make in makers.items():
        comment = f"{notes[name]}\nGenerated by worlds/make_worlds.py; units mm, deg."
        write_wld(make(), HERE / f"{name}.wld", comment=comment)
    for name in PAIRS:
        write_pairs(name)
    (HERE / "office.map").write_text(office_map(), encoding="ascii")
    (HERE / "building.map").write_text(building_map(), encoding="ascii")


if __name__ == "__main__":
    main()
