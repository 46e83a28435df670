"""First code cell of every lab, in a fresh Jupyter kernel: wall and CPU time.

Each notebook's first code cell runs in a new ipykernel (as JupyterLab
starts one, inline matplotlib backend) with numba's cache as it is (run
``robotlib warmup`` first for the warm figure). Prints, per notebook, the
cell's wall time, its CPU time (the kernel's process time plus its
children's) and the load average when it ran; the machine is shared, so the
CPU column is the one to compare.

    .venv/bin/python bench/bench_first_cell.py [--repeat 2] [PATH ...]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from jupyter_client.manager import start_new_kernel

ROOT = Path(__file__).resolve().parents[1]
PROBE = """
import json as _j, os as _o, resource as _r, time as _t
def _cpu():
    s, c = _r.getrusage(_r.RUSAGE_SELF), _r.getrusage(_r.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime
_w0, _c0 = _t.perf_counter(), _cpu()
"""
REPORT = (
    "print('@@' + _j.dumps([_t.perf_counter() - _w0, _cpu() - _c0,"
    " _o.getloadavg()[0]]))"
)


def first_cell(path: Path) -> str:
    nb = json.loads(path.read_text())
    return "".join(next(c for c in nb["cells"] if c["cell_type"] == "code")["source"])


def run_in_kernel(code: str, cwd: Path, profile: Path | None = None):
    env = {**os.environ, "MPLBACKEND": "module://matplotlib_inline.backend_inline"}
    km, kc = start_new_kernel(cwd=str(cwd), env=env)
    try:
        out = []

        def hook(msg):
            if msg["msg_type"] == "stream":
                out.append(msg["content"]["text"])
            elif msg["msg_type"] == "error":
                out.append("\n".join(msg["content"]["traceback"]))

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
        text = "".join(out)
        line = [ln for ln in text.splitlines() if ln.startswith("@@")]
        if not line:
            raise RuntimeError(text[-2000:])
        return tuple(json.loads(line[-1][2:]))
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("paths", nargs="*")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--profile", help="folder for each cell's cProfile stats")
    args = ap.parse_args()
    paths = [Path(p) for p in args.paths] or [
        p for d in ("solutions", "labs") for p in sorted((ROOT / d).glob("*.ipynb"))
    ]
    print(f"{'notebook':36s} {'wall s':>7s} {'CPU s':>7s} {'load':>5s}")
    for path in paths:
        for _ in range(args.repeat):
            prof = None
            if args.profile:
                Path(args.profile).mkdir(parents=True, exist_ok=True)
                stem = f"{path.parent.name}_{path.stem}.prof"
                prof = Path(args.profile).resolve() / stem
            wall, cpu, load = run_in_kernel(first_cell(path), path.parent, prof)
            name = str(path.resolve().relative_to(ROOT))
            print(f"{name:36s} {wall:7.2f} {cpu:7.2f} {load:5.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
