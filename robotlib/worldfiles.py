"""Read and write world files: Saphira/SRISim ``.wld`` and MobileSim ``.map``.

Both formats store millimetres and degrees; a `World` holds metres and
radians. This module is the one place where that conversion happens.

``.wld`` (Saphira / SRISim world), ASCII, ``;`` starts a comment:

- ``width W`` and ``height H``: the world's size, mm.
- ``position x y th``: the robot's start pose, mm, mm, deg (``th`` may be
  left out and is then 0).
- ``origin x y``: the lower-left corner of the world, mm. This keyword is a
  robotlib extension (other readers ignore unknown lines); it defaults to
  ``0 0``, the Saphira convention that a world spans ``[0, W] x [0, H]``.
- a line that starts with a number is a wall segment ``x1 y1 x2 y2``, mm.
- any other line (an unknown keyword) is ignored.

``.map`` (ARIA / MobileSim ``2D-Map``, ``2D-Map-Ex``, ``2D-Map-Ex2``): the
magic first line, then ``Key: values`` header lines, then sections: ``LINES``
(one ``x1 y1 x2 y2`` per line) and ``DATA`` (one ``x y`` per line). Of the
header, ``MinPos``/``MaxPos`` and ``LineMinPos``/``LineMaxPos`` give the
bounds, the first ``Cairn: RobotHome`` (else the first ``Cairn: Dock``) the
start pose, and every ``Cairn: Sim.BoxObstacle x y th "desc" ICON "label" x1
y1 x2 y2`` a rectangle, four walls (the rectangle ``x1..x2, y1..y2`` rotated by
``th`` about the map origin, as MobileSim places it). Counts (``NumLines``,
``NumPoints``), ``Resolution`` and every other key, cairn type and section are
ignored.

Decisions
---------
Strictness
    Tolerant of what a file may legitimately contain (unknown keywords, keys,
    cairn types and sections, CRLF or CR line ends, no final newline, trailing
    blanks, comments, advisory counts that disagree); strict about the records
    it reads. A known record with a wrong number of values, a value that is
    not a plain decimal number (``nan``, ``inf``, ``1_000`` and non-ASCII
    digits are refused), a non-positive size or an inverted box raises
    `WorldFileError` naming the file, the line and what was expected. In a
    ``.wld`` a line whose first token starts like a number (a digit, a sign or
    a point) is a wall segment and must be exactly four numbers; in a ``.map``
    every line of a ``LINES`` or ``DATA`` section must be four or two numbers.
    Segment coordinates may be fractional (the writers emit them when a
    coordinate is not a whole millimetre).
Bounds
    The declared rectangle (``.wld``: ``origin`` and ``width``/``height``;
    ``.map``: the union of ``MinPos``/``MaxPos`` and
    ``LineMinPos``/``LineMaxPos``, an inverted pair being ignored as "no
    data"), grown where needed to contain every wall, point and the start
    position, so nothing of the file lies outside its world. A ``.wld`` that
    gives only one of ``width`` and ``height`` takes the other extent from
    its contents. Without any declared rectangle, `World`'s default applies
    (the contents' bounding box grown by 0.5 m).
Empty files
    A file with nothing to build a world from (a ``.wld`` with no wall, size
    or position; a ``.map`` with no line, point, position box or cairn) raises
    `WorldFileError`: it is almost certainly the wrong file. A world with
    walls but no start, or a size but no walls, is fine.
Start heading
    Degrees in the file, wrapped to (-pi, pi] in the `World`.

Writers write whole millimetres as integers and other values as the shortest
decimal that reads back to the same float, so ``read(write(world)) == world``
for any world whose walls, points and start lie within its bounds.
"""

from __future__ import annotations

import math
import os
import re
from decimal import Context, Decimal
from pathlib import Path
from typing import IO

import numpy as np

from .geometry import wrap_angle
from .world import World

__all__ = [
    "WorldFileError",
    "parse_wld",
    "parse_map",
    "read_wld",
    "read_map",
    "read_world",
    "write_wld",
    "write_map",
    "format_wld",
    "format_map",
]

