"""Print the browser test's timings: each notebook's first cell and Run All, each panel.

The browser test (``tests/notebooks/test_browser.py``) writes
``artifacts/browser/timings.json``; this prints it as two tables: per
notebook, the first cell's and Run All's seconds in JupyterLab; per panel,
the seconds from a key press to the first sign of a run (the status line or
greyed figure, as the page sees it, and as the test's poll sees it) and to
the new image.

    .venv/bin/python bench/browser_timings.py [artifacts/browser/timings.json]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

DEFAULT = Path(__file__).resolve().parents[1] / "artifacts" / "browser" / "timings.json"


def main(argv: list[str]) -> int:
    timings = json.loads(Path(argv[0] if argv else DEFAULT).read_text())
    print(f"{'notebook':38s} {'first cell s':>12s} {'Run All s':>10s}")
    for name, t in timings.items():
        if not name.startswith(("solutions/", "labs/")):
            continue
        first, whole = t.get("first_cell_s"), t.get("run_all_s")
        cells = f"{first:12.1f}" if first is not None else f"{'-':>12s}"
        run = f"{whole:10.1f}" if whole is not None else f"{'-':>10s}"
        print(f"{name:38s} {cells} {run}")
    print()
    print(f"{'panel':46s} {'feedback s':>10s} {'in page s':>9s} {'redraw s':>9s}")
    for name, t in timings.items():
        for p in t.get("panels", []):
            label = f"{name} #{p['panel']} {p.get('kind', '')} ({p['slider']})"
            page = (p.get("in_page") or {}).get("feedback_s")
            page_s = f"{page:9.3f}" if page is not None else f"{'-':>9s}"
            redraw = p.get("redraw_s")
            redraw_s = f"{redraw:9.2f}" if redraw is not None else f"{'-':>9s}"
            print(f"{label[:46]:46s} {p['feedback_s']:10.3f} {page_s} {redraw_s}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
