"""Where code runs: the IPython shell, and whether it is a Jupyter kernel.

A leaf (layer 0): imports nothing of robotlib, and IPython only if something
else already imported it. The notebook set-up and the widgets both ask here.
"""

from __future__ import annotations

import sys

__all__ = ["in_kernel", "ipython_shell"]


def ipython_shell():
    """Return the running IPython shell, or None.

    Also from a widget's callback or a worker thread, where the builtin
    ``get_ipython`` is gone (IPython adds it only while a cell runs).
    """
    ipython = sys.modules.get("IPython")
    return None if ipython is None else ipython.get_ipython()


def in_kernel() -> bool:
    """Return True inside a Jupyter kernel (where a frontend can send changes)."""
    return getattr(ipython_shell(), "kernel", None) is not None
