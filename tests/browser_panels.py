"""Checking a notebook's panels and players in the page (tests/browser.py uses it).

`check_panels` moves the first slider of each panel and times its first
feedback (polled, and in the page: `tests.browser_feedback`) and its redraw
(a change of the pixels of its image, read through a canvas, so a
greyed-out old figure does not count), and, for one panel of each class,
its answer to a second move made while the kernel runs the first;
`check_animations` presses each player's play button and reads its frame
slider.
"""

from __future__ import annotations

import time
from pathlib import Path

from tests import browser_feedback as in_page
from tests.contention import Clock

_LOOK = """(root, moved) => {
  // the panel's images (a hash of each one's pixels, kept per image and source,
  // so an unchanged image is read once), its text and classes outside the
  // moved slider (whose own readout changes at once, no sign that the panel
  // runs), the last line of an error it shows, its status line's text
  const cache = window.__robotlibHashes || (window.__robotlibHashes = new WeakMap());
  const pixels = [];
  for (const img of root.querySelectorAll('img')) {
    if (!img.complete || !img.naturalWidth) { pixels.push('loading'); continue; }
    const key = img.currentSrc || img.src;
    const hit = cache.get(img);
    if (hit && hit.key === key) { pixels.push(hit.hash); continue; }
    const c = document.createElement('canvas');
    c.width = img.naturalWidth; c.height = img.naturalHeight;
    const g = c.getContext('2d'); g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let h = 2166136261 >>> 0;
    for (let i = 0; i < d.length; i += 7) { h = Math.imul(h ^ d[i], 16777619) >>> 0; }
    const hash = c.width + 'x' + c.height + ':' + h;
    cache.set(img, { key, hash });
    pixels.push(hash);
  }
  const inside = (n) => !!moved && moved.contains(n);
  const parts = [];
  for (const el of root.querySelectorAll('*')) {
    if (inside(el)) continue;
    parts.push(el.tagName + '.' + el.className + (el.style.opacity || ''));
  }
  const walk = document.createTreeWalker(root, NodeFilter.SHOW_TEXT);
  for (let n = walk.nextNode(); n; n = walk.nextNode()) {
    if (!inside(n)) parts.push(n.textContent);
  }
  let error = null;
  const e = root.querySelector(
    '[data-mime-type="application/vnd.jupyter.stderr"], .jp-RenderedText.jp-mod-error');
  if (e) {
    const lines = e.innerText.trim().split('\\n').filter(l => l.trim());
    error = lines.slice(-1)[0] || 'error';
  }
  const status = root.querySelector('.robotlib-status')?.textContent ?? null;
  return { pixels: pixels.join('|'), outside: parts.join('|'), error, status };
}"""
"""One look at a panel (one round trip to the page): ``pixels`` (a hash of
each image's pixels, read through a canvas, so a greyed-out old figure is
the same figure), ``outside`` (its text and classes outside the slider that
moved), ``error`` (the last line of an error it shows, else None) and
``status`` (its robotlib status line's text, else None)."""


_AT_TOP = """(h) => parseFloat(h.getAttribute('aria-valuenow'))
  >= parseFloat(h.getAttribute('aria-valuemax'))"""


def _settle(panel, slider, bound: float, quiet: float = 1.0) -> float:
    """Wait until the panel has not changed for ``quiet`` s; return the wait, s.

    A panel that draws its first figure in the background (the MCL panel)
    may still be drawing when the notebook's kernel turns idle: a change of
    its image then would not be an answer to the slider.
    """
    t0 = time.monotonic()
    state, since = None, t0
    while time.monotonic() - t0 < bound:
        look = panel.evaluate(_LOOK, slider)
        now = look["pixels"] + look["outside"]
        if now != state or "loading" in now:
            state, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet:
            break
        time.sleep(0.05)
    return since - t0


def _move(page, panel, handle, slider, bound: float, stem: str, twice=True) -> dict:
    """Move one slider one step once the panel is still; time its answer.

    With ``twice``, once the kernel has said it runs (the status line no
    longer reads the browser's own "running ..."), and before the new figure
    shows, the slider moves once more: ``busy`` times the answer to that
    second move, made while the kernel is busy with the first.
    """
    key = "ArrowLeft" if handle.evaluate(_AT_TOP) else "ArrowRight"
    settled = _settle(panel, slider, bound)  # a first run may still be drawing
    look = panel.evaluate(_LOOK, slider)
    before_pixels, before_text = look["pixels"], look["outside"]
    before_status = look["status"]
    panel.screenshot(path=f"{stem}-before.png")
    handle.focus()
    in_page.watch(panel, slider)
    clock = Clock()  # the bound in quiet seconds (tests.contention)
    t0 = clock.start
    page.keyboard.press(key)
    feedback = redraw = error = quiet = None
    page_times, busy = None, None
    while (elapsed := clock.elapsed()) < bound:
        now = time.monotonic() - t0
        look = panel.evaluate(_LOOK, slider)  # one round trip for all of it
        if feedback is None and look["outside"] != before_text:
            feedback = now
        error = look["error"]
        if error is not None:
            break
        pixels = look["pixels"]
        if pixels not in (before_pixels, "") and "loading" not in pixels:
            redraw, quiet = now, elapsed
            feedback = now if feedback is None else feedback  # the answer itself
            break
        status = look["status"]
        said = status not in (None, before_status, "running ...")
        if twice and busy is None and said:
            page_times = in_page.read(page)  # the kernel runs the first move
            in_page.watch(panel, slider)
            busy = {"at_s": time.monotonic() - t0, "status": status}
            page.keyboard.press(key)
        time.sleep(0.02)
    if busy is None:
        page_times = in_page.read(page)
    else:
        busy.update(in_page.read(page))
    if redraw is not None or error is not None:
        page.wait_for_timeout(300)
        panel.screenshot(path=f"{stem}-after.png")
    return {"key": key, "settle_s": settled, "feedback_s": feedback,
            "redraw_s": redraw, "redraw_quiet_s": quiet, "error": error,
            "in_page": page_times,
            "busy": busy, "status_line": before_status is not None}  # fmt: skip


