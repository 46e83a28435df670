"""The two sandboxed processes that grade a submission, and their wire format.

``python -m robotlib.course.worker student IN OUT`` (the student process)
runs the lab's canonical set-up cell, arms the tripwires (`tripwires.arm`),
then runs the student's exercise cells (and cells the student added), and
serves calls: ``call NAME`` runs the student's function on the pickled
arguments and answers with the result and the arguments as they are after
the call (a robot that was driven, a generator that was drawn from).

``python -m robotlib.course.worker check IN OUT`` (the check process) runs
only the instructor's code: the set-up cell, the definitions the checks need
(taken from ``solutions/``) and the check cells, hidden tests included. Each
name an exercise defines is a proxy: calling it asks the student process,
through the grader, and decodes the answer with `safe_loads` (numbers,
arrays, containers, robotlib's own classes; never a callable the student
made). Student code never runs here, so it cannot patch what the checks
call, print or compare; the check's ``CHECK`` lines go to the grader on a
pipe only this process holds.

Frames: a 12-byte header (4-byte JSON length, 8-byte payload length, big
endian), the JSON header, the payload. Imports only the standard library at
module level; the student process imports `tripwires`.
"""

from __future__ import annotations

import io
import json
import os
import pickle
import re
import struct
import sys
import traceback

__all__ = ["send", "recv", "safe_loads", "main"]

MAX_FRAME = 1 << 30


def send(fd: int, header: dict, payload: bytes = b"") -> None:
    """Write one frame to ``fd``."""
    head = json.dumps(header).encode()
    data = struct.pack(">IQ", len(head), len(payload)) + head + payload
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _read(fd: int, n: int) -> bytes:
    chunks, left = [], n
    while left:
        chunk = os.read(fd, min(left, 1 << 20))
        if not chunk:
            raise EOFError
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def recv(fd: int) -> tuple[dict, bytes]:
    """Read one frame from ``fd``; raise EOFError at the end, ValueError if bad."""
    nh, npay = struct.unpack(">IQ", _read(fd, 12))
    if nh > 1 << 24 or npay > MAX_FRAME:
        raise ValueError("frame too large")
    header = json.loads(_read(fd, nh))
    if not isinstance(header, dict):
        raise ValueError("bad frame")
    return header, _read(fd, npay)


_SAFE = {
    "builtins": {
        "list", "dict", "tuple", "set", "frozenset", "complex", "bytearray",
        "slice", "range", "int", "float", "bool", "str", "bytes", "object",
    },
    "collections": {"OrderedDict", "deque", "defaultdict"},
    "copyreg": {"_reconstructor"},
    "numpy": {"ndarray", "dtype"},
    "numpy.core.multiarray": {"_reconstruct", "scalar"},
    "numpy._core.multiarray": {"_reconstruct", "scalar"},
    "numpy.random._pickle": {
        "__generator_ctor", "__bit_generator_ctor", "__randomstate_ctor",
    },
}  # fmt: skip


class _SafeUnpickler(pickle.Unpickler):
    def find_class(self, module, name):
        if name in _SAFE.get(module, ()):
            return super().find_class(module, name)
        if module.startswith("numpy.random.") and name.startswith("__pyx_unpickle_"):
            return super().find_class(module, name)  # bit generators' state
        if module == "pathlib" and name in ("PosixPath", "PurePosixPath", "Path"):
            return super().find_class(module, name)
        if module.startswith(("numpy.dtypes", "numpy.random.")):
            obj = super().find_class(module, name)
            if isinstance(obj, type):
                return obj
        if module.startswith("robotlib.") and not module.startswith("robotlib.course"):
            obj = super().find_class(module, name)
            if isinstance(obj, type):  # classes only: data, never a function
                return obj
        if module in ("numpy", "numpy._core.numerictypes", "numpy.core.numerictypes"):
            obj = super().find_class(module, name)
            import numpy as np

            if isinstance(obj, type) and issubclass(obj, np.generic):
                return obj
        raise pickle.UnpicklingError(f"not allowed from student code: {module}.{name}")


def safe_loads(data: bytes):
    """Unpickle data that came from student code: plain data and robotlib classes."""
    return _SafeUnpickler(io.BytesIO(data)).load()


# -- the student process ---------------------------------------------------------


def _trim(exc: BaseException, sources: dict[str, str]) -> str:
    """Return the student's traceback: frames of their cells only."""
    lines = []
    for fr in traceback.extract_tb(exc.__traceback__):
        m = re.fullmatch(r"<ipython-input-\d+-(.*)>", fr.filename)
        if m:
            cid = m.group(1)
            src = sources.get(cid, "").splitlines()
            code = (
                src[fr.lineno - 1].strip() if 0 < (fr.lineno or 0) <= len(src) else ""
            )
            lines.append(f"  cell {cid}, line {fr.lineno}, in {fr.name}: {code}")
        elif lines and not lines[-1].endswith("(library)"):
            lines.append("  ... (library)")
    lines.append(f"{type(exc).__name__}: {exc}"[:500])
    return "\n".join(lines[-12:])


