"""First code cell, and Run All, of every lab in a fresh Jupyter kernel.

Each notebook's first code cell runs in a new ipykernel (as JupyterLab
starts one, inline matplotlib backend) with numba's cache as it is (run
``robotlib warmup`` first for the warm figure), or with an empty one
(``--cold``: a fresh ``NUMBA_CACHE_DIR`` per notebook, as on a machine that
skipped the set-up). Prints, per notebook, the cell's wall time, its CPU time
(the kernel's process time plus its children's) and the load average when
it ran; the machine is shared, so the CPU column is the one to compare.
``--run-all`` then runs the notebook's other code cells in order, one
execute each as JupyterLab's Run All sends them, stopping at the first
error as it does, and adds the whole run's wall and CPU time.

    .venv/bin/python bench/bench_first_cell.py [--repeat 2] [--cold] [--run-all] [PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

from jupyter_client.manager import start_new_kernel

ROOT = Path(__file__).resolve().parents[1]
PROBE = """
import json as _bench_json, os as _bench_os, resource as _bench_r, time as _bench_t
def _bench_cpu():
    s = _bench_r.getrusage(_bench_r.RUSAGE_SELF)
    c = _bench_r.getrusage(_bench_r.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime
_bench_w0, _bench_c0 = _bench_t.perf_counter(), _bench_cpu()
"""
# names a notebook's own cells are unlikely to rebind (Lab 5 has its own ``_j``)
REPORT = (
    "print('@@' + _bench_json.dumps([_bench_t.perf_counter() - _bench_w0,"
    " _bench_cpu() - _bench_c0, _bench_os.getloadavg()[0]]))"
)


def code_cells(path: Path) -> list[str]:
    """The notebook's code cells' sources, in order."""
    nb = json.loads(path.read_text())
    return ["".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code"]


def run_in_kernel(
    cells: list[str],
    cwd: Path,
    profile: Path | None = None,
    run_all: bool = False,
    cache: str | None = None,
):
    """Time the first cell (and with ``run_all`` every cell) in a new kernel.

    Returns ``(wall s, CPU s, load)`` of the first cell, then, with
    ``run_all``, ``(wall s, CPU s, cells run, error name or None)`` of the
    whole run, timed from before the first cell.
    """
    env = {**os.environ, "MPLBACKEND": "module://matplotlib_inline.backend_inline"}
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    km, kc = start_new_kernel(cwd=str(cwd), env=env)
    try:
        out = []

        def hook(msg):
            if msg["msg_type"] == "stream":
                out.append(msg["content"]["text"])
            elif msg["msg_type"] == "error":
                out.append("\n".join(msg["content"]["traceback"]))

        code = cells[0]

        # one execute: the probe, the cell and the report (as one cell's run)
        if profile is not None:  # the cell under cProfile, its stats to a file
            code = (
                f"import cProfile as _cp\n_pr = _cp.Profile()\n_pr.enable()\n"
                f"exec(compile({code!r}, 'cell', 'exec'))\n_pr.disable()\n"
                f"_pr.dump_stats({str(profile)!r})"
            )
        kc.execute_interactive(
            PROBE + "\n" + code + "\n" + REPORT, output_hook=hook, timeout=300
        )
        first = _report(out)
        if not run_all:
            return first
        error, ran = None, 1
        for cell in cells[1:]:
            reply = kc.execute_interactive(cell, output_hook=hook, timeout=900)
            if reply["content"]["status"] != "ok":
                error = reply["content"].get("ename", "error")
                break
            ran += 1
        out.clear()
        kc.execute_interactive(REPORT, output_hook=hook, timeout=60)
        wall, cpu, _ = _report(out)
        return first, (wall, cpu, ran, error)
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)


def _report(out: list[str]) -> tuple:
    text = "".join(out)
    line = [ln for ln in text.splitlines() if ln.startswith("@@")]
    if not line:
        raise RuntimeError(text[-2000:])
    return tuple(json.loads(line[-1][2:]))


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("paths", nargs="*")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--profile", help="folder for each cell's cProfile stats")
    ap.add_argument("--cold", action="store_true", help="an empty numba cache each")
    ap.add_argument("--run-all", action="store_true", help="then every other cell")
    args = ap.parse_args()
    paths = [Path(p) for p in args.paths] or [
        p for d in ("solutions", "labs") for p in sorted((ROOT / d).glob("*.ipynb"))
    ]
    head = f"{'notebook':36s} {'wall s':>7s} {'CPU s':>7s} {'load':>5s}"
    if args.run_all:
        head += f" {'all wall':>9s} {'all CPU':>8s} {'cells':>6s}  stopped at"
    print(head)
    for path in paths:
        for _ in range(args.repeat):
            prof = None
            if args.profile:
                Path(args.profile).mkdir(parents=True, exist_ok=True)
                stem = f"{path.parent.name}_{path.stem}.prof"
                prof = Path(args.profile).resolve() / stem
            cells = code_cells(path)
            with tempfile.TemporaryDirectory(prefix="numba-cold-") as tmp:
                cache = tmp if args.cold else None
                got = run_in_kernel(cells, path.parent, prof, args.run_all, cache)
            first, whole = got if args.run_all else (got, None)
            name = str(path.resolve().relative_to(ROOT))
            line = f"{name:36s} {first[0]:7.2f} {first[1]:7.2f} {first[2]:5.1f}"
            if whole is not None:
                wall, cpu, ran, error = whole
                line += f" {wall:9.1f} {cpu:8.1f} {ran:3d}/{len(cells):<3d} "
                line += f" {error or '-'}"
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
