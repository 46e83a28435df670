"""Each gallery example runs headless, as it is, and draws its figure."""

from __future__ import annotations

import runpy
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "docs" / "examples").glob("plot_*.py"))


def test_the_gallery_has_ten_to_fifteen_examples():
    assert 10 <= len(EXAMPLES) <= 15


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_and_draws(example, tmp_path, monkeypatch):
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("ROBOTLIB_TABLE_CACHE", "off")
    plt.close("all")
    try:
        runpy.run_path(str(example), run_name="__main__")
        figures = [plt.figure(n) for n in plt.get_fignums()]
        assert figures, f"{example.name} drew no figure"
        assert all(fig.axes for fig in figures)
    finally:
        plt.close("all")