MAP_MAGICS = ("2D-Map", "2D-Map-Ex", "2D-Map-Ex2")
"""First lines that mark an ARIA map file."""

_WALL = "4 numbers x1 y1 x2 y2 (mm) for a wall"
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_CAIRN_TOKEN = re.compile(r'"[^"]*"|\S+')
_SECTION = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_KEY = re.compile(r"\s*([A-Za-z][A-Za-z0-9_.]*):(.*)")


class WorldFileError(ValueError):
    """A world file that cannot be read.

    Parameters
    ----------
    path : str
        The file's name (or ``"<string>"`` for parsed text).
    line : int or None
        1-based line number of the offending line, or None for the file as a
        whole.
    message : str
        What was expected, and what was found.

    Attributes
    ----------
    path : str
    line : int or None
    reason : str
        ``message`` without the location.
    """

    def __init__(self, path: str, line: int | None, message: str):
        self.path = str(path)
        self.line = line
        self.reason = message
        where = self.path if line is None else f"{self.path}:{line}"
        super().__init__(f"{where}: {message}")

    def __reduce__(self):
        return (type(self), (self.path, self.line, self.reason))


# --------------------------------------------------------------------------
# helpers


def _lines(text: str) -> list[str]:
    """Split text into lines at CRLF, CR or LF only.

    Not at the other characters `str.splitlines` breaks at, so that line
    numbers agree with an editor's.
    """
    if text.startswith("\ufeff"):
        text = text[1:]
    return _LINE_BREAK.split(text)


def _short(s: str, n: int = 60) -> str:
    s = s.strip()
    return repr(s if len(s) <= n else s[: n - 3] + "...")


def _numbers(
    tokens: list[str], source: str, lineno: int, what: str, line: str
) -> list[Decimal]:
    """Parse plain finite decimal numbers (exactly), or raise a located error."""
    out = []
    for tok in tokens:
        if not _NUMBER.fullmatch(tok):
            raise WorldFileError(source, lineno, f"expected {what}, got {_short(line)}")
        try:
            d = _CTX.create_decimal(tok)
        except ArithmeticError:  # an exponent beyond even Decimal's range
            d = Decimal("nan")
        if not (d.is_finite() and math.isfinite(float(d))):
            raise WorldFileError(
                source, lineno, f"expected {what}, got {tok!r} (out of range)"
            )
        out.append(d)
    return out


# Exact decimal arithmetic for the unit conversions, so that a written value
# reads back to the very same float.
_CTX = Context(prec=80, Emax=10**6, Emin=-(10**6), traps=[])
_PI = Decimal(
    "3.14159265358979323846264338327950288419716939937510582097494459230781640628"
)


def _mm(v: Decimal) -> float:
    """Millimetres (exact decimal) to metres, correctly rounded."""
    return float(v.scaleb(-3, _CTX))


def _deg(v: Decimal) -> float:
    """Degrees (exact decimal) to radians, wrapped to (-pi, pi]."""
    return float(wrap_angle(float(_CTX.divide(_CTX.multiply(v, _PI), 180))))


def _text(d: Decimal) -> str:
    """Decimal as file text: an integer when whole, else plain decimal notation."""
    if d == d.to_integral_value(context=_CTX) and abs(d) < 10**18:
        return str(int(d))
    return str(d.normalize(_CTX))


def _mm_decimal(m: float) -> Decimal:
    """Return the shortest decimal of the metres ``m`` in millimetres (exact)."""
    return Decimal(repr(float(m))).scaleb(3, _CTX)


def _fmt_mm(m: float) -> str:
    """Metres as millimetre text that reads back to exactly ``m``."""
    return _text(_mm_decimal(m))


