"""Run-time tripwires: the library's own answers replaced where students reach them.

`arm` runs in the sandboxed student process: every object an exercise lists
(``writes``), under every name a loaded module or class gives it, is
replaced by a tripwire that reports (on the grader's channel) and raises
`Tripwire`, so routes the static pass (`scan.scan_code`) cannot see
(strings built at run time, library calls that do the work indirectly) are
caught when they run. A listed function becomes a function that trips when
called; a listed value (Lab 2's ``BRAITENBERG`` table of weight matrices)
becomes a `TripValue` that trips when read in any way (indexed, iterated,
an attribute, converted to an array, called), so ``Braitenberg('fear').
weights`` is reported rather than failing with a library error. Modules
imported or reloaded later are re-armed by an import hook. Imports
`answers`.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable

from .answers import _places, _Targets, _targets, resolve

__all__ = ["Tripwire", "TripValue", "arm"]


class Tripwire(RuntimeError):
    """Raised when graded code calls a library function an exercise asks for."""


class TripValue:
    """A listed value's stand-in: any read of it reports and raises `Tripwire`."""

    __slots__ = ("_listed", "_report", "_via")

    def __init__(self, listed: str, report: Callable[[str, str], None], via: str):
        object.__setattr__(self, "_listed", listed)
        object.__setattr__(self, "_report", report)
        object.__setattr__(self, "_via", via)

    def _trip(self, *args, **kwargs):
        self._report(self._listed, self._via)
        raise Tripwire(f"{self._listed} is the exercise's own work: write it yourself")

    __getitem__ = __iter__ = __len__ = __contains__ = __call__ = _trip
    __array__ = __bool__ = __float__ = __int__ = __index__ = _trip
    __add__ = __radd__ = __mul__ = __rmul__ = __matmul__ = __rmatmul__ = _trip
    __neg__ = __sub__ = __rsub__ = __truediv__ = __rtruediv__ = _trip

    def __getattr__(self, name: str):
        if name.startswith("__") or name.startswith(("_repr_", "_ipython")):
            raise AttributeError(name)  # the machinery's probes are not reads
        self._trip()

    def __repr__(self) -> str:
        return f"<{self._listed}: the exercise's own work>"


def _tripwire(
    listed: str, report: Callable[[str, str], None], via: str = "", value=False
):
    if value:
        return TripValue(listed, report, via)

    def tripwire(*args, **kwargs):
        report(listed, via)
        raise Tripwire(f"{listed} is the exercise's own work: write it yourself")

    tripwire.__name__ = listed.rsplit(".", 1)[-1]
    tripwire.__qualname__ = tripwire.__name__
    return tripwire


def _where(container, attr: str) -> str:
    """Return the dotted name of ``container.attr`` (a class by its own module)."""
    if isinstance(container, type):
        return f"{container.__module__}.{container.__qualname__}.{attr}"
    return f"{getattr(container, '__name__', '?')}.{attr}"


def arm(
    writes: Iterable[str], report: Callable[[str, str], None], namespaces=()
) -> int:
    """Replace every listed function, wherever it is named, by a tripwire.

    Parameters
    ----------
    writes : iterable of str
        The listed functions.
    report : callable
        ``report(listed, via)`` when a tripwire fires (before it raises):
        the listed name and the name the call came through (``""`` when it
        is the listed name itself).
    namespaces : iterable of dict
        More namespaces to clean (e.g. the notebook's globals).

    Returns
    -------
    int
        How many places were armed.
    """
    writes = list(dict.fromkeys(writes))
    if not writes:
        return 0
    targets = _targets(writes)  # imports the listed functions' modules only
    made: dict[tuple[str, str], Callable] = {}

    def wire(listed: str, via: str):
        if (listed, via) not in made:
            value = listed in targets.values
            made[listed, via] = _tripwire(listed, report, via, value)
        return made[listed, via]

    n = 0

    def put(container, attr, listed):
        nonlocal n
        old = vars(container)[attr] if isinstance(container, type) else None
        w = wire(listed, _where(container, attr))
        if isinstance(old, staticmethod):
            w = staticmethod(w)
        elif isinstance(old, classmethod):
            w = classmethod(w)
        setattr(container, attr, w)
        n += 1

    for container, attr, listed, _ in list(_places(targets)):
        put(container, attr, listed)
    for w in writes:  # the listed name itself, wherever it lives
        parent, _, attr = w.rpartition(".")
        try:
            container = resolve(parent)
        except (ImportError, AttributeError):
            continue
        if (listed := targets.get(getattr(container, attr, None))) is not None:
            put(container, attr, listed)
    for ns in namespaces:
        for k, v in list(ns.items()):
            if (listed := targets.get(v)) is not None:
                ns[k] = wire(listed, k)
                n += 1
    _hook(wire, targets, writes)
    return n


def _hook(wire: Callable, targets: _Targets, writes: list[str]) -> None:
    """Re-arm robotlib modules executed (imported or reloaded) from now on."""
    import importlib.abc

    def rearm(module):
        for attr, val in list(vars(module).items()):
            if (listed := targets.get(val)) is not None:
                setattr(module, attr, wire(listed, _where(module, attr)))
        for w in writes:
            mod, _, attr = w.rpartition(".")
            if module.__name__ == mod and hasattr(module, attr):
                setattr(module, attr, wire(w, w))
            owner, _, cls = mod.rpartition(".")
            if module.__name__ == owner and isinstance(getattr(module, cls, 0), type):
                setattr(getattr(module, cls), attr, wire(w, w))

    class Loader(importlib.abc.Loader):
        def __init__(self, inner):
            self.inner = inner

        def create_module(self, spec):
            return self.inner.create_module(spec)

        def exec_module(self, module):
            self.inner.exec_module(module)
            rearm(module)

    class Finder(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path, target=None):
            if not name.startswith("robotlib.") or name.startswith("robotlib.course"):
                return None
            for f in sys.meta_path:
                if f is self or not hasattr(f, "find_spec"):
                    continue
                spec = f.find_spec(name, path, target)
                if spec is not None:
                    if spec.loader is not None:
                        spec.loader = Loader(spec.loader)
                    return spec
            return None

    sys.meta_path.insert(0, Finder())
    for name in [n for n in sys.modules if n.startswith("robotlib.")]:
        mod = sys.modules.get(name)
        spec = getattr(mod, "__spec__", None)
        if spec is not None and spec.loader is not None:
            spec.loader = Loader(spec.loader)
