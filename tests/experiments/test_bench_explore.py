"""``robotlib bench explore`` runs, writes JSON, refuses bad team sizes."""

import argparse
import json

import pytest

from robotlib.experiments import bench_explore


def _parse(*argv):
    parser = argparse.ArgumentParser()
    bench_explore.add_arguments(parser)
    return parser.parse_args(list(argv))


def test_team_sizes_are_checked():
    assert _parse("--robots", "1,3").robots == [1, 3]
    with pytest.raises(SystemExit):
        _parse("--robots", "1,9")
    with pytest.raises(SystemExit):
        _parse("--robots", "two")


@pytest.mark.slow
def test_a_short_bench_writes_its_table(tmp_path, capsys):
    out = tmp_path / "explore.json"
    args = _parse(
        "--robots", "1,2", "--seeds", "1", "--worlds", "gen-hall",
        "--max-time", "60", "--json", str(out),
    )  # fmt: skip
    assert bench_explore.run(args) == 0
    doc = json.loads(out.read_text())
    assert [r["robots"] for r in doc["table"]] == [1, 2]
    assert len(doc["runs"]) == 2
    for r in doc["runs"]:
        assert 0.0 < r["explored"] <= 1.0
    assert "load average" in capsys.readouterr().out
