"""The shipped worlds, any world file, and generated worlds by name.

`load_world`, `world_names`, `read_world`; `seeded_world` also names a world
`generate_world` draws (``"gen-office"``). Imports the world's file readers,
generator and model; nothing above the world layer.
"""

from __future__ import annotations

import os
import zlib
from pathlib import Path

from .._shipped import shipped_dir
from .fileformat import WorldFileError
from .generate import generate_world
from .mapfile import read_map
from .model import World
from .wld import read_wld

__all__ = ["WORLDS_DIR", "load_world", "read_world", "seeded_world", "world_names"]


WORLDS_DIR = shipped_dir("worlds")
"""The folder of the shipped worlds (short names are looked up here): the
repository's ``worlds/``, or ``share/robotlib/worlds`` of an install."""


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


def world_names() -> list[str]:
    """Short names of the worlds shipped in `WORLDS_DIR`."""
    names = {p.stem for p in WORLDS_DIR.glob("*.wld")}
    names |= {p.stem for p in WORLDS_DIR.glob("*.map")}
    return sorted(names)


def load_world(name_or_path: str | Path) -> World:
    """Load a world by short name (``"corridor"``) or from a file path.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A name from `world_names`, or a path to a ``.wld`` or ``.map`` file.

    Returns
    -------
    World

    Raises
    ------
    FileNotFoundError
        If neither a shipped world nor a file of that name exists.
    robotlib.world.WorldFileError
        If the file is malformed.
    """
    path = Path(name_or_path)
    if not path.exists() and path.suffix == "" and path.parent == Path("."):
        for ext in (".wld", ".map"):
            if (WORLDS_DIR / f"{path.name}{ext}").exists():
                path = WORLDS_DIR / f"{path.name}{ext}"
                break
        else:
            raise FileNotFoundError(
                f"no world named {str(name_or_path)!r}; "
                f"shipped worlds: {', '.join(world_names())}"
            )
    return read_world(path)


def seeded_world(name: str, seed: int) -> World:
    """Return a bench's world for one seed: shipped, a file, or ``gen-KIND``.

    ``"gen-KIND"`` draws a fresh world of that kind (`generate_world`) from
    ``[seed, crc32(KIND)]``, so each seed of a bench runs on its own map and
    two kinds never share a stream; any other name goes to `load_world`
    (the same map for every seed).

    Parameters
    ----------
    name : str
        A shipped world's name, a file path, or ``"gen-"`` and one of
        `robotlib.world.KINDS`.
    seed : int
        The run's seed.

    Returns
    -------
    World
    """
    if name.startswith("gen-"):
        kind = name[4:]
        return generate_world(kind, [seed, zlib.crc32(kind.encode())])
    return load_world(name)
