"""World files written by others, and hostile ones: every real file loads, and
every malformed one raises `WorldFileError` with its file and line."""

import io
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.world import (
    MAX_EXTENT,
    WORLDS_DIR,
    WorldFileError,
    load_world,
    parse_map,
    parse_wld,
    read_map,
    read_wld,
)
from tests.fuzz.fuzz_worldfiles import check_bytes

ROOT = Path(__file__).resolve().parents[2]


def real_worlds_dir() -> Path | None:
    """``shared/real-worlds`` beside the checkout (CI), or beside its parent."""
    for base in (ROOT.parent, ROOT.parent.parent):
        d = base / "shared" / "real-worlds"
        if d.is_dir():
            return d
    return None


REAL = real_worlds_dir()


@pytest.mark.slow
def test_every_real_world_file_loads():
    if REAL is None:
        pytest.skip(f"no shared/real-worlds folder beside {ROOT} (CI has one)")
    files = sorted(p for p in REAL.iterdir() if p.suffix in (".map", ".wld"))
    assert len(files) >= 40
    for path in files:
        world = load_world(path)
        assert world.size[0] > 0 and world.size[1] > 0, path
        assert len(world.segments) + len(world.points) > 0 or path.suffix == ".wld"
        assert np.all(np.isfinite(world.obstacles)), path
    # spot checks of what the readers made of them
    eyesim = load_world(REAL / "eyesim_Straight.wld")  # floor W H, no walls
    assert eyesim.bounds == (0.0, 0.0, 5.0, 5.0) and len(eyesim.segments) == 0
    columbia = load_world(REAL / "ariacoda_columbia.map")
    assert len(columbia.points) > 60_000 and columbia.size[1] > 50


def located(exc_info, line):
    err = exc_info.value
    assert err.line == line, str(err)
    assert err.path in str(err)
    return str(err)


def test_bom_then_a_bad_byte_is_an_error_at_that_line(tmp_path):
    path = tmp_path / "bom.wld"
    path.write_bytes(b"\xef\xbb\xbfwidth 4000\nheight 3000\n; caf\xe9\n0 0 1 1\n")
    with pytest.raises(WorldFileError) as info:
        read_wld(path)
    assert "byte-order mark" in located(info, 3)
    # a BOM and good UTF-8, or Latin-1 without a BOM, still read
    path.write_bytes(b"\xef\xbb\xbfwidth 4000\nheight 3000\n; caf\xc3\xa9\n")
    assert read_wld(path).size == (4.0, 3.0)
    path.write_bytes(b"width 4000\nheight 3000\n; caf\xe9\n")
    assert read_wld(path).size == (4.0, 3.0)


@pytest.mark.parametrize(
    "wall",
    [
        "\u22121000 0 1000 1000",  # Unicode minus sign
        "\u20131000 0 1000 1000",  # en dash
        "\u0661\u0660\u0660 0 100 100",  # Arabic-Indic digits
        "\uff11\uff10\uff10 0 100 100",  # fullwidth digits
        "100 \u2212100 200 200",  # a lookalike after a good first number
    ],
)
def test_lookalike_numbers_in_walls_are_errors_not_skipped(wall):
    with pytest.raises(WorldFileError) as info:
        parse_wld(f"width 4000\nheight 4000\n{wall}\n")
    located(info, 3)
    with pytest.raises(WorldFileError) as info:
        parse_map(f"2D-Map\nMinPos: 0 0\nLINES\n{wall}\n")
    located(info, 4)


@pytest.mark.parametrize(
    "text, line",
    [
        ("width 1e300\nheight 1000\n", 1),
        ("width 20000000\nheight 1000\n", 1),  # 20 km
        ("width 1000\nheight 1000\n0 0 1e8 0\n", 3),
        ("position 1e12 0 0\n", 1),
    ],
)
def test_worlds_beyond_the_size_limit_are_refused_at_load(text, line):
    with pytest.raises(WorldFileError, match="10 km") as info:
        parse_wld(text)
    located(info, line)