_KIND = """(root) => {
  const p = root.querySelector('.robotlib-panel');
  const k = p && [...p.classList].find(c => c.startsWith('robotlib-kind-'));
  return k ? k.slice('robotlib-kind-'.length) : null;
}"""
"""The class of a robotlib panel (its ``robotlib-kind-<Class>`` class), else None."""


def check_panels(
    page,
    stem: Path,
    bound: float = 60.0,
    feedback_bound: float = 1.0,
    busy_done: set | None = None,
) -> list[dict]:
    """Move the first enabled slider of each panel; time feedback and redraw.

    A panel is an output holding both a slider and an image, found once
    before any slider moves (so a panel whose image is replaced while it
    redraws, or by an error, is still the same panel). Its first enabled
    slider moves one step right (left when it sits at its maximum), once the
    panel has been still for a second (``settle_s``: how long it was still
    changing). Returns, per panel, ``feedback_s`` (until the panel's text or
    classes change: a status line, a greyed figure, or the new figure
    itself; the moved slider's own readout does not count), ``redraw_s``
    (until its image's pixels change; None if they did not within ``bound``
    s), ``error`` (the last line of an error the panel shows instead, else
    None) and the slider's label; ``in_page`` the same first sign timed in
    the page (`tests.browser_feedback`: no polling latency), with
    ``running_s`` until a robotlib status line (``status_line``) read
    "running"; ``busy`` the page's times for a second move made once the
    kernel said it runs the first (None if the figure came first), and
    ``at_s`` when that was (``redraw_s - at_s``: the newest change's
    redraw, a superseded run's figure being dropped). The second move is
    made on one panel of each class (``kind``, from its ``robotlib-kind-``
    class): the first whose kernel said it runs before the figure came;
    ``busy_done`` holds the classes done so far (shared by the notebooks of
    one test), and ``busy_skipped`` says a panel's class was done before. A
    panel that redrew but showed its first sign later than
    ``feedback_bound`` s (a loaded machine) is moved once more and the
    second try counts (``tries``; ``first_try`` keeps the first); a panel
    that does not redraw, or shows an error, is not.
    """
    busy_done = set() if busy_done is None else busy_done
    results = []
    outputs = page.locator(".jp-OutputArea-output:has(.widget-slider):has(img)")
    for k, panel in enumerate(outputs.element_handles()):
        panel.scroll_into_view_if_needed()
        handles = panel.query_selector_all(
            # a disabled slider (greyed: its setting is unused) cannot move
            ".widget-slider:not(.mod-disabled)"
            " .noUi-target:not([disabled]) .noUi-handle"
        )
        if not handles:
            continue
        handle = handles[0]
        slider = handle.evaluate_handle("h => h.closest('.widget-slider')")
        label = slider.evaluate(
            "s => s.querySelector('.widget-label')?.textContent || ''"
        )
        kind = panel.evaluate(_KIND)
        twice = kind is None or kind not in busy_done
        tries = []
        for attempt in range(2):  # once more if the answer came late
            tried = _move(page, panel, handle, slider, bound, f"{stem}-panel{k}", twice)
            tries.append(tried)
            late = tried["feedback_s"] is None or tried["feedback_s"] > feedback_bound
            if tried["error"] or tried["redraw_s"] is None or not late or attempt:
                break
        if kind is not None and tries[-1]["busy"] is not None:
            busy_done.add(kind)
        results.append(
            {"panel": k, "slider": label.strip(), **tries[-1], "tries": len(tries),
             "first_try": tries[0], "kind": kind, "busy_skipped": not twice}
        )  # fmt: skip
    return results


def check_animations(page, wait: float = 2.0) -> list[dict]:
    """Press play on every jshtml player, wait once; return each one's frames.

    ``shown``: whether the player showed a frame before play was pressed.

    The players play at the same time (each on its own page timer), so one
    wait of ``wait`` s serves them all.
    """
    players = page.locator(".jp-OutputArea-output .animation").element_handles()
    frames, starts, shown = [], [], []
    for player in players:
        player.scroll_into_view_if_needed()
        image = player.query_selector("img")  # a frame, before anything is pressed
        shown.append(bool(image and image.evaluate("e => e.naturalWidth > 0")))
        frames.append(player.query_selector("input[type=range]"))
        starts.append(int(frames[-1].input_value()))
        player.query_selector("button[title='Play']").click()
    if players:
        page.wait_for_timeout(int(wait * 1000))
    return [
        {"player": k, "start": start, "after": int(f.input_value()), "shown": seen}
        for k, (start, f, seen) in enumerate(zip(starts, frames, shown, strict=True))
    ]
