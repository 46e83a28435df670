"""A panel's status line that answers in the browser: `StatusLine`.

A panel's kernel-side answer to a slider change (its status reading
"running ...") takes a round trip through the kernel, which may be busy with
the previous run, or slow on a loaded machine. `StatusLine` shows the
kernel's text like an ``ipywidgets.Label`` (its ``value``), and also watches
the panel's controls in the browser (an anywidget, so no JupyterLab
extension to build): the moment a control moves away from the values the
kernel last drew for, it reads "running ..." and the panel's figure greys
(class ``robotlib-pending`` on the panel), with no message to the kernel,
also while the kernel still runs an older change. The kernel's text takes
over when it next speaks (it says what it runs), and the grey goes when the
kernel has drawn the values shown (`StatusLine.answered`). Without a
browser (tests, scripts) it is a plain holder of ``value``.

Imports nothing of robotlib; panels in this package use it.
"""

from __future__ import annotations

import anywidget
import traitlets

__all__ = ["StatusLine", "front_value"]

_ESM = r"""
const read = (m) =>
  m.get("_options_labels") !== undefined ? m.get("index") : m.get("value");
const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);

function render({ model, el }) {
  el.classList.add("robotlib-status");
  const controls = {};
  let local = 0; // when a control last moved here
  let kernel = 0; // when the kernel last spoke
  const update = () => {
    const drawn = model.get("drawn") || {};
    let pending = false;
    for (const [id, m] of Object.entries(controls)) {
      if (id in drawn && !same(drawn[id], read(m))) pending = true;
    }
    const panel = el.closest(".robotlib-panel");
    if (panel) panel.classList.toggle("robotlib-pending", pending);
    el.classList.toggle("robotlib-pending", pending);
    el.textContent = pending && local >= kernel ? "running ..." : model.get("value");
  };
  const moved = () => { local = performance.now(); update(); };
  const spoke = () => { kernel = performance.now(); update(); };
  const manager = model.widget_manager;
  for (const id of model.get("controls") || []) {
    manager.get_model(id).then((m) => {
      controls[id] = m;
      m.on("change:value change:index", moved);
      update();
    });
  }
  model.on("change:value change:busy", spoke);
  model.on("change:drawn", update);
  update();
  return () => {
    for (const m of Object.values(controls)) m.off("change:value change:index", moved);
  };
}
export default { render };
"""

_CSS = """
.robotlib-status { font-size: var(--jp-widgets-font-size); line-height: 20px;
  padding: 4px 0; white-space: normal; overflow-wrap: anywhere; }
.robotlib-pending .robotlib-figure, .robotlib-pending .robotlib-figure img,
.robotlib-pending .robotlib-mcl-figure { opacity: .45; }
"""


def front_value(control):
    """Return what the browser's model of ``control`` holds for its choice.

    A selection widget (dropdown, toggle buttons) syncs its ``index``; any
    other its ``value``.
    """
    if hasattr(control, "_options_labels"):
        return control.index
    return control.value


class StatusLine(anywidget.AnyWidget):
    """A status line (like ``ipywidgets.Label``) that greys its panel at once.

    Attributes
    ----------
    value : str
        The kernel's status text.
    busy : bool
        True while the kernel runs for the newest values (its text then
        shows even while the browser's values differ from ``drawn``).
    controls : list of str
        Model ids of the controls watched in the browser.
    drawn : dict
        Model id to the value (``front_value``) the shown figure was drawn for.
    """

    _esm = _ESM
    _css = _CSS
    value = traitlets.Unicode("").tag(sync=True)
    busy = traitlets.Bool(False).tag(sync=True)
    controls = traitlets.List(traitlets.Unicode()).tag(sync=True)
    drawn = traitlets.Dict().tag(sync=True)

    def watch(self, *widgets) -> None:
        """Watch these controls (their changes grey the panel in the browser)."""
        self._watched = list(widgets)
        self.controls = [w.model_id for w in widgets]
        self.drawn = self.values()

    def values(self) -> dict:
        """Return the watched controls' values now, as `drawn` holds them."""
        return {w.model_id: front_value(w) for w in getattr(self, "_watched", [])}

    def answered(self, values: dict | None = None, busy: bool = False) -> None:
        """Say the figure now shown was drawn for ``values`` (default: now's)."""
        self.drawn = self.values() if values is None else dict(values)
        self.busy = busy
