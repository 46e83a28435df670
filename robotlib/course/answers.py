"""Answers not shipped: find student code that reaches the library's own answers.

Each exercise lists (``writes``) the dotted library functions whose work it
asks for. Two defences, both keyed on those lists:

- `scan_code`, static, in the grader: the student's cells are parsed and
  every route to a listed function is followed: imports and aliases
  (``from robotlib.localization.paper import innovation_weights as f``),
  attribute chains, re-exports (`aliases` finds every module or class
  attribute naming the same object), ``getattr``/``importlib`` with
  constant strings, ``exec``/``eval`` of constant strings, names in string
  constants, reading ``solutions/`` or notebooks; dynamic machinery
  (``exec``, ``importlib``, ``sys.modules``, subprocesses) in an exercise's
  own cell counts as reaching, elsewhere it is flagged;
- `tripwires.arm`, at run time, in the sandboxed student process: every
  listed object, under every name a loaded module or class gives it, is
  replaced by a tripwire (see there), using what this module finds.

Imports nothing of robotlib's at module level (`aliases` imports the library
to resolve names).
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
import sys
from collections.abc import Iterable
from dataclasses import dataclass

from .astlock import parse

__all__ = [
    "Finding",
    "aliases",
    "equivalents",
    "resolve",
    "scan_code",
]

DYNAMIC = {
    "exec": "exec",
    "eval": "eval",
    "compile": "compile",
    "__import__": "__import__",
    "importlib": "importlib",
    "reload": "importlib.reload",
    "modules": "sys.modules",
    "meta_path": "sys.meta_path",
    "subprocess": "a subprocess",
    "system": "os.system",
    "popen": "os.popen",
    "execv": "os.exec*",
    "execve": "os.exec*",
    "execl": "os.exec*",
    "multiprocessing": "multiprocessing",
    "ctypes": "ctypes",
    "getsource": "inspect.getsource",
    "__code__": "__code__",
    "__globals__": "__globals__",
    "__closure__": "__closure__",
    "__wrapped__": "__wrapped__",
    "get_objects": "gc.get_objects",
    "get_referents": "gc.get_referents",
}
"""Names of dynamic machinery: reaching with it in an exercise cell scores zero."""


@dataclass(frozen=True)
class Finding:
    """One route from student code to a listed function (or to the answers)."""

    function: str  # the listed name, or what was used ("exec", "solutions/")
    how: str  # e.g. "imported as f", "getattr with a string"
    line: int = 0
    listed: bool = True  # False: dynamic machinery or reading the solutions
    via: str = ""  # the dotted name the code used (an alias of ``function``)


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


# -- static analysis ---------------------------------------------------------------


def _python(source: str) -> str:
    try:
        from IPython.core.inputtransformer2 import TransformerManager

        return TransformerManager().transform_cell(source)
    except Exception:  # noqa: BLE001 - IPython missing or a transformer failed
        return source


def _const_str(node) -> str | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        a, b = _const_str(node.left), _const_str(node.right)
        return a + b if a is not None and b is not None else None
    if isinstance(node, ast.JoinedStr):
        parts = [_const_str(v) for v in node.values]
        return "".join(parts) if all(p is not None for p in parts) else None
    return None


_LOOKUPS = {
    "getattr", "hasattr", "attrgetter", "methodcaller", "__getattribute__",
    "__getattr__", "get", "pop", "setdefault", "import_module", "__import__",
}  # fmt: skip
"""Calls whose string arguments name a thing to fetch (a bare name counts there)."""


class _Scanner(ast.NodeVisitor):
    def __init__(self, names: dict[str, str]):
        self.names = names  # alias path -> listed
        self.lasts = {p.rsplit(".", 1)[-1]: w for p, w in names.items()}
        self.env: dict[str, str] = {}  # local name -> dotted path
        self.found: list[Finding] = []
        self.docstrings: set[int] = set()
        self.lookups: set[int] = set()  # strings used as a name to look up

    def hit(self, dotted: str, how: str, node) -> bool:
        for path, listed in self.names.items():
            if dotted == path or path.startswith(dotted + ".") and how == "star":
                line = getattr(node, "lineno", 0)
                self.found.append(Finding(listed, how, line, via=path))
                return True
        return False

    def dotted(self, node) -> str | None:
        if isinstance(node, ast.Name):
            return self.env.get(node.id)
        if isinstance(node, ast.Attribute):
            base = self.dotted(node.value)
            return f"{base}.{node.attr}" if base else None
        if isinstance(node, ast.Call):
            f = self.dotted(node.func) or ""
            args = node.args
            if (
                f.endswith("import_module")
                or f == "__import__"
                or (isinstance(node.func, ast.Name) and node.func.id == "__import__")
            ):
                s = _const_str(args[0]) if args else None
                return s
            if isinstance(node.func, ast.Name) and node.func.id == "getattr":
                if len(args) >= 2:
                    base, s = self.dotted(args[0]), _const_str(args[1])
                    if base and s:
                        return f"{base}.{s}"
        return None

    def visit_Module(self, node):
        self._docstring(node)
        self.generic_visit(node)

    def _docstring(self, node):
        body = getattr(node, "body", [])
        if body and isinstance(body[0], ast.Expr):
            if isinstance(body[0].value, ast.Constant):
                self.docstrings.add(id(body[0].value))

    def visit_FunctionDef(self, node):
        self._docstring(node)
        self.generic_visit(node)

    visit_AsyncFunctionDef = visit_FunctionDef  # noqa: N815
    visit_ClassDef = visit_FunctionDef  # noqa: N815

    def visit_Import(self, node):
        for a in node.names:
            if a.asname:
                self.env[a.asname] = a.name
            else:
                top = a.name.split(".")[0]
                self.env[top] = top
            self.hit(a.name, "imported", node)

    def visit_ImportFrom(self, node):
        if node.level or not node.module:
            return
        for a in node.names:
            if a.name == "*":
                self.hit(node.module, "star", node)
                continue
            path = f"{node.module}.{a.name}"
            self.env[a.asname or a.name] = path
            how = f"imported as {a.asname}" if a.asname else "imported"
            self.hit(path, how, node)

    def visit_Assign(self, node):
        self.generic_visit(node)
        d = self.dotted(node.value)
        if d:
            for t in node.targets:
                if isinstance(t, ast.Name):
                    self.env[t.id] = d

    def visit_Attribute(self, node):
        d = self.dotted(node)
        if not (d and self.hit(d, "attribute", node)):
            self.generic_visit(node)
        if node.attr in DYNAMIC:
            self.found.append(Finding(DYNAMIC[node.attr], "used", node.lineno, False))

    def visit_Name(self, node):
        if node.id in DYNAMIC:
            self.found.append(Finding(DYNAMIC[node.id], "used", node.lineno, False))

    def visit_Call(self, node):
        f = node.func
        called = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
        if called in _LOOKUPS:
            self.lookups.update(id(a) for a in node.args)
        d = self.dotted(node)
        if d and d in self.names:
            self.hit(d, "looked up by a string", node)
        f = node.func
        if isinstance(f, ast.Name) and f.id in ("exec", "eval", "compile"):
            s = _const_str(node.args[0]) if node.args else None
            if s is not None:
                for fd in scan_code(s, self.names):
                    how, line = f"in {f.id}()", node.lineno
                    self.found.append(Finding(fd.function, how, line, via=fd.via))
        self.generic_visit(node)

    def visit_Subscript(self, node):
        v = node.value
        if isinstance(v, ast.Call) or getattr(v, "attr", "") == "__dict__":
            self.lookups.add(id(node.slice))  # vars(m)["name"], m.__dict__["name"]
        self.generic_visit(node)

    def visit_Constant(self, node):
        if not isinstance(node.value, str) or id(node) in self.docstrings:
            return
        self._string(node.value, node)

    def visit_BinOp(self, node):
        s = _const_str(node)
        if s is not None:
            self._string(s, node)
        self.generic_visit(node)

    def _string(self, s: str, node) -> None:
        if s.strip() in self.lasts and id(node) in self.lookups:
            listed = self.lasts[s.strip()]
            self.found.append(Finding(listed, "named in a string", node.lineno))
        for path, listed in self.names.items():
            if path in s:
                f = Finding(listed, "named in a string", node.lineno, via=path)
                self.found.append(f)
        low = s.lower()
        if "solutions" in low and ("/" in low or "ipynb" in low) or ".ipynb" in low:
            self.found.append(
                Finding("solutions/", "reads notebooks", node.lineno, False)
            )


def scan_code(source: str, names: dict[str, str]) -> list[Finding]:
    """Find the routes from ``source`` to the functions of ``names``.

    Parameters
    ----------
    source : str
        A cell's code (IPython syntax allowed).
    names : dict
        `aliases` of the listed functions.

    Returns
    -------
    list of Finding
        ``listed=True`` findings name a listed function; ``listed=False``
        ones name dynamic machinery or reading notebooks. A cell that does not
        parse gives no findings (it fails when run).
    """
    try:
        tree = parse(_python(source))
    except (SyntaxError, ValueError):
        return []
    sc = _Scanner(names)
    sc.visit(tree)
    seen, out = set(), []
    for f in sc.found:
        if (f.function, f.how, f.via) not in seen:
            seen.add((f.function, f.how, f.via))
            out.append(f)
    return out
