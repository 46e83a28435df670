"""MobileSim / ARIA ``.map`` world files: parse, format, read, write.

The format and the reader's decisions are described in
`robotlib.world.fileformat`. Imports only the world's own modules.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import IO

import numpy as np

from .fileformat import (
    _CAIRN_TOKEN,
    _KEY,
    _SECTION,
    MAP_MAGICS,
    WorldFileError,
    _deg,
    _fmt_deg,
    _fmt_mm,
    _lines,
    _looks_numeric,
    _make_world,
    _mm,
    _numbers,
    _read_text,
    _short,
)
from .model import World

__all__ = ["parse_map", "format_map", "read_map", "write_map"]

# A run of DATA or LINES records of plain integers (mm) within the size limit
# is read in one go, without `decimal`: an integer below 2**53 divided by 1000
# is correctly rounded, as `_mm` rounds, and "-0" stays -0.0. Any other line
# ends the run and takes the full path.
_INT = r"[ \t]*[+-]?[0-9]{1,7}"
_INT_RUNS = {
    n: re.compile(r"(?:" + r"[ \t]".join([_INT] * n) + r"[ \t]*\n)*") for n in (2, 4)
}


def _int_run(lines: list[str], first: int, n: int) -> tuple[list[list[float]], int]:
    """Read the records of ``n`` plain integers from ``lines[first]`` on.

    Returns their numbers in m (one list per line) and how many lines they
    take (0 when ``lines[first]`` is another line). Looks ahead in windows
    that double while they fill, so the work stays in proportion to the
    lines read, however the records are interleaved with others.
    """
    rows: list[list[float]] = []
    window = 16
    while True:
        part = lines[first + len(rows) : first + len(rows) + window]
        run = _INT_RUNS[n].match("\n".join(part) + "\n").group()
        count = run.count("\n")
        if count:
            values = np.fromstring(run, dtype=np.float64, sep=" ") / 1000.0
            rows.extend(values.reshape(count, n).tolist())
        if count < window:
            return rows, len(rows)
        window *= 2


def parse_map(
    text: str, source: str = "<string>", name: str = "", path: Path | None = None
) -> World:
    """Parse the text of an ARIA/MobileSim ``.map`` file.

    Parameters
    ----------
    text : str
        The file's contents.
    source : str
        Name used in error messages.
    name : str
        The world's short name.
    path : pathlib.Path, optional
        Recorded as `World.source`.

    Returns
    -------
    World
        Walls (``LINES`` and box obstacles), points (``DATA``), bounds and
        start in metres and radians.

    Raises
    ------
    WorldFileError
        On a missing ``2D-Map`` first line, a malformed record or an empty
        map (see the module docstring).
    """
    lines = _lines(text)
    first = 0
    while first < len(lines) and not lines[first].strip():
        first += 1
    if first == len(lines) or lines[first].strip() not in MAP_MAGICS:
        got = _short(lines[first]) if first < len(lines) else "an empty file"
        raise WorldFileError(
            source,
            first + 1 if first < len(lines) else None,
            f"expected a first line '2D-Map', '2D-Map-Ex' or '2D-Map-Ex2', got {got}",
        )
    segments: list[list[float]] = []
    points: list[list[float]] = []
    boxes: dict[str, tuple[float, float]] = {}
    home = dock = None
    section = None
    resume = 0
    for lineno in range(first + 2, len(lines) + 1):
        if lineno < resume:  # read in a run of plain records
            continue
        line = lines[lineno - 1]
        if section == "DATA" or section == "LINES":  # the bulk of a map: sooner
            rows, count = _int_run(lines, lineno - 1, 2 if section == "DATA" else 4)
            if count:
                (points if section == "DATA" else segments).extend(rows)
                resume = lineno + count
                continue
        tokens = line.split()
        if not tokens:
            continue
        head = tokens[0]
        keyed = _KEY.match(line)
        if keyed:
            key, args = keyed.groups()
            if key in ("MinPos", "MaxPos", "LineMinPos", "LineMaxPos"):
                what = f"'{key}: x y' (mm)"
                vals = args.split()
                if len(vals) != 2:
                    raise WorldFileError(
                        source, lineno, f"expected {what}, got {_short(line)}"
                    )
                # not limited: ARIA writes an inverted +-2^31 pair for "no data"
                boxes[key] = tuple(_numbers(vals, source, lineno, what, line, False))
            elif key == "Cairn":
                cairn = _parse_cairn(args, source, lineno, line)
                if cairn is None:
                    continue
                kind, pose, rect = cairn
                if kind == "RobotHome" and home is None:
                    home = pose
                elif kind == "Dock" and dock is None:
                    dock = pose
                elif kind == "Sim.BoxObstacle":
                    segments.extend(_box_walls(pose[2], rect))
            continue  # any other key: ignored
        if len(tokens) == 1 and _SECTION.fullmatch(head):
            section = head
            continue
        if section == "LINES":
            what = "4 numbers x1 y1 x2 y2 (mm) in LINES"
            if len(tokens) != 4:
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            segments.append(
                [_mm(v) for v in _numbers(tokens, source, lineno, what, line)]
            )
        elif section == "DATA":
            what = "2 numbers x y (mm) in DATA"
            if len(tokens) != 2:
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            points.append(
                [_mm(v) for v in _numbers(tokens, source, lineno, what, line)]
            )
        elif section is None and _looks_numeric(head):
            raise WorldFileError(
                source,
                lineno,
                f"expected 'Key: values' or a section name (LINES, DATA) "
                f"before data, got {_short(line)}",
            )
        # lines of unknown sections, and other header lines: ignored
    start = home if home is not None else dock
    declared = None
    for lo_key, hi_key in (("MinPos", "MaxPos"), ("LineMinPos", "LineMaxPos")):
        if lo_key in boxes and hi_key in boxes:
            (x0, y0), (x1, y1) = boxes[lo_key], boxes[hi_key]
            if x0 <= x1 and y0 <= y1:  # inverted: ARIA's "no data" marker
                box = (_mm(x0), _mm(y0), _mm(x1), _mm(y1))
                if declared is None:
                    declared = box
                else:
                    declared = (
                        min(declared[0], box[0]),
                        min(declared[1], box[1]),
                        max(declared[2], box[2]),
                        max(declared[3], box[3]),
                    )
    if not segments and not points and declared is None and start is None:
        raise WorldFileError(
            source, None, "no lines, points, bounds or robot home: an empty map"
        )
    if declared is not None:
        # a box that is a point or a line (one wall, one DATA point) gets the
        # default margin rather than no area at all
        seg = np.asarray(segments, dtype=float).reshape(-1, 4)
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        xy = np.concatenate(
            [seg[:, :2], seg[:, 2:], pts, [declared[:2]], [declared[2:]]]
        )
        if start is not None:
            xy = np.concatenate([xy, [start[:2]]])
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        if not (lo[0] < hi[0] and lo[1] < hi[1]):
            declared = None
    return _make_world(source, segments, points, declared, start, name, path)


def _parse_cairn(args: str, source: str, lineno: int, line: str):
    """Return ``(type, pose, rect)`` of a cairn we use, or None for other types.

    ``pose`` is ``(x, y, theta)`` in m and rad; ``rect`` ``(x1, y1, x2, y2)``
    in mm (for box obstacles) or None.
    """
    tokens = _CAIRN_TOKEN.findall(args)
    if not tokens or tokens[0] not in ("RobotHome", "Dock", "Sim.BoxObstacle"):
        return None
    kind = tokens[0]
    if kind == "Sim.BoxObstacle":
        what = (
            'Cairn: Sim.BoxObstacle x y th "desc" ICON "label" x1 y1 x2 y2 '
            "(mm, mm, deg, then the box in mm)"
        )
        if len(tokens) < 11:
            raise WorldFileError(source, lineno, f"expected {what}, got {_short(line)}")
        rect = tuple(_numbers(tokens[7:11], source, lineno, what, line))
    else:
        what = f'Cairn: {kind} x y th "desc" ICON "label" (mm, mm, deg)'
        rect = None
    if len(tokens) < 4:
        raise WorldFileError(source, lineno, f"expected {what}, got {_short(line)}")
    x, y, th = _numbers(tokens[1:4], source, lineno, what, line)
    return kind, (_mm(x), _mm(y), _deg(th)), rect


def _box_walls(theta: float, rect) -> list[list[float]]:
    """Four walls (m) of the box ``rect`` (mm) rotated by ``theta`` about (0, 0)."""
    x1, y1, x2, y2 = (_mm(v) for v in rect)
    corners = [(x1, y1), (x2, y1), (x2, y2), (x1, y2)]
    if theta != 0.0:
        c, s = math.cos(theta), math.sin(theta)
        corners = [(c * x - s * y, s * x + c * y) for x, y in corners]
    return [[*corners[k], *corners[(k + 1) % 4]] for k in range(4)]


def format_map(world: World) -> str:
    """Return the ``2D-Map`` text of a world (see `write_map`)."""
    xmin, ymin, xmax, ymax = world.bounds
    seg, pts = world.segments, world.points
    out = [
        "2D-Map",
        f"MinPos: {_fmt_mm(xmin)} {_fmt_mm(ymin)}",
        f"MaxPos: {_fmt_mm(xmax)} {_fmt_mm(ymax)}",
        f"NumPoints: {len(pts)}",
    ]
    if len(seg):
        lo = np.minimum(seg[:, :2], seg[:, 2:]).min(axis=0)
        hi = np.maximum(seg[:, :2], seg[:, 2:]).max(axis=0)
        out += [
            f"LineMinPos: {_fmt_mm(lo[0])} {_fmt_mm(lo[1])}",
            f"LineMaxPos: {_fmt_mm(hi[0])} {_fmt_mm(hi[1])}",
        ]
    out.append(f"NumLines: {len(seg)}")
    x, y, th = world.start
    out.append(
        f'Cairn: RobotHome {_fmt_mm(x)} {_fmt_mm(y)} {_fmt_deg(th)} "" ICON "start"'
    )
    out.append("LINES")
    out += [" ".join(_fmt_mm(v) for v in s) for s in seg]
    out.append("DATA")
    out += [f"{_fmt_mm(p[0])} {_fmt_mm(p[1])}" for p in pts]
    return "\n".join(out) + "\n"


def write_map(world: World, path: str | os.PathLike) -> None:
    """Write a world as a MobileSim ``2D-Map`` file.

    Walls go to ``LINES``, points to ``DATA``, the bounds to
    ``MinPos``/``MaxPos`` and the start pose to a ``Cairn: RobotHome``.

    Parameters
    ----------
    world : World
    path : str or path-like
        Destination file.
    """
    Path(path).write_text(format_map(world), encoding="ascii")


def read_map(path_or_file: str | os.PathLike | IO) -> World:
    """Read a ``.map`` file (a path or an open file) into a `World`."""
    text, source, path = _read_text(path_or_file)
    name = path.stem if path is not None else ""
    return parse_map(text, source=source, name=name, path=path)