def test_a_world_wider_than_the_limit_from_its_walls_is_refused():
    half = int(MAX_EXTENT * 1000 * 0.6)  # two walls 12 km apart
    text = f"{-half} 0 {-half} 1000\n{half} 0 {half} 1000\n"
    with pytest.raises(WorldFileError, match="10 km"):
        parse_wld(text)
    with pytest.raises(WorldFileError, match="10 km"):
        parse_map("2D-Map\nMinPos: -9000000 0\nMaxPos: 9000000 1000\n")
    # ARIA's inverted "no data" box of +-2^31 is still fine
    w = parse_map("2D-Map\nMinPos: 2147483647 2147483647\n"
                  "MaxPos: -2147483648 -2147483648\nLINES\n0 0 1000 0\n")  # fmt: skip
    assert w.size[0] == pytest.approx(2.0)


def test_eyesim_floor_gives_the_bounds_even_without_walls():
    w = parse_wld("# World file\nfloor_texture  Tracks/Straight.png\nfloor 5000 4000")
    assert w.bounds == (0.0, 0.0, 5.0, 4.0) and len(w.segments) == 0
    w = parse_wld("floor 2000 2000\n0 0 0 2000\n")
    assert w.bounds == (0.0, 0.0, 2.0, 2.0) and len(w.segments) == 1
    for bad in ("floor 2000\n", "floor 0 2000\n", "floor -1 2 \n", "floor a b\n"):
        with pytest.raises(WorldFileError) as info:
            parse_wld(bad)
        located(info, 1)


# -- hypothesis: mutated world files, bounded ------------------------------------
SEEDS = [
    (WORLDS_DIR / "corridor.wld").read_bytes(),
    (WORLDS_DIR / "office.map").read_bytes()[:6000],
    b"\xef\xbb\xbf2D-Map\r\nMinPos: 0 0\r\nMaxPos: 5000 5000\r\n"
    b'Cairn: Sim.BoxObstacle 100 100 30 "" ICON "b" 0 0 500 500\r\nLINES\r\n'
    b"0 0 5000 0\r\nDATA\r\n10 10\r\n",
    b"# World file\nfloor 2000 2000\n0 0 0 2000\n2000 0 2000 2000\n",
]
NASTY = [b"\xef\xbb\xbf", b"\xe2\x88\x92", b"\xd9\xa1", b"1e309", b"nan", b"\r",
         b"\n", b"\x00", b" -", b"9" * 30, b"LINES\n", b"DATA\n", b"Cairn: ",
         b"floor ", b"width ", b"\xff", b'"']  # fmt: skip


@st.composite
def mutated(draw):
    data = bytearray(draw(st.sampled_from(SEEDS)))
    for _ in range(draw(st.integers(1, 8))):
        at = draw(st.integers(0, len(data)))
        op = draw(st.sampled_from(["insert", "delete", "replace", "flip"]))
        if op == "insert":
            data[at:at] = draw(st.sampled_from(NASTY) | st.binary(max_size=6))
        elif op == "delete":
            del data[at : at + draw(st.integers(1, 40))]
        elif op == "replace" and at < len(data):
            data[at] = draw(st.integers(0, 255))
        elif at < len(data):
            data[at] ^= 1 << draw(st.integers(0, 7))
    return bytes(data)


@settings(max_examples=150, deadline=None)
@given(mutated())
def test_mutated_world_files_raise_only_world_file_errors(data):
    check_bytes(data)


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_raise_only_world_file_errors(data):
    check_bytes(data)
    check_bytes(b"2D-Map\n" + data)


def test_the_atheris_target_runs_on_the_shipped_worlds():
    for name in sorted(os.listdir(WORLDS_DIR)):
        if name.endswith((".wld", ".map")):
            check_bytes((WORLDS_DIR / name).read_bytes())
    assert read_map(io.BytesIO((WORLDS_DIR / "office.map").read_bytes())).points.size
