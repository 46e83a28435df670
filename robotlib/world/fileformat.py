"""What the world file formats share: the formats, `WorldFileError`, number parsing.

Saphira/SRISim ``.wld`` is read and written by `robotlib.world.wld`, MobileSim
``.map`` by `robotlib.world.mapfile`; both use the helpers here. Imports only
`robotlib.world.model` and `robotlib.world.geometry`.

Both formats store millimetres and degrees; a `World` holds metres and
radians. This module is the one place where that conversion happens.

``.wld`` (Saphira / SRISim world), ASCII, ``;`` starts a comment:

- ``width W`` and ``height H``: the world's size, mm.
- ``position x y th``: the robot's start pose, mm, mm, deg (``th`` may be
  left out and is then 0).
- ``floor W H``: both sizes at once, mm (EyeSim's world files, which are
  otherwise this format with ``#`` comment lines).
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

MobileSim objects: simulated, or only read
    robotlib builds its world from the walls and obstacles MobileSim puts
    in the simulation, and reads (but does not simulate) the rest:

    ============================  ==============================================
    ``LINES``, ``DATA``           simulated: walls, and points (small crosses)
    ``Cairn: Sim.BoxObstacle``    simulated: a static box of four walls
                                  (MobileSim's box can be pushed; robotlib's
                                  cannot)
    ``Cairn: RobotHome``          used: the start pose (else the first ``Dock``)
    ``Cairn: Dock``               used as the start only without a RobotHome;
                                  no docking or charging
    ``ForbiddenLine``,            read and ignored: navigation hints, not
    ``ForbiddenArea``,            obstacles (MobileSim does not simulate them
    ``Goal``, ``GoalWithHeading``  either)
    other ``Sim.*`` cairns        ignored (e.g. MobileSim's ``Sim.Robot``
                                  poses and custom simulated object types
                                  declared by ``MapInfo: ObjectType``)
    ``MapInfo``, ``Resolution``,  read and ignored (counts are advisory)
    ``NumPoints``, ``NumLines``
    ============================  ==============================================

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
Encoding
    UTF-8 (a byte-order mark is skipped), else Latin-1. A file that starts
    with a UTF-8 byte-order mark but is not UTF-8 further on raises
    `WorldFileError` at the line of the first bad byte, rather than reading
    its first line as garbage.
Size
    No number may exceed `MAX_EXTENT` (10 km) in magnitude, and no world may
    be wider or higher than that or reach further from the origin: a larger
    one raises `WorldFileError` (the line of the number, or the file).
Lookalike numbers
    A line whose first token starts with any digit (also non-ASCII ones) or
    a sign, including the Unicode minus and dashes, is read as a record and
    so refused with its line, rather than skipped as an unknown keyword.
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
from .model import World

__all__ = ["WorldFileError", "MAP_MAGICS", "MAX_EXTENT"]

MAX_EXTENT = 10_000.0
"""Largest world size, and largest distance of any coordinate from the origin, m."""
_MAX_NUMBER = Decimal(10_000_000)  # MAX_EXTENT in mm: the largest number a file holds
_SIGNS = "+-.\u2212\u2010\u2011\u2012\u2013\u2014\u2015\ufe63\uff0d\uff0b\u207a\u207b"

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


def _lines(text: str) -> list[str]:
    """Split text into lines at CRLF, CR or LF only.

    Not at the other characters `str.splitlines` breaks at, so that line
    numbers agree with an editor's.
    """
    if text.startswith("\ufeff"):
        text = text[1:]
    return _LINE_BREAK.split(text)


def _looks_numeric(token: str) -> bool:
    """Whether a line's first token is meant as a number (or a lookalike)."""
    c = token[0]
    return c in _SIGNS or c.isdigit() or c.isnumeric()


def _short(s: str, n: int = 60) -> str:
    s = s.strip()
    return repr(s if len(s) <= n else s[: n - 3] + "...")


def _numbers(
    tokens: list[str],
    source: str,
    lineno: int,
    what: str,
    line: str,
    limited: bool = True,
) -> list[Decimal]:
    """Parse plain finite decimal numbers (exactly), or raise a located error.

    ``limited``: refuse magnitudes beyond `MAX_EXTENT` (in mm) too.
    """
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
        if limited and abs(d) > _MAX_NUMBER:
            raise WorldFileError(
                source,
                lineno,
                f"expected {what}, got {tok!r}: beyond the {MAX_EXTENT / 1000:g} km"
                " a world may span",
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
    _check_extent(source, seg, pts, bounds)
    try:
        return World(
            segments=seg, bounds=bounds, start=start, points=pts, name=name, source=path
        )
    except ValueError as exc:  # degenerate contents World refuses
        raise WorldFileError(source, None, f"not a valid world: {exc}") from None


def _check_extent(source: str, seg: np.ndarray, pts: np.ndarray, bounds) -> None:
    """Refuse a world larger than `MAX_EXTENT` or reaching further from the origin."""
    xy = np.concatenate([seg[:, :2], seg[:, 2:], pts])
    if bounds is not None:
        xy = np.concatenate([xy, [bounds[:2], bounds[2:]]])
    if not len(xy):
        return
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    if np.any(hi - lo > MAX_EXTENT) or np.any(np.abs(xy) > MAX_EXTENT):
        raise WorldFileError(
            source,
            None,
            f"world spans x {lo[0]:g}..{hi[0]:g} m, y {lo[1]:g}..{hi[1]:g} m: larger"
            f" than the {MAX_EXTENT / 1000:g} km limit (size and distance from the"
            " origin)",
        )


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
        data = _decode(data, name)
    return data, name, path


def _decode(data: bytes, source: str) -> str:
    """Bytes as text: UTF-8 (BOM skipped), else Latin-1; a BOM then bad bytes: error."""
    bom = data.startswith(b"\xef\xbb\xbf")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if bom:
            line = data[: exc.start].count(b"\n") + 1
            raise WorldFileError(
                source,
                line,
                f"the file starts with a UTF-8 byte-order mark but byte "
                f"{data[exc.start]:#04x} at offset {exc.start} is not UTF-8",
            ) from None
        return data.decode("latin-1")
