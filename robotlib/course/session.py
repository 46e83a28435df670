"""Grade one submission: two sandboxed processes, the grader relaying between them.

The student process (their cells) and the check process (the instructor's
checks) never share memory, files or a PID namespace; every message goes
through `run_submission`, which also keeps the time:

- a student cell (at start-up) running longer than the cell limit is
  killed and the process restarted without it;
- a call into the student's code running longer than the cell limit is
  killed: the check fails ("timed out"), the student process is restarted
  for the next checks; a student process that dies (``os._exit``, a crash,
  memory) fails the call in flight and is restarted, a few times at most;
- a check whose time (its own and its calls into the student's code)
  passes its limit is killed and the check process restarted from the
  next check; the limit is ``budgets[gid]``: `grade` scales it from the
  solution's CPU time for that check, and records each check's time in
  ``Outcome.checks[gid]["cpu"]``;
- the submission's total CPU time (start-ups, restarts and checks) is
  bounded: what has not run by then fails with that reason.

Every limit is charged time (`processes.Clock`): CPU time of the process
tree, or for the student's code wall time between samples not spent waiting
for a CPU, so a busy machine or a classmate's CPU hogs cost a student
nothing. Wall time only bounds it from behind
(``Options.backstop`` times each limit): a submission that reaches it
is "overloaded" (to grade again), never scored. A student process running
more than `cpu.HOGS` busy processes at once is flagged; its slot's control
group holds it to one core (without one, it is slowed down). One that runs
up to its process limit (a fork bomb, a flood of processes) is flagged.

Killing a sandbox's first process ends every process in it (PID namespace);
without the sandbox every process carrying the job's id is killed.
Imports `cpu`, `sandbox`, `processes` and `plan`.
"""

from __future__ import annotations

import os
import queue
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import cpu
from . import sandbox as sb
from .cpu import descendants as _descendants  # noqa: F401 - the tests' helpers use it
from .plan import LabPlan
from .processes import JOB_ENV, Clock, Options, Proc, kill_job

_OVERLOADED = "the machine was too busy to finish in time: re-grade"

__all__ = ["Options", "Outcome", "run_submission", "JOB_ENV", "kill_job"]


@dataclass
class Outcome:
    """What the processes reported for one submission."""

    checks: dict[str, dict] = field(default_factory=dict)
    cells: dict[str, dict] = field(default_factory=dict)
    tripwires: list[tuple[str, str | None, str]] = field(default_factory=list)
    status: str = "ok"
    restarts: int = 0
    log: str = ""
    flags: list[str] = field(default_factory=list)
    cpu: float = 0.0  # CPU time of all its processes, s