def _fmt_deg(theta: float) -> str:
    """Radians as degree text that reads back (via `_deg`) to exactly ``theta``."""
    theta = float(theta)
    if theta == 0.0:
        return "0"
    deg = _CTX.divide(_CTX.multiply(Decimal(theta), 180), _PI)
    for digits in range(1, 40):
        d = Context(prec=digits).plus(deg)
        if _deg(d) == theta:
            return _text(d)
    return _text(deg)


def _make_world(
    source: str,
    segments: list,
    points: list,
    declared: tuple[float, float, float, float] | None,
    start: tuple[float, float, float] | None,
    name: str,
    path: Path | None,
) -> World:
    """Build the World in metres, growing ``declared`` bounds over the contents."""
    seg = np.asarray(segments, dtype=float).reshape(-1, 4)
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    bounds = None
    if declared is not None:
        xmin, ymin, xmax, ymax = declared
        xy = np.concatenate([seg[:, :2], seg[:, 2:], pts])
        if start is not None:
            xy = np.concatenate([xy, [start[:2]]])
        if len(xy):
            lo, hi = xy.min(axis=0), xy.max(axis=0)
            xmin, ymin = min(xmin, lo[0]), min(ymin, lo[1])
            xmax, ymax = max(xmax, hi[0]), max(ymax, hi[1])
        bounds = (float(xmin), float(ymin), float(xmax), float(ymax))
        if not all(math.isfinite(b) for b in bounds):
            raise WorldFileError(source, None, f"bounds out of range: {bounds}")
    try:
        return World(
            segments=seg, bounds=bounds, start=start, points=pts, name=name, source=path
        )
    except ValueError as exc:  # degenerate contents World refuses
        raise WorldFileError(source, None, f"not a valid world: {exc}") from None


def _read_text(path_or_file: str | os.PathLike | IO) -> tuple[str, str, Path | None]:
    """Return ``(text, source name, path)`` of a file path or an open file."""
    if hasattr(path_or_file, "read"):
        data = path_or_file.read()
        name = str(getattr(path_or_file, "name", "<file>"))
        path = None
    else:
        path = Path(path_or_file)
        name = str(path)
        data = path.read_bytes()
    if isinstance(data, bytes):
        try:
            data = data.decode("utf-8")
        except UnicodeDecodeError:
            data = data.decode("latin-1")
    return data, name, path


# --------------------------------------------------------------------------
# .wld


def parse_wld(
    text: str, source: str = "<string>", name: str = "", path: Path | None = None
) -> World:
    """Parse the text of a Saphira/SRISim ``.wld`` world.

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
        Walls, bounds and start in metres and radians; no points.

    Raises
    ------
    WorldFileError
        On a malformed record or an empty file (see the module docstring).
    """
    segments: list[list[float]] = []
    width = height = None
    origin = (Decimal(0), Decimal(0))
    start = None
    for lineno, raw in enumerate(_lines(text), start=1):
        line = raw.split(";", 1)[0]
        tokens = line.split()
        if not tokens:
            continue
        first = tokens[0]
        if first[0] in "0123456789+-.":
            if len(tokens) != 4:
                raise WorldFileError(
                    source,
                    lineno,
                    f"expected {_WALL}, got {_short(line)}",
                )
            segments.append(
                [_mm(v) for v in _numbers(tokens, source, lineno, _WALL, line)]
            )
            continue
        key = first.lower()
        args = tokens[1:]
        if key in ("width", "height"):
            what = f"'{key} <mm>' with one positive number"
            if len(args) != 1:
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            (v,) = _numbers(args, source, lineno, what, line)
            if not v > 0:
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            if key == "width":
                width = v
            else:
                height = v
        elif key == "position":
            what = "'position x y th' (mm, mm, deg)"
            if len(args) not in (2, 3):
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            v = _numbers(args, source, lineno, what, line)
            start = (_mm(v[0]), _mm(v[1]), _deg(v[2]) if len(v) == 3 else 0.0)
        elif key == "origin":
            what = "'origin x y' (mm)"
            if len(args) != 2:
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            origin = tuple(_numbers(args, source, lineno, what, line))
        # any other keyword: ignored
    if not segments and width is None and height is None and start is None:
        raise WorldFileError(
            source, None, "no walls, width, height or position: not a world file"
        )
    declared = None
    if width is not None or height is not None:
        seg = np.asarray(segments, dtype=float).reshape(-1, 4)
        xy = np.concatenate([seg[:, :2], seg[:, 2:]])
        if start is not None:
            xy = np.concatenate([xy, [start[:2]]])
        if len(xy) == 0:
            xy = np.zeros((1, 2))
        lo, hi = xy.min(axis=0) - 0.5, xy.max(axis=0) + 0.5
        ox, oy = _mm(origin[0]), _mm(origin[1])
        if width is not None:
            xr = (ox, _mm(_CTX.add(origin[0], width)))
        else:
            xr = (float(lo[0]), float(hi[0]))
        if height is not None:
            yr = (oy, _mm(_CTX.add(origin[1], height)))
        else:
            yr = (float(lo[1]), float(hi[1]))
        if not (xr[0] < xr[1] and yr[0] < yr[1]):
            raise WorldFileError(source, None, "width or height too small to matter")
        declared = (xr[0], yr[0], xr[1], yr[1])
    return _make_world(source, segments, [], declared, start, name, path)


