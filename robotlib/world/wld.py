"""Saphira/SRISim ``.wld`` world files: parse, format, read, write.

The format and the reader's decisions are described in
`robotlib.world.fileformat`. Imports only the world's own modules.
"""

from __future__ import annotations

import os
from decimal import Decimal
from pathlib import Path
from typing import IO

import numpy as np

from .fileformat import (
    _CTX,
    _WALL,
    WorldFileError,
    _deg,
    _fmt_deg,
    _fmt_mm,
    _lines,
    _looks_numeric,
    _make_world,
    _mm,
    _mm_decimal,
    _numbers,
    _read_text,
    _short,
    _text,
)
from .model import World

__all__ = ["parse_wld", "format_wld", "read_wld", "write_wld"]


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
        if _looks_numeric(first):
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
        elif key == "floor":  # EyeSim: floor W H
            what = "'floor <width mm> <height mm>' with two positive numbers"
            if len(args) != 2:
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            w, h = _numbers(args, source, lineno, what, line)
            if not (w > 0 and h > 0):
                raise WorldFileError(
                    source, lineno, f"expected {what}, got {_short(line)}"
                )
            width, height = w, h
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
            source, None, "no walls, width, height, floor or position: not a world file"
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