def _register(name: str, source: str) -> str:
    """Put a cell's source in linecache under its name, as IPython does.

    numba's cache for a function defined in a cell reads the function's
    source (``inspect.getsource``); without this an ``@njit(cache=True)``
    in a set-up or student cell raises ``OSError: could not get source``.
    """
    import linecache

    linecache.cache[name] = (len(source), None, source.splitlines(True), name)
    return source


def _no_warm_up(spec: dict) -> None:
    """Make the set-up cell's warm-ups a no-op when the cache holds the kernels."""
    if spec.get("skip_warm_up"):
        os.environ["ROBOTLIB_SKIP_WARM_UP"] = "1"  # read by robotlib.notebook.setup


def _student(fin: int, fout: int) -> None:
    from IPython.core.interactiveshell import InteractiveShell

    from . import tripwires

    spec, _ = recv(fin)
    shell = InteractiveShell.instance()
    ns = shell.user_ns
    ns["__name__"] = "__main__"
    active = {"exercise": None}  # the exercise whose cell or function runs

    def report(listed: str, via: str = "") -> None:
        ex = active["exercise"]
        msg = {"op": "tripwire", "function": listed, "exercise": ex, "via": via}
        send(fout, msg)

    def run(cid: str, source: str) -> None:
        # named like IPython's cells: numba can cache @njit(cache=True) in them
        name = f"<ipython-input-{len(sources)}-{cid}>"
        code = compile(_register(name, shell.transform_cell(source)), name, "exec")
        exec(code, ns)  # noqa: S102 - the student's cell, in its sandbox

    sources = {c["id"]: c["source"] for c in spec["cells"]}
    sources["setup"] = spec["setup"]
    _no_warm_up(spec)
    run("setup", spec["setup"])
    tripwires.arm(spec["writes"], report, [ns])
    for cell in spec["cells"]:
        send(fout, {"op": "cell", "id": cell["id"], "status": "start"})
        active["exercise"] = cell.get("exercise")
        try:
            run(cell["id"], cell["source"])
            send(fout, {"op": "cell", "id": cell["id"], "status": "ok"})
        except BaseException as exc:  # noqa: BLE001 - the student's error
            tb = _trim(exc, sources)
            send(fout, {"op": "cell", "id": cell["id"], "status": "error", "error": tb})
        active["exercise"] = None
    send(fout, {"op": "ready"})
    while True:
        try:
            req, payload = recv(fin)
        except EOFError:
            return
        active["exercise"] = req.get("exercise")
        try:
            if req["op"] == "get":
                value = ns[req["name"]]
                out = pickle.dumps((value, (), {}))
            else:
                args, kwargs = pickle.loads(payload)  # from the check process
                fn = ns[req["name"]]
                value = fn(*args, **kwargs)
                out = pickle.dumps((value, args, kwargs))
            send(fout, {"op": "result", "ok": True}, out)
        except BaseException as exc:  # noqa: BLE001 - the student's error
            if isinstance(exc, KeyError) and exc.args == (req.get("name"),):
                tb = f"NameError: {req.get('name')!r} is not defined"
            else:
                tb = _trim(exc, sources)
            send(fout, {"op": "result", "ok": False, "error": tb})
        active["exercise"] = None


# -- the check process ---------------------------------------------------------------


class StudentError(Exception):
    """The student's function raised, hung or crashed; carries their traceback."""

    def __init__(self, name: str, error: str):
        super().__init__(f"{name}: {error}")
        self.name, self.error = name, error


def _sync(old, new) -> None:
    """Make ``old`` (an argument) look like ``new`` (the same after the call)."""
    import numpy as np

    if isinstance(old, np.ndarray):
        if isinstance(new, np.ndarray) and new.shape == old.shape:
            if old.flags.writeable:
                old[...] = new
    elif isinstance(old, np.random.Generator):
        if isinstance(new, np.random.Generator):
            old.bit_generator.state = new.bit_generator.state
    elif isinstance(old, list) and isinstance(new, list):
        old[:] = new
    elif isinstance(old, dict) and isinstance(new, dict):
        old.clear()
        old.update(new)
    elif type(new) is type(old) and hasattr(old, "__dict__"):
        try:
            vars(old).clear()
            vars(old).update(vars(new))
        except TypeError:
            pass


