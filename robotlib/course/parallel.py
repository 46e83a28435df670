"""Run a class's grading tasks at once: threads on this machine, or a Dask cluster.

- `thread_map`: ``jobs`` submissions at a time in threads of the grader (each
  submission's work happens in its sandboxed processes, so threads suffice).
- `dask_map`: each submission a task on a ``dask.distributed`` cluster (a
  local one for ``"local"``), one task per worker process at a time.
- `slot`: a grading slot no other grading process of this machine holds (a
  lock file per slot): the slot picks the sandbox's uids, so two submissions
  graded at once on one machine never share a uid (nor its process limit),
  whatever ran them.
- `Bar`: the progress bar (tqdm, or plain lines).

Imports nothing of robotlib's; the task function is passed in.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import sys
import tempfile
import threading
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

__all__ = ["Bar", "SLOTS", "dask_map", "raise_interrupt", "slot", "thread_map"]

SLOTS = 64
"""Grading slots per machine (each uses two uids, see `sandbox.sandbox_uid`)."""


@contextlib.contextmanager
def slot(prefer: int = 0):
    """Hold a free grading slot of this machine; yield its number."""
    folder = os.path.join(tempfile.gettempdir(), "robotlib-grade-slots")
    os.makedirs(folder, mode=0o700, exist_ok=True)
    while True:
        for k in [*range(prefer, SLOTS), *range(prefer)]:
            path = os.path.join(folder, f"{k}.lock")
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                os.close(fd)
                continue
            try:
                yield k
            finally:
                os.close(fd)  # releases the lock
            return
        threading.Event().wait(0.5)  # every slot busy: wait for one


class Bar:
    """A progress bar on stderr (tqdm if installed, else a line per step)."""

    def __init__(self, total: int, label: str, enabled: bool):
        self.bar = None
        if enabled:
            try:
                from tqdm import tqdm

                self.bar = tqdm(total=total, desc=label, unit="sub", file=sys.stderr)
            except ImportError:
                self.bar = None
        self.enabled, self.total, self.done, self.label = enabled, total, 0, label

    def advance(self, note: str = "") -> None:
        """Count one more finished step, with a short note."""
        self.done += 1
        if self.bar is not None:
            self.bar.set_postfix_str(note[:40])
            self.bar.update(1)
        elif self.enabled:
            sys.stderr.write(f"{self.label} {self.done}/{self.total} {note}\n")

    def close(self) -> None:
        """Close the bar."""
        if self.bar is not None:
            self.bar.close()


def raise_interrupt(signum, frame):
    """Turn SIGTERM into KeyboardInterrupt (a signal handler)."""
    raise KeyboardInterrupt(f"signal {signum}")


def _in_slot(task_fn, task, prefer: int = 0):
    with slot(prefer) as k:
        return task_fn(*task, slot=k)


def thread_map(task_fn, tasks, jobs: int, stop, on_result) -> None:
    """Run ``task_fn(*task, slot=k)`` for each task, ``jobs`` at a time.

    ``on_result`` gets each result (a dict) as it comes, unless its status
    says it was interrupted; ``stop`` (a `threading.Event`) is set at the end.
    """
    pool = ThreadPoolExecutor(max_workers=jobs)
    try:
        pending = {
            pool.submit(_in_slot, task_fn, t, i % jobs) for i, t in enumerate(tasks)
        }
        while pending:
            finished, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for fut in finished:
                data = fut.result()
                if not str(data.get("status", "")).startswith("interrupted"):
                    on_result(data)
    finally:
        stop.set()  # running submissions end their processes and return
        pool.shutdown(wait=True, cancel_futures=True)


def dask_map(task_fn, tasks, scheduler: str, jobs: int, stop, on_result, failed):
    """Run the tasks on a Dask cluster (``"local"``: one of ``jobs`` workers here).

    ``task[0]`` names the task; a task whose worker died gives
    ``failed(name, exc)`` instead of a result.
    """
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError as exc:
        raise ImportError(
            "--scheduler needs dask.distributed: pip install 'robotlib[grade-dask]'"
        ) from exc
    cluster = None
    if scheduler == "local":
        cluster = LocalCluster(
            n_workers=jobs,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            memory_limit=0,  # the sandboxes have their own limits
        )
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        futures = {
            client.submit(_in_slot, task_fn, t, pure=False, key=f"grade-{i}"): t[0]
            for i, t in enumerate(tasks)
        }
        for fut in as_completed(list(futures)):
            if stop.is_set():
                client.cancel(list(futures))
                break
            try:
                data = fut.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker, not the class
                failed(futures[fut], exc)
                continue
            on_result(data)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
