"""Answers not shipped: find student code that reaches the library's own answers.

Each exercise lists (``writes``) the dotted library functions whose work it
asks for. Two defences, both keyed on those lists:

- `scan.scan_code`, static, in the grader: every route in the student's
  cells to a name `aliases` gives a listed function (see there);
- `tripwires.arm`, at run time, in the sandboxed student process: every
  listed object, under every name a loaded module or class gives it, is
  replaced by a tripwire (see there), using what this module finds.

Imports nothing of robotlib's at module level (`aliases` imports the library
to resolve names).
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
from collections.abc import Iterable

__all__ = ["aliases", "equivalents", "resolve"]


def resolve(dotted: str):
    """Import the object a dotted name names (``pkg.mod.Class.attr``)."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(f"cannot import {dotted}")


def _import_all(root: str = "robotlib") -> None:
    pkg = importlib.import_module(root)
    for info in pkgutil.walk_packages(pkg.__path__, root + "."):
        if info.name.split(".")[-1] in ("__main__", "cli") or ".course" in info.name:
            continue
        try:
            importlib.import_module(info.name)
        except Exception:  # noqa: BLE001 - an optional dependency missing
            continue


def _raw(obj):
    return getattr(obj, "__func__", obj)


class _Targets:
    """The listed objects, by identity: ``get(obj)`` is the name listing it, or None.

    Holds the objects themselves: once a tripwire replaces a function in its
    module, nothing else may keep it alive, and an object made later could
    be given its id (a call of ``astar`` reported as ``pure_pursuit``).
    """

    def __init__(self):
        self.by_id: dict[int, tuple[str, object]] = {}
        self.values: set[str] = set()  # listed names of objects not called

    def add(self, obj, name: str) -> None:
        self.by_id.setdefault(id(_raw(obj)), (name, _raw(obj)))
        if not callable(obj):
            self.values.add(name)

    def get(self, obj) -> str | None:
        hit = self.by_id.get(id(_raw(obj)))
        return hit[0] if hit is not None and hit[1] is _raw(obj) else None


def _places(targets: _Targets, roots=("robotlib",)):
    """Yield ``(container, attr, listed, dotted)`` for each place a target sits."""
    for name, mod in list(sys.modules.items()):
        if mod is None or not name.startswith(roots):
            continue
        for attr, val in list(vars(mod).items()):
            if (listed := targets.get(val)) is not None:
                yield mod, attr, listed, f"{name}.{attr}"
            elif isinstance(val, type) and val.__module__.startswith(roots):
                for k, v in list(vars(val).items()):
                    if (listed := targets.get(v)) is not None:
                        yield val, k, listed, f"{name}.{attr}.{k}"


def _targets(writes: Iterable[str]) -> _Targets:
    """Map each listed object to the first name listing it (in order)."""
    out = _Targets()
    for w in writes:
        try:
            out.add(resolve(w), w)
        except (ImportError, AttributeError):
            continue
    return out


def equivalents(writes: Iterable[str]) -> dict[str, list[str]]:
    """Map each listed name to every listed name of the same object, in order.

    Two exercises may list one function under two of its names (Lab 5 lists
    ``robotlib.mapping.inverse_sonar_model`` and
    ``robotlib.mapping.occupancy.inverse_sonar_model``); a note about an
    exercise names the one that exercise lists.
    """
    by_id: dict[int, list[str]] = {}
    names = list(dict.fromkeys(writes))
    for w in names:
        try:
            by_id.setdefault(id(_raw(resolve(w))), []).append(w)
        except (ImportError, AttributeError):
            by_id.setdefault(id(w), []).append(w)
    return {w: group for group in by_id.values() for w in group}


def aliases(writes: Iterable[str]) -> dict[str, str]:
    """Map every dotted path naming a listed function to the listed name.

    Imports the whole library first so that re-exports are found.

    Raises
    ------
    ImportError
        If a listed name does not exist (a lab's metadata is wrong).
    """
    writes = list(dict.fromkeys(writes))
    for w in writes:
        resolve(w)
    _import_all()
    out = {}
    for _, _, listed, dotted in _places(_targets(writes)):
        out[dotted] = listed
    out.update({w: w for w in writes})  # a listed name names itself
    return out
