"""Timing a panel's first sign of a run inside the page (tests/browser.py uses it).

Polling the page from playwright adds its own latency (each look at a
panel's image and text takes tens of ms on a loaded machine), so the time
from a key press to the panel's first change is also taken in the page: a
keydown listener notes when the key went down, a MutationObserver when the
panel first changed outside the moved slider (``feedback_ms``) and when its
status line (``.robotlib-status``, robotlib's panels) first read "running"
(``running_ms``), both on the page's clock.
"""

from __future__ import annotations

_WATCH = """(root, moved) => {
  const rec = { t0: null, feedback_ms: null, running_ms: null };
  window.__robotlibFeedback = rec;
  document.addEventListener("keydown", () => { rec.t0 = performance.now(); },
                            { capture: true, once: true });
  const status = root.querySelector(".robotlib-status");
  const before = status ? status.textContent : null;
  const obs = new MutationObserver((muts) => {
    if (rec.t0 === null) return;
    const dt = performance.now() - rec.t0;
    for (const m of muts) {
      const n = m.target.nodeType === 1 ? m.target : m.target.parentElement;
      if (n && !moved.contains(n) && rec.feedback_ms === null) rec.feedback_ms = dt;
    }
    const text = status ? status.textContent : null;
    const running = status && text !== before && text.startsWith("running");
    if (rec.running_ms === null && running) rec.running_ms = dt;
    const done = rec.feedback_ms !== null && (rec.running_ms !== null || !status);
    if (done) obs.disconnect();
  });
  obs.observe(root, { subtree: true, childList: true, attributes: true,
                      characterData: true });
}"""


def watch(panel, slider) -> None:
    """Start timing the panel's answer to the next key press (in the page)."""
    panel.evaluate(_WATCH, slider)


def read(page) -> dict:
    """Return the page's timings of the last `watch`: s, or None if not seen."""
    rec = page.evaluate("() => window.__robotlibFeedback || {}")
    return {
        k.replace("_ms", "_s"): (None if rec.get(k) is None else rec[k] / 1000.0)
        for k in ("feedback_ms", "running_ms")
    }