class _Proxy:
    def __init__(self, name: str, exercise: str, fin: int, fout: int):
        self.name, self.exercise, self.fin, self.fout = name, exercise, fin, fout
        self.__name__ = name

    def _ask(self, op: str, payload: bytes = b""):
        send(
            self.fout, {"op": op, "name": self.name, "exercise": self.exercise}, payload
        )
        reply, data = recv(self.fin)
        if not reply.get("ok"):
            raise StudentError(self.name, str(reply.get("error", "failed"))[:3000])
        try:
            return safe_loads(data)
        except Exception as exc:
            raise StudentError(
                self.name, f"returned something unusable: {exc}"
            ) from None

    def __call__(self, *args, **kwargs):
        value, args2, kwargs2 = self._ask("call", pickle.dumps((args, kwargs)))
        after = args2 if isinstance(args2, tuple | list) else ()
        for a, b in zip(args, after, strict=False):
            _sync(a, b)
        if isinstance(kwargs2, dict):
            for k, v in kwargs.items():
                if k in kwargs2:
                    _sync(v, kwargs2[k])
        return value

    def __repr__(self):
        return f"<your {self.name}>"


HIDDEN_MARK = "ROBOTLIB-HIDDEN-TESTS-FOLLOW"


def _check(fin: int, fout: int) -> None:
    import contextlib

    from IPython.core.interactiveshell import InteractiveShell

    spec, _ = recv(fin)
    shell = InteractiveShell.instance()
    ns = shell.user_ns
    ns["__name__"] = "__main__"

    count = [0]

    def run(label, source):
        # named like IPython's cells, so that numba can cache an
        # @njit(cache=True) function the set-up cell or a check defines (a
        # plain "<setup>" has no cache locator: numba raises)
        count[0] += 1
        name = f"<ipython-input-{count[0]}-{label}>"
        code = compile(_register(name, shell.transform_cell(source)), name, "exec")
        exec(code, ns)  # noqa: S102 - the instructor's code

    _no_warm_up(spec)
    run("setup", spec["setup"])
    # the solution's answers, for the exercises a check does not grade: in a
    # namespace of their own (they call each other, never the student's)
    solved = dict(ns)
    for i, src in enumerate(spec.get("answers", [])):
        try:
            count[0] += 1
            name = f"<ipython-input-{count[0]}-answer-{i}>"
            source = _register(name, shell.transform_cell(src))
            exec(compile(source, name, "exec"), solved)  # noqa: S102 - ours
        except BaseException:  # noqa: BLE001 - that exercise keeps the student's
            continue
    proxies = {}
    for name, info in spec["names"].items():
        proxies[name] = _Proxy(name, info["exercise"], fin, fout)
        if info["kind"] == "function":
            ns[name] = proxies[name]
    for i, src in enumerate(spec["defs"]):
        run(f"definition-{i}", src)
    for name, info in spec["names"].items():  # definitions never replace proxies
        if info["kind"] == "function":
            ns[name] = proxies[name]
    send(fout, {"op": "ready"})
    for chk in spec["checks"][spec.get("start", 0) :]:
        send(fout, {"op": "begin", "gid": chk["gid"]})
        buf = io.StringIO()
        status, error, student = "passed", "", ""
        graded = set(chk.get("exercises") or [chk["gid"]])
        for name, info in spec["names"].items():
            theirs = info["exercise"] in graded or name not in solved
            if info["kind"] == "function":
                ns[name] = proxies[name] if theirs else solved[name]
        try:
            for name in chk.get("values", []):
                mine = spec["names"][name]["exercise"] in graded or name not in solved
                ns[name] = proxies[name]._ask("get")[0] if mine else solved[name]
            with contextlib.redirect_stdout(buf):
                run(f"check-{chk['gid']}", chk["source"])
        except StudentError as exc:
            last = exc.error.strip().splitlines()[-1] if exc.error.strip() else ""
            status, student = "failed", exc.error
            error = f"your {exc.name} failed: {last}"[:300]
        except AssertionError as exc:
            status, error = "failed", str(exc) or "an assertion failed"
        except BaseException as exc:  # noqa: BLE001 - reported, the next check runs
            status = "failed"
            error = f"{type(exc).__name__}: {exc}"
        lines = buf.getvalue().splitlines()
        hidden = lines.index(HIDDEN_MARK) if HIDDEN_MARK in lines else len(lines)
        shown = [ln.rstrip() for ln in lines[:hidden] if ln.startswith("CHECK ")]
        secret = [ln.rstrip() for ln in lines[hidden:] if ln.startswith("CHECK ")]
        send(
            fout,
            {
                "op": "end",
                "gid": chk["gid"],
                "status": status,
                "error": error[:1000],
                "student": student,
                "lines": shown[:50],
                "hidden": secret[:50],
            },
        )
    send(fout, {"op": "done"})


def main(argv: list[str] | None = None) -> int:
    """Run the student or check process (``student|check IN_FD OUT_FD``)."""
    argv = sys.argv[1:] if argv is None else argv
    role, fin, fout = argv[0], int(argv[1]), int(argv[2])
    os.environ.setdefault("MPLBACKEND", "Agg")
    if role == "student":
        _student(fin, fout)
    else:
        _check(fin, fout)
    sys.stdout.flush()
    os._exit(0)  # skip interpreter teardown (threads of numba, matplotlib)


if __name__ == "__main__":
    main()
