"""The static pass: routes from a student's code to the library's own answers.

`scan_code` parses a cell and follows every name to what it names: imports
and aliases (``from robotlib.localization.paper import innovation_weights
as f``), attribute chains, re-exports (the ``names`` of
`answers.aliases`), ``getattr``/``vars(m)[...]``/``importlib``/
``__import__``/``sys.modules`` with constant strings, ``exec``/``eval`` of
constant strings, and strings that are a listed name or code reaching one.
A route found names the listed function (``listed=True``).

Machinery that can reach the library's answers where no name shows it
(``listed=False``) is reported only where it is that machinery: running
code built at run time (``exec`` of a variable), a subprocess or a process
pool (a fresh interpreter without the tripwires), reloading or loading
modules by hand, changing ``sys.modules`` or the import hooks, reading
source or code objects, the garbage collector's object lists, ``ctypes``, a
name built at run time looked up in a module holding a listed function,
and paths to notebooks or ``solutions/``. Names are resolved first, so
ordinary code is not mistaken for it: ``__import__('time')``,
``importlib.import_module('math')``, ``re.compile``, ``model.eval()``,
``platform.system()``, a variable called ``modules``, ``getattr(np,
'hypot')``, ``params.get('step')`` or a message that mentions a library
function are nothing. Names built at run time are left to the run-time
tripwires (`tripwires.arm`), which catch every call of a listed function.

Imports nothing of robotlib's.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass

from .astlock import parse

__all__ = ["MACHINERY", "Finding", "scan_code"]

MACHINERY = {
    "subprocess": "a subprocess",
    "os.system": "os.system",
    "os.popen": "os.popen",
    "os.exec*": "os.exec*",
    "os.spawn*": "os.spawn*",
    "os.posix_spawn*": "os.posix_spawn",
    "pty.spawn": "pty.spawn",
    "multiprocessing": "multiprocessing",
    "concurrent.futures.ProcessPoolExecutor": "a process pool",
    "ctypes": "ctypes",
    "importlib.reload": "importlib.reload",
    "importlib.util": "importlib.util",
    "importlib.machinery": "importlib.machinery",
    "runpy": "runpy",
    "sys.meta_path": "sys.meta_path",
    "sys.path_hooks": "sys.path_hooks",
    "inspect.getsource*": "inspect.getsource",
    "gc.get_objects": "gc.get_objects",
    "gc.get_referents": "gc.get_referents",
    "gc.get_referrers": "gc.get_referrers",
}
"""Dotted names (``*``: any name so starting) of machinery that can reach the
answers unseen: reaching for it in an exercise's own cell scores zero."""

_INSIDE = {"__code__", "__globals__", "__closure__", "__wrapped__"} | {
    "__file__",
    "__spec__",
    "__loader__",
    "__path__",
}  # a library function's code or a library module's files
_RUNNERS = {"builtins.exec", "builtins.eval", "builtins.compile"}
_BUILTINS = {"exec", "eval", "compile", "getattr", "vars", "__import__"}
_FETCH = {"get", "pop", "setdefault", "__getitem__", "__getattribute__", "__getattr__"}
_CHANGE = {
    "pop",
    "popitem",
    "clear",
    "update",
    "setdefault",
    "__delitem__",
    "__setitem__",
}
_NOTEBOOK = re.compile(r"(^|[/\\])solutions([/\\]|$)|^\S*\.ipynb$", re.IGNORECASE)
_DYNAMIC = "?"  # the dotted name of a module imported by a name built at run time


@dataclass(frozen=True)
class Finding:
    """One route from student code to a listed function (or to the answers)."""

    function: str  # the listed name, or what was used ("exec", "solutions/")
    how: str  # e.g. "imported as f", "getattr with a string"
    line: int = 0
    listed: bool = True  # False: machinery or reading the solutions
    via: str = ""  # the dotted name the code used (an alias of ``function``)


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


def _empty(node) -> bool:
    if isinstance(node, ast.Constant):
        return not node.value
    return isinstance(node, ast.List | ast.Tuple) and not node.elts


def _machinery(dotted: str | None) -> str | None:
    if not dotted:
        return None
    for key, what in MACHINERY.items():
        if key.endswith("*"):
            if dotted.startswith(key[:-1]):
                return what
        elif dotted == key or dotted.startswith(key + "."):
            return what
    return None


