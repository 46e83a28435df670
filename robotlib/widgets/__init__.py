"""Notebook panels (ipywidgets), one module per topic, over plain tested functions.

- `mcl`: `MCLPanel`, `mcl_filter`, `run_mcl`, `plot_mcl_run` (Lab 3)
- `teleop`: `TeleopPanel`, `teleop` (Lab 0)
- `interact`: `interact`, `InteractPanel` (Labs 1 and 4: a plotting function's panel)

Import a topic's panels from its module (``from robotlib.widgets.mcl import
MCLPanel``); this package imports none of them, so a lab loads only what it
uses. Widgets sit on top: they may import any layer; nothing imports them.
"""