def run_submission(
    plan: LabPlan,
    cells: list[dict],
    opts: Options,
    slot: int = 0,
    budgets: dict[str, float] | None = None,
    modules: dict[str, str] | None = None,
) -> Outcome:
    """Run ``cells`` (the student's) against ``plan``'s checks.

    ``budgets`` maps a check's grade id to its limit in charged time, s
    (its own time and its calls; default ``opts.cell_timeout``);
    ``modules`` (file name to source) are written beside the student's
    cells, where they can import them. Never raises for anything the
    submission does.
    """
    budgets = budgets or {}
    out = Outcome()
    t_start = time.monotonic()
    root = Path(__import__("tempfile").mkdtemp(prefix="rg-", dir=opts.workroot))
    os.chmod(root, 0o711)
    events: queue.Queue = queue.Queue()
    uid = sb.sandbox_uid(2 * slot) if opts.sandbox else None
    cuid = sb.sandbox_uid(2 * slot + 1) if opts.sandbox else None
    if opts.warm:  # the solution's two processes both write the shared cache
        cuid = uid
    logf = open(root / "log.txt", "wb")  # noqa: SIM115
    skip: set[str] = set()
    gen = {"student": 0, "check": 0}
    procs: dict[str, Proc | None] = {"student": None, "check": None}
    st = {"ready": False, "cell": None, "pending": None, "queued": None}
    ck = {"cur": None, "clock": None, "index": 0, "done": False, "restarts": 0}
    ck["calls"] = 0.0  # charged time of the current check's finished calls
    gids = [c["gid"] for c in plan.check_specs]
    share = cpu.Share(slot, 2 * opts.limits.processes + 64, opts.sandbox)
    made: list[Proc] = []  # every process started, for the CPU time spent
    hog = {"seen": 0, "flagged": False, "crowd": False}

    def start_student():
        gen["student"] += 1
        spec = {
            "setup": plan.setup,
            "cells": [c for c in cells if c["id"] not in skip],
            "writes": plan.writes,
        }
        scratch = root / f"student{gen['student']}"
        scratch.mkdir()
        for name, source in (modules or {}).items():  # names checked: x.py
            (scratch / name).write_text(source, encoding="utf-8")
        procs["student"] = Proc(
            "student", spec, scratch, opts, uid, events, gen["student"], logf, share
        )
        made.append(procs["student"])
        st.update(ready=False, cell=None)

    def start_check(index: int):
        gen["check"] += 1
        spec = {
            "setup": plan.setup,
            "defs": plan.defs,
            "checks": plan.check_specs,
            "names": plan.names,
            "answers": plan.answers,
            "start": index,
        }
        scratch = root / f"check{gen['check']}"
        procs["check"] = Proc(
            "check", spec, scratch, opts, cuid, events, gen["check"], logf, share
        )
        made.append(procs["check"])
        ck.update(cur=None, clock=Clock.start(procs["check"], False), index=index)

    def fail_call(error: str):
        if st["pending"] is not None:
            procs["check"].post({"op": "result", "ok": False, "error": error})
            st["pending"] = None

    def student_died(why: str):
        if procs["student"] is None:
            return  # given up already: a late event of the last process
        procs["student"].kill()
        watch_hogs(procs["student"], final=True)
        if not opts.keep:  # what it wrote goes now, not at the end
            shutil.rmtree(procs["student"].scratch, ignore_errors=True)
        out.restarts += 1
        if st["cell"] is not None:
            cid = st["cell"][0]
            skip.add(cid)
            out.cells.setdefault(cid, {"status": "error", "error": why})
        fail_call(why)
        if out.restarts <= opts.restarts:
            start_student()
        else:
            procs["student"] = None
            st.update(ready=False, cell=None)
            if st["queued"] is not None:
                st["queued"] = None
                procs["check"].post(
                    {
                        "op": "result",
                        "ok": False,
                        "error": "not run: your code "
                        "kept hanging or crashing the process",
                    }  # fmt: skip
                )

    def check_time(fresh: bool = False) -> float:
        """Charged time of the current check so far: its own and its calls."""
        own = ck["clock"].charged(fresh) if ck["cur"] is not None else 0.0
        return own + ck["calls"]

    def budget() -> float:
        return budgets.get(ck["cur"], opts.cell_timeout)

    def timed_out(limit: float) -> str:
        if limit <= opts.cell_timeout:
            return f"timed out after {limit:g} s"
        slower = f"{opts.slower:g} times the solution's"
        return f"timed out after {limit:.0f} s of CPU time ({slower})"

    def forward(item):
        header, payload, sent = item
        base = check_time()  # the check's time before this call
        st["pending"] = (header, payload, base, Clock.start(procs["student"]), sent)
        if not procs["student"].post(header, payload):
            student_died("the process of your code had ended")

    def verdict(clock: Clock, limit: float, base: float = 0.0) -> str | None:
        """Return "over" past the limit, "overloaded" past the backstop, else None.

        ``base``: time already charged against the same limit.
        """
        now = time.monotonic()
        if base + clock.charged() > limit:
            return "over"
        return "overloaded" if clock.elapsed(now) > limit * opts.backstop else None

    def overloaded():
        out.status = "overloaded"
        for gid in gids:
            out.checks.setdefault(gid, {"status": "failed", "error": _OVERLOADED})

    def watch_hogs(proc: Proc | None, final: bool = False):
        """Flag (once) a student process running CPU hogs; slow it down if need be.

        Its slot's control group holds it to one core already; without one
        its processes get the lowest priority (`cpu.Share.tame`).

        Seen in two samples after its first second (the sandbox's wrappers
        start it), or still running when the process is ended (``final``:
        an honest one is idle then).
        """
        if proc is None or proc.popen is None or proc.last.running <= cpu.HOGS:
            return
        if not final and time.monotonic() - proc.started < 1.0:
            return
        if not (proc.alive or final):
            return  # its last sample, counted already
        hog["seen"] += 2 if final else 1
        if hog["seen"] >= 2:
            if proc.alive and not share.groups:
                cpu.Share.tame(proc.popen.pid)
            if not hog["flagged"]:
                hog["flagged"] = True
                how = "held to one core" if share.groups else "slowed down"
                out.flags.append(
                    f"ran {proc.last.running} busy processes at once "
                    f"(CPU hogs): {how}, their CPU time charged to it"
                )

    def watch_processes(proc: Proc | None):
        """Flag (once) a student process tree that ran up to its process limit."""
        most = opts.limits.processes
        if proc is None or proc.last.processes < 0.9 * most or hog["crowd"]:
            return
        hog["crowd"] = True
        out.flags.append(
            f"started {proc.last.processes} processes at once (the limit is {most})"
        )

    sampled = weighed = 0.0
    try:
        start_student()
        start_check(0)
        while not ck["done"]:
            now = time.monotonic()
            if opts.stop is not None and opts.stop.is_set():
                out.status = "interrupted"
                break
            if now - sampled >= 0.25:
                sampled = now
                for p in procs.values():
                    if p is not None:
                        p.sample()
                watch_hogs(procs["student"])
                watch_processes(procs["student"])
            if now - weighed >= 1.0 and procs["student"] is not None:
                weighed = now
                p = procs["student"]
                if sb.scratch_bytes(p.scratch) - p.base > opts.limits.disk:
                    mib = opts.limits.disk / (1 << 20)
                    note = f"wrote more than {mib:g} MiB to disk"
                    if note not in out.flags:
                        out.flags.append(note)
                    student_died(f"your code {note}")
                    continue
            spent = sum(p.last.cpu for p in made)
            if spent > opts.timeout or now - t_start > opts.timeout * opts.backstop:
                over = spent <= opts.timeout
                why = (
                    _OVERLOADED
                    if over
                    else f"the submission's CPU time limit ({opts.timeout:g} s) ran out"
                )
                out.status = "overloaded" if over else "timed out"
                for gid in gids:
                    out.checks.setdefault(
                        gid, {"status": "failed", "error": f"not run: {why}"}
                    )
                break
            verdicts = []
            if st["cell"] is not None:
                verdicts.append(verdict(st["cell"][1], opts.cell_timeout))
            if st["pending"] is not None:
                limit = budget()
                verdicts.append(verdict(st["pending"][3], limit, st["pending"][2]))
            if "overloaded" in verdicts:
                overloaded()
                break
            if "over" in verdicts:
                why = timed_out(budget() if st["cell"] is None else opts.cell_timeout)
                student_died(why)
                continue
            busy = st["pending"] is not None or st["queued"] is not None
            limit = budget() if ck["cur"] is not None else 3 * opts.cell_timeout
            late = None if busy else verdict(ck["clock"], limit, ck["calls"])
            if late == "overloaded":
                overloaded()
                break
            if late == "over":
                gid = ck["cur"] or gids[min(ck["index"], len(gids) - 1)]
                out.checks.setdefault(
                    gid,
                    {"status": "failed", "error": timed_out(limit)},
                )
                procs["check"].kill()
                nxt = gids.index(gid) + 1 if gid in gids else len(gids)
                if nxt >= len(gids):
                    break
                start_check(nxt)
                continue
            try:
                role, g, header, payload, arrived = events.get(timeout=0.2)
            except queue.Empty:
                continue
            if g != gen[role] or procs[role] is None:
                continue  # from a process already replaced or given up
            op = header.get("op")
            if role == "student":
                if op == "cell":
                    if header.get("status") == "start":
                        clock = Clock.start(procs["student"])
                        st["cell"] = (str(header.get("id")), clock)
                    else:
                        cid = str(header.get("id"))
                        out.cells.setdefault(cid, header)
                        st["cell"] = None
                elif op == "ready":
                    st.update(ready=True, cell=None)
                    if st["queued"] is not None:
                        item, st["queued"] = st["queued"], None
                        # the wait for the restart is not the check's time
                        ck["clock"] = Clock.start(procs["check"], False)
                        forward((*item[:2], time.monotonic()))
                elif op == "tripwire":
                    hit = (
                        str(header.get("function")),
                        header.get("exercise"),
                        str(header.get("via") or ""),
                    )
                    if hit not in out.tripwires:
                        out.tripwires.append(hit)
                elif op == "result" and st["pending"] is not None:
                    call, sent = st["pending"][3:]
                    # the check waits from its call's frame to this reply's relay
                    ck["clock"].paused += time.monotonic() - sent
                    ck["calls"] += call.charged(fresh=True)
                    st["pending"] = None
                    procs["check"].post(
                        {
                            "op": "result",
                            "ok": bool(header.get("ok")),
                            "error": str(header.get("error", ""))[:3000],
                        },  # fmt: skip
                        payload,
                    )
                elif op == "eof":
                    student_died("your code ended or crashed the process")
            else:
                if op == "ready":
                    ck["clock"] = Clock.start(procs["check"], False)
                elif op == "begin":
                    ck["cur"] = header.get("gid")
                    ck["clock"] = Clock.start(procs["check"], False)
                    ck["calls"] = 0.0
                elif op == "end":
                    header["cpu"] = round(check_time(fresh=True), 3)
                    out.checks.setdefault(str(header.get("gid")), header)
                    ck["cur"], ck["clock"] = None, Clock.start(procs["check"], False)
                    ck["calls"] = 0.0
                elif op in ("call", "get"):
                    item = (header, payload, arrived)
                    if procs["student"] is None:
                        procs["check"].post(
                            {
                                "op": "result",
                                "ok": False,
                                "error": "not run: your "
                                "code kept hanging or crashing the process",
                            }  # fmt: skip
                        )
                    elif st["ready"]:
                        forward(item)
                    else:  # its time so far kept; the wait not charged
                        ck["calls"] = check_time()
                        st["queued"] = item
                elif op == "done":
                    ck["done"] = True
                elif op == "eof":
                    gid = ck["cur"]
                    procs["check"].kill()
                    if gid is None and not out.checks:
                        out.status = "set-up failed"
                        break
                    if gid is not None:
                        out.checks.setdefault(
                            gid,
                            {
                                "status": "failed",
                                "error": "the check's process ended (out of memory?)",
                            },  # fmt: skip
                        )
                    done = [g2 for g2 in gids if g2 in out.checks]
                    nxt = max(gids.index(g2) for g2 in done) + 1 if done else 0
                    ck["restarts"] += 1
                    if nxt >= len(gids) or ck["restarts"] > opts.restarts:
                        break
                    start_check(nxt)
    finally:
        for p in procs.values():
            if p is not None:
                p.kill()
        watch_hogs(procs["student"], final=True)
        watch_processes(procs["student"])
        share.close()
        out.cpu = sum(p.last.cpu for p in made)
        logf.close()
        try:
            out.log = (root / "log.txt").read_text(errors="replace")[-3000:]
        except OSError:
            pass
        if not opts.keep:
            shutil.rmtree(root, ignore_errors=True)
    for gid in gids:
        out.checks.setdefault(gid, {"status": "failed", "error": "not run"})
    return out