def format_wld(world: World, comment: str | None = None) -> str:
    """Return the ``.wld`` text of a world (see `write_wld`)."""
    if len(world.points):
        raise ValueError(
            "the .wld format has no point obstacles; write this world with write_map"
        )
    xmin, ymin, xmax, ymax = world.bounds
    lines = []
    if comment:
        lines += [f"; {c}".rstrip() for c in comment.splitlines()]
    # width/height are the exact differences of the mm corners, so that the
    # reader's origin + width reproduces xmax exactly.
    lo = [_mm_decimal(xmin), _mm_decimal(ymin)]
    w = _text(_CTX.subtract(_mm_decimal(xmax), lo[0]))
    h = _text(_CTX.subtract(_mm_decimal(ymax), lo[1]))
    lines += [f"width {w}", f"height {h}"]
    if lo[0] != 0 or lo[1] != 0:
        lines.append(f"origin {_text(lo[0])} {_text(lo[1])}")
    x, y, th = world.start
    lines.append(f"position {_fmt_mm(x)} {_fmt_mm(y)} {_fmt_deg(th)}")
    lines.append("; walls: x1 y1 x2 y2 (mm)")
    for s in world.segments:
        lines.append(" ".join(_fmt_mm(v) for v in s))
    return "\n".join(lines) + "\n"


def write_wld(
    world: World, path: str | os.PathLike, comment: str | None = None
) -> None:
    """Write a world as a ``.wld`` file.

    Parameters
    ----------
    world : World
        A world without point obstacles.
    path : str or path-like
        Destination file.
    comment : str, optional
        Text written at the top as ``;`` comment lines.

    Raises
    ------
    ValueError
        If the world has point obstacles (the format cannot hold them).
    """
    Path(path).write_text(format_wld(world, comment), encoding="ascii")


def read_wld(path_or_file: str | os.PathLike | IO) -> World:
    """Read a ``.wld`` file (a path or an open file) into a `World`."""
    text, source, path = _read_text(path_or_file)
    name = path.stem if path is not None else ""
    return parse_wld(text, source=source, name=name, path=path)


# --------------------------------------------------------------------------
# .map


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
    for lineno in range(first + 2, len(lines) + 1):
        line = lines[lineno - 1]
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
                boxes[key] = tuple(_numbers(vals, source, lineno, what, line))
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
        elif section is None and head[0] in "0123456789+-.":
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


def read_world(path: str | os.PathLike) -> World:
    """Read a world file, choosing the format by extension (``.wld``, ``.map``).

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    WorldFileError
        If the extension is unknown or the file is malformed.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".wld":
        return read_wld(path)
    if ext == ".map":
        return read_map(path)
    raise WorldFileError(
        str(path), None, f"unknown world file extension {ext!r}: expected .wld or .map"
    )
