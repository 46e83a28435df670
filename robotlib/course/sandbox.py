"""The sandbox each grading process runs in: bubblewrap, an unprivileged user, limits.

`command` wraps a command line so that it runs

- in its own PID, network, IPC and UTS namespaces (``bwrap --unshare-*``):
  it sees only its own processes, has no network (not even loopback to the
  host), and killing the sandbox's first process ends every process in it,
  whatever they did (``setsid``, double forks);
- as an unprivileged user: as root, a uid of its own per grading slot
  (``setpriv`` inside the sandbox, all capabilities dropped,
  ``no_new_privs``); otherwise in a user namespace as the instructor's uid;
- seeing only what it needs, read-only: the system (``/usr``, ``/etc``),
  Python, the virtual environment, the installed library and its worlds;
  never ``solutions/``, the submissions, the gradebook or the grader's work
  folders; its own writable scratch folder at ``/scratch`` and a private
  ``/tmp`` (writable by all, its size limited);
- under resource limits (``prlimit``): address space, processes, file size,
  open files, CPU time, no core files.

`available` says whether bubblewrap works here. With ``sandbox=False`` the
same limits and environment apply, without the isolation (``--no-sandbox``).
Imports nothing of robotlib's but the location of the installed package.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "Limits",
    "available",
    "command",
    "readonly_paths",
    "scratch_bytes",
    "SCRATCH",
]

SCRATCH = "/scratch"
"""Where the submission's writable scratch folder appears in the sandbox."""


@dataclass(frozen=True)
class Limits:
    """Resource limits of one sandboxed process (``prlimit``).

    Attributes
    ----------
    memory : int
        Address space, bytes.
    processes : int
        Processes and threads of the sandbox's user.
    file_size : int
        Largest file it may write, bytes.
    open_files : int
        Open file descriptors.
    cpu : int
        CPU time, s.
    tmp : int
        Size of the sandbox's private ``/tmp`` (memory), bytes.
    disk : int
        Bytes a submission may add to its scratch folder (the grader measures
        it every second and ends the process past it; see `scratch_bytes`).
    """

    memory: int = 6 << 30
    processes: int = 256
    file_size: int = 256 << 20
    open_files: int = 512
    cpu: int = 900
    tmp: int = 512 << 20
    disk: int = 1 << 30

    def prlimit(self) -> list[str]:
        """Return the ``prlimit`` command prefix setting these limits."""
        return [
            "prlimit",
            f"--as={self.memory}",
            f"--nproc={self.processes}",
            f"--fsize={self.file_size}",
            f"--nofile={self.open_files}",
            f"--cpu={self.cpu}",
            "--core=0",
            "--",
        ]


def readonly_paths() -> list[Path]:
    """Folders a grading process needs, read-only: Python, the venv, the library."""
    pkg = Path(__file__).resolve().parents[1]  # the installed robotlib package
    paths = {
        Path(sys.base_prefix).resolve(),
        Path(sys.prefix).resolve(),
        Path(sys.executable).resolve().parent.parent,
        pkg,
    }
    worlds = pkg.parent / "worlds"
    if worlds.is_dir():
        paths.add(worlds)
    for p in list(paths):
        if str(p) in ("/", "/usr") or not p.exists():
            paths.discard(p)
    # keep the outermost of nested paths
    out = sorted(paths, key=lambda p: len(p.parts))
    return [p for i, p in enumerate(out) if not any(q in p.parents for q in out[:i])]


def _parents(paths: list[Path]) -> list[Path]:
    seen: list[Path] = []
    for p in paths:
        for parent in reversed(p.parents):
            if parent != Path("/") and parent not in seen:
                seen.append(parent)
    return seen


_SYSTEM = ("/usr", "/etc", "/opt")
_LINKS = {"/bin": "usr/bin", "/sbin": "usr/sbin", "/lib": "usr/lib"}


def scratch_bytes(folder: Path) -> int:
    """Return the bytes the files under ``folder`` take (links not followed)."""
    total, todo = 0, [str(folder)]
    while todo:
        try:
            with os.scandir(todo.pop()) as it:
                for e in it:
                    try:
                        if e.is_dir(follow_symlinks=False):
                            todo.append(e.path)
                        else:
                            total += e.stat(follow_symlinks=False).st_blocks * 512
                    except OSError:
                        continue
        except OSError:
            continue
    return total