def _bound(tree) -> set[str]:
    """Names the code binds itself (assigned, defined, arguments)."""
    bound = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
            bound.add(node.id)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            bound.add(node.name)
        elif isinstance(node, ast.arg):
            bound.add(node.arg)
    return bound


class _Scanner(ast.NodeVisitor):
    def __init__(self, names: dict[str, str], tree, depth: int):
        self.names = names  # alias path -> listed
        self.lasts = {p.rsplit(".", 1)[-1]: w for p, w in names.items()}
        self.holders = {p.rsplit(".", 1)[0] for p in names}  # modules, classes
        self.roots = {p.split(".")[0] for p in names}
        self.bound = _bound(tree)
        self.depth = depth
        self.env: dict[str, str] = {}  # local name -> dotted path
        self.found: list[Finding] = []
        self.skip: set[int] = set()  # docstrings and strings exec'd (scanned)
        self.called: set[int] = set()  # the function nodes of calls

    def hit(self, dotted: str, how: str, node) -> bool:
        line = getattr(node, "lineno", 0)
        if dotted.startswith(_DYNAMIC + "."):
            listed = self.lasts.get(dotted.rsplit(".", 1)[-1])
            if listed is not None:
                how = f"{how}, from a module imported by a name built at run time"
                self.found.append(Finding(listed, how, line))
            return listed is not None
        for path, listed in self.names.items():
            if dotted == path or path.startswith(dotted + ".") and how == "star":
                self.found.append(Finding(listed, how, line, via=path))
                return True
        return False

    def machine(self, what: str, how: str, node) -> None:
        self.found.append(Finding(what, how, getattr(node, "lineno", 0), False))

    def library(self, dotted: str | None) -> bool:
        return bool(dotted) and dotted.split(".")[0] in self.roots

    # -- what a name, attribute, lookup or call names ----------------------------

    def dotted(self, node) -> str | None:
        if isinstance(node, ast.Name):
            if node.id in self.env:
                return self.env[node.id]
            if node.id in _BUILTINS and node.id not in self.bound:
                return f"builtins.{node.id}"
            return None
        if isinstance(node, ast.Attribute):
            base = self.dotted(node.value)
            if node.attr == "__dict__":
                return base
            return f"{base}.{node.attr}" if base else None
        if isinstance(node, ast.Subscript):
            return self.member(self.dotted(node.value), node.slice, node)
        if isinstance(node, ast.Call):
            return self.returns(node)
        return None

    def member(self, base: str | None, key, node) -> str | None:
        """Return what ``base[key]`` or ``getattr(base, key)`` names."""
        if not base:
            return None
        s = _const_str(key)
        if base == "sys.modules":
            return s or _DYNAMIC
        if s is None:
            if base in self.holders or base == _DYNAMIC:
                self.machine("a name built at run time", f"looked up in {base}", node)
            return None
        return f"{base}.{s}"

    def returns(self, node: ast.Call) -> str | None:
        """Return what a call returns, when it is a module or something looked up."""
        f, args = self.dotted(node.func), node.args
        if f in ("builtins.__import__", "importlib.import_module"):
            s = _const_str(args[0]) if args else None
            if s is None:
                return _DYNAMIC
            fromlist = [k.value for k in node.keywords if k.arg == "fromlist"]
            fromlist += args[3:4]
            empty = all(_empty(v) for v in fromlist)
            return s.split(".")[0] if f.startswith("builtins") and empty else s
        if f == "builtins.getattr" and len(args) >= 2:
            return self.member(self.dotted(args[0]), args[1], node)
        if f == "builtins.vars" and len(args) == 1:
            return self.dotted(args[0])
        if f == "pydoc.locate" and args:
            return _const_str(args[0])
        func = node.func
        if isinstance(func, ast.Attribute) and func.attr in _FETCH and args:
            return self.member(self.dotted(func.value), args[0], node)
        if isinstance(func, ast.Call) and len(args) == 1:  # attrgetter(s)(obj)
            g = self.dotted(func.func) or ""
            if g.endswith("attrgetter") and len(func.args) == 1:
                return self.member(self.dotted(args[0]), func.args[0], node)
        return None

    # -- visits ------------------------------------------------------------------

    def visit_Module(self, node):
        self._docstring(node)
        self.generic_visit(node)

    def _docstring(self, node):
        body = getattr(node, "body", [])
        if body and isinstance(body[0], ast.Expr):
            if isinstance(body[0].value, ast.Constant):
                self.skip.add(id(body[0].value))

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
        for t in node.targets:
            self._changes_modules(t, node)
        d = self.dotted(node.value)
        if d:
            for t in node.targets:
                if isinstance(t, ast.Name):
                    self.env[t.id] = d

    def visit_Delete(self, node):
        for t in node.targets:
            self._changes_modules(t, node)
        self.generic_visit(node)

    def _changes_modules(self, target, node) -> None:
        if isinstance(target, ast.Subscript):
            target = target.value
        if self.dotted(target) == "sys.modules":
            self.machine("sys.modules", "changed", node)

    def visit_Attribute(self, node):
        d = self.dotted(node)
        if d and self.hit(d, "attribute", node):
            return
        self.generic_visit(node)
        if (what := _machinery(d)) is not None:
            self.machine(what, "used", node)
        base = self.dotted(node.value)
        if node.attr in _INSIDE and self.library(base):
            self.machine(f"{base}.{node.attr}", "read", node)

    def visit_Subscript(self, node):
        d = self.dotted(node)
        if d and self.hit(d, "looked up by a string", node):
            return
        self.generic_visit(node)

    def visit_Name(self, node):
        d = self.dotted(node)
        if (what := _machinery(d)) is not None:
            self.machine(what, "used", node)
        if d in _RUNNERS and id(node) not in self.called:
            self.machine(d.split(".")[1], "passed around", node)

    def visit_Call(self, node):
        self.called.add(id(node.func))
        f = self.dotted(node.func)
        d = self.returns(node)
        if d and d in self.names or d and d.startswith(_DYNAMIC + "."):
            self.hit(d, "looked up by a string", node)
        if f in _RUNNERS:
            runner = f.split(".")[1]
            s = _const_str(node.args[0]) if node.args else None
            if s is None:
                self.machine(runner, "on code built at run time", node)
            else:
                self.skip.add(id(node.args[0]))
                for fd in scan_code(s, self.names, self.depth + 1):
                    how, line = f"in {runner}()", node.lineno
                    self.found.append(
                        Finding(fd.function, how, line, fd.listed, fd.via)
                    )
        func = node.func
        if isinstance(func, ast.Attribute) and func.attr in _CHANGE:
            self._changes_modules(func.value, node)
        self.generic_visit(node)

    def visit_Constant(self, node):
        if isinstance(node.value, str) and id(node) not in self.skip:
            self._string(node.value, node)

    def visit_BinOp(self, node):
        s = _const_str(node)
        if s is not None:
            self._string(s, node)
        self.generic_visit(node)

    def _string(self, s: str, node) -> None:
        line = getattr(node, "lineno", 0)
        text = s.strip()
        if text in self.names:
            listed = self.names[text]
            self.found.append(Finding(listed, "named in a string", line, via=text))
        elif self.depth < 3 and any(r in s for r in self.roots):
            for fd in scan_code(s, self.names, self.depth + 1):
                if fd.listed:
                    how = "in a string of code"
                    self.found.append(Finding(fd.function, how, line, via=fd.via))
        if "\n" not in text and _NOTEBOOK.search(text):
            self.found.append(Finding("solutions/", "reads notebooks", line, False))


def scan_code(source: str, names: dict[str, str], depth: int = 0) -> list[Finding]:
    """Find the routes from ``source`` to the functions of ``names``.

    Parameters
    ----------
    source : str
        A cell's code (IPython syntax allowed).
    names : dict
        `answers.aliases` of the listed functions.
    depth : int
        How deep in strings of code this source is (strings are followed
        three deep).

    Returns
    -------
    list of Finding
        ``listed=True`` findings name a listed function; ``listed=False``
        ones name machinery (`MACHINERY`, code run from a string built at
        run time) or reading notebooks. A cell that does not parse gives no
        findings (it fails when run).
    """
    try:
        tree = parse(_python(source) if depth == 0 else source)
    except (SyntaxError, ValueError):
        return []
    sc = _Scanner(names, tree, depth)
    sc.visit(tree)
    seen, out = set(), []
    for f in sc.found:
        if (f.function, f.how, f.via) not in seen:
            seen.add((f.function, f.how, f.via))
            out.append(f)
    return out


def _python(source: str) -> str:
    try:
        from IPython.core.inputtransformer2 import TransformerManager

        return TransformerManager().transform_cell(source)
    except Exception:  # noqa: BLE001 - IPython missing or a transformer failed
        return source