def _bwrap(scratch: Path, uid: int | None, cwd: str, tmp: int) -> list[str]:
    args = [
        "bwrap",
        "--unshare-pid",
        "--unshare-net",
        "--unshare-ipc",
        "--unshare-uts",
        "--unshare-cgroup-try",
        "--die-with-parent",
        "--new-session",
        "--hostname",
        "sandbox",
    ]
    if uid is None:  # unprivileged: a user namespace as ourselves
        args.append("--unshare-user")
    else:
        args += ["--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    for d in _SYSTEM:
        if os.path.isdir(d):
            args += ["--ro-bind", d, d]
    for link, target in _LINKS.items():
        if os.path.islink(link):
            args += ["--symlink", target, link]
        elif os.path.isdir(link):
            args += ["--ro-bind", link, link]
    for lib in ("/lib64", "/lib32"):
        if os.path.islink(lib):
            args += ["--symlink", os.readlink(lib), lib]
        elif os.path.isdir(lib):
            args += ["--ro-bind", lib, lib]
    # /tmp first: a checkout or venv under /tmp is then bound on top of it
    args += ["--proc", "/proc", "--dev", "/dev"]
    args += ["--perms", "1777", "--size", str(tmp), "--tmpfs", "/tmp"]
    ro = [p for p in readonly_paths() if not str(p).startswith(_SYSTEM)]
    for parent in _parents(ro):
        if not str(parent).startswith(_SYSTEM):
            args += ["--perms", "0755", "--dir", str(parent)]
    for p in ro:
        args += ["--ro-bind", str(p), str(p)]
    args += ["--bind", str(scratch), SCRATCH, "--chdir", cwd, "--clearenv"]
    return args


def command(
    argv: list[str],
    scratch: Path,
    env: dict[str, str],
    limits: Limits,
    uid: int | None = None,
    sandbox: bool = True,
    cwd: str = SCRATCH,
) -> tuple[list[str], dict[str, str]]:
    """Wrap ``argv`` to run sandboxed; return ``(command, environment)``.

    Parameters
    ----------
    argv : list of str
        The command (its paths as seen inside the sandbox).
    scratch : pathlib.Path
        The writable folder, mounted at `SCRATCH` (owned by ``uid``).
    env : dict
        The environment inside (nothing else is passed).
    limits : Limits
        Resource limits.
    uid : int, optional
        As root: the unprivileged uid (and gid) to run as.
    sandbox : bool
        False: no isolation (``--no-sandbox``); ``SCRATCH`` paths in ``env``
        and ``argv`` are rewritten to ``scratch``.
    cwd : str
        Working directory inside.
    """
    if uid is None:  # the limit counts all our own processes, not the sandbox's
        limits = Limits(**{**vars(limits), "processes": 1 << 16})
    if not sandbox:
        fix = functools.partial(_rewrite, str(scratch))
        return [*limits.prlimit(), *map(fix, argv)], {k: fix(v) for k, v in env.items()}
    args = _bwrap(scratch, uid, cwd, limits.tmp)
    for k, v in env.items():
        args += ["--setenv", k, v]
    args.append("--")
    if uid is not None:
        args += [
            "setpriv",
            f"--reuid={uid}",
            f"--regid={uid}",
            "--clear-groups",
            "--inh-caps=-all",
            "--bounding-set=-all",
            "--no-new-privs",
        ]
    return [*limits.prlimit(), *args, *argv], {"PATH": os.defpath}


def _rewrite(root: str, value: str) -> str:
    if value == SCRATCH or value.startswith(SCRATCH + "/"):
        return root + value[len(SCRATCH) :]
    return value


def sandbox_uid(slot: int) -> int | None:
    """Return the uid grading slot ``slot`` runs as (None unless we are root)."""
    if os.geteuid() != 0:
        return None
    return 61000 + slot


@functools.cache
def available() -> str:
    """Return "" if the sandbox works here, else why not."""
    for tool in ("bwrap", "prlimit") + (("setpriv",) if os.geteuid() == 0 else ()):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (apt-get install bubblewrap util-linux)"
    import tempfile

    with tempfile.TemporaryDirectory(prefix="rg-probe-") as tmp:
        uid = sandbox_uid(0)
        if uid is not None:
            os.chown(tmp, uid, uid)
        cmd, env = command(
            [sys.executable, "-c", "import robotlib, os; print(os.getuid())"],
            Path(tmp),
            {"PATH": os.defpath},
            Limits(),
            uid,
        )
        try:
            proc = subprocess.run(
                cmd, env=env, capture_output=True, text=True, timeout=60
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            return f"bwrap failed: {exc}"
        if proc.returncode != 0:
            return f"bwrap failed: {proc.stderr.strip()[-300:]}"
    return ""
