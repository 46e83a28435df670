"""Tests of robotlib.world's .wld and .map files: parsing, writing, errors."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robotlib.world import (
    World,
    WorldFileError,
    format_map,
    format_wld,
    parse_map,
    parse_wld,
    read_map,
    read_wld,
    read_world,
    write_map,
    write_wld,
)

SETTINGS = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)

WLD = """\
; a small test world
width 10000
height 6000
position 1000 2000 90
0 0 10000 0
0 0 0 6000
5000 1000 5000 5000 ; a wall with a comment
"""

MAP = """\
2D-Map
MinPos: -100 -200
MaxPos: 8000 6000
NumPoints: 2
LineMinPos: 0 0
LineMaxPos: 8000 5000
NumLines: 2
Resolution: 100
Cairn: RobotHome 1000 1500 -45 "" ICON "home"
LINES
0 0 8000 0
0 0 0 5000
DATA
100 200
300 400
"""


# --------------------------------------------------------------------------
# .wld


def test_wld_golden():
    w = parse_wld(WLD)
    np.testing.assert_array_equal(
        w.segments, [[0, 0, 10, 0], [0, 0, 0, 6], [5, 1, 5, 5]]
    )
    assert w.bounds == (0.0, 0.0, 10.0, 6.0)
    assert w.start == (1.0, 2.0, math.pi / 2)
    assert w.points.shape == (0, 2)


def test_wld_crlf_no_final_newline_trailing_blanks_and_unknown_keywords():
    text = WLD.replace("\n", "  \r\n").rstrip() + "\r\nfrobnicate 1 2 3\r\nlabel x"
    assert parse_wld(text) == parse_wld(WLD)
    cr_only = WLD.replace("\n", "\r")
    assert parse_wld(cr_only) == parse_wld(WLD)


def test_wld_keywords_are_case_insensitive_and_position_may_omit_theta():
    w = parse_wld("WIDTH 4000\nHeight 3000\nPosition 1000 1000\n")
    assert w.bounds == (0.0, 0.0, 4.0, 3.0)
    assert w.start == (1.0, 1.0, 0.0)
    assert len(w.segments) == 0


def test_wld_fractional_and_signed_numbers():
    w = parse_wld("+1.5 -2 3e3 .5\n")
    np.testing.assert_array_equal(w.segments, [[0.0015, -0.002, 3.0, 0.0005]])


def test_wld_heading_wraps():
    assert parse_wld("position 0 0 270\n0 0 1 1").start[2] == pytest.approx(
        -math.pi / 2
    )
    assert parse_wld("position 0 0 -180\n0 0 1 1").start[2] == pytest.approx(math.pi)


def test_wld_bounds_grow_over_walls_outside_the_declared_size():
    # a centred world: the declared width/height does not cover the walls
    w = parse_wld("width 4000\nheight 2000\n-1000 -500 1000 500\n")
    assert w.bounds == (-1.0, -0.5, 4.0, 2.0)


def test_wld_without_size_gets_the_default_margin():
    w = parse_wld("0 0 2000 1000\n")
    assert w.bounds == (-0.5, -0.5, 2.5, 1.5)


def test_wld_origin_extension():
    w = parse_wld("origin -3000 -1000\nwidth 6000\nheight 2000\n")
    assert w.bounds == (-3.0, -1.0, 3.0, 1.0)
    assert w.start == (0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("text", "line", "fragment"),
    [
        ("width 100\n0 0 a b\n", 2, "4 numbers"),
        ("width 100\n\n0 0 10\n", 3, "4 numbers"),
        ("0 0 10 10 10\n", 1, "4 numbers"),
        ("0 0 10 nan\n", 1, "4 numbers"),
        ("0 0 10 inf\n", 1, "4 numbers"),
        ("0 0 10 1_0\n", 1, "4 numbers"),
        ("0 0 10 1e999\n", 1, "out of range"),
        ("3a 4 5 6\n", 1, "4 numbers"),
        ("width\n", 1, "width"),
        ("width -5\n", 1, "positive"),
        ("height 0\n", 1, "positive"),
        ("height 10 20\n", 1, "height"),
        ("; c\nposition 1\n", 2, "position x y th"),
        ("position 1 2 x\n", 1, "position x y th"),
        ("origin 1\n", 1, "origin x y"),
    ],
)
def test_wld_malformed_records_name_file_and_line(text, line, fragment):
    with pytest.raises(WorldFileError) as err:
        parse_wld(text, source="bad.wld")
    assert err.value.line == line
    assert err.value.path == "bad.wld"
    assert str(err.value).startswith(f"bad.wld:{line}: ")
    assert fragment in str(err.value)


@pytest.mark.parametrize(
    "text", ["", "\n\n", "; only a comment\n; and another", "foo bar"]
)
def test_wld_empty_file_is_an_error(text):
    with pytest.raises(WorldFileError, match="not a world file") as err:
        parse_wld(text, source="empty.wld")
    assert err.value.line is None


def test_wld_size_without_walls_is_an_open_world():
    w = parse_wld("width 5000\nheight 5000\n")
    assert len(w.segments) == 0
    assert w.is_free(w.start[:2])


def test_wld_error_message_example():
    text = "\n".join(["; header"] * 11 + ["a b"] + [""])
    # 'a b' starts with a letter: an unknown keyword, ignored; a numeric start is not
    assert parse_wld(text + "0 0 1 1") is not None
    text = "\n".join(["; header"] * 11 + ["1 b"])
    with pytest.raises(WorldFileError) as err:
        parse_wld(text, source="corridor.wld")
    assert str(err.value).startswith("corridor.wld:12: expected 4 numbers")
    assert "'1 b'" in str(err.value)


def test_read_wld_names_the_file(tmp_path):
    p = tmp_path / "broken.wld"
    p.write_bytes(b"width 1000\r\nheight 1000\r\n\r\n1 2 3\r\n")
    with pytest.raises(WorldFileError) as err:
        read_wld(p)
    assert err.value.line == 4
    assert "broken.wld:4:" in str(err.value)
    with pytest.raises(WorldFileError, match="broken.wld:4:"):
        read_world(p)


def test_read_world_dispatches_on_extension(tmp_path):
    (tmp_path / "a.wld").write_text(WLD)
    (tmp_path / "b.MAP").write_text(MAP)
    a, b = read_world(tmp_path / "a.wld"), read_world(tmp_path / "b.MAP")
    assert a == parse_wld(WLD) and a.name == "a" and a.source == tmp_path / "a.wld"
    assert b == parse_map(MAP) and b.name == "b"
    (tmp_path / "c.txt").write_text(WLD)
    with pytest.raises(WorldFileError, match="extension"):
        read_world(tmp_path / "c.txt")
    with pytest.raises(FileNotFoundError):
        read_world(tmp_path / "missing.wld")


def test_read_accepts_open_files_and_non_utf8_bytes(tmp_path):
    p = tmp_path / "latin.map"
    p.write_bytes(MAP.replace('"home"', '"caf\xe9"').encode("latin-1"))
    with open(p, "rb") as f:
        assert read_map(f) == parse_map(MAP)


def test_write_wld_refuses_points(tmp_path):
    w = World(np.zeros((0, 4)), points=[[1.0, 1.0]])
    with pytest.raises(ValueError, match="point"):
        write_wld(w, tmp_path / "x.wld")


def test_write_wld_comment_and_reread(tmp_path):
    w = parse_wld(WLD)
    write_wld(w, tmp_path / "x.wld", comment="line one\nline two")
    text = (tmp_path / "x.wld").read_text()
    assert text.startswith("; line one\n; line two\n")
    assert read_wld(tmp_path / "x.wld") == w


# --------------------------------------------------------------------------
# .map


def test_map_golden():
    w = parse_map(MAP)
    np.testing.assert_array_equal(w.segments, [[0, 0, 8, 0], [0, 0, 0, 5]])
    np.testing.assert_array_equal(w.points, [[0.1, 0.2], [0.3, 0.4]])
    assert w.bounds == (-0.1, -0.2, 8.0, 6.0)
    assert w.start == (1.0, 1.5, -math.pi / 4)


@pytest.mark.parametrize(
    "mutate",
    [
        lambda t: t.replace("\n", "\r\n"),  # CRLF
        lambda t: t.rstrip("\n"),  # no final newline
        lambda t: t.replace("Resolution: 100\n", ""),  # no resolution
        lambda t: t.replace("Resolution: 100", "Resolution: 0"),
        lambda t: t.replace("\n", "   \n"),  # trailing spaces
        lambda t: t.replace("\n", " \t\r\n"),
        lambda t: t.replace("NumLines: 2", "NumLines: 17"),  # advisory counts
        lambda t: t.replace("NumPoints: 2", "NumPoints: 0"),
        lambda t: t.replace("2D-Map\n", "2D-Map-Ex2\nSources: x\nFooBar: 1 2 3\n"),
        lambda t: t.replace("2D-Map\n", "2D-Map-Ex\nMapInfo: ObjectType Name=Foo\n"),
        lambda t: t.replace("LINES\n", 'Cairn: Goal 1 2 3.7 "a b" ICON "g"\nLINES\n'),
        lambda t: t.replace(
            "LINES\n", 'Cairn: ForbiddenArea 0 0 0 "" ICON ""\nLINES\n'
        ),
        lambda t: t + "SCAN\nwhatever 1 2\n\nanything\n",  # unknown section
        lambda t: t.replace("DATA\n", "SCAN\n1 2 3 4 5 6\nDATA\n"),
        lambda t: "\ufeff" + t,  # byte-order mark
        lambda t: "\n\n" + t,  # blank lines before the magic
        lambda t: t.replace("Resolution: 100", "Resolution:"),
    ],
)
def test_map_tolerated_quirks(mutate):
    assert parse_map(mutate(MAP)) == parse_map(MAP)


def test_map_fractional_cairn_theta():
    w = parse_map(MAP.replace("-45 ", "12.5 "))
    assert w.start[2] == pytest.approx(math.radians(12.5))


def test_map_empty_data_and_no_lines():
    text = "2D-Map\nMinPos: 0 0\nMaxPos: 1000 1000\nLINES\nDATA\n"
    w = parse_map(text)
    assert w.bounds == (0.0, 0.0, 1.0, 1.0)
    assert len(w.segments) == 0 and len(w.points) == 0


def test_map_bounds_without_minpos_come_from_line_positions():
    text = "2D-Map\nLineMinPos: 0 0\nLineMaxPos: 4000 2000\nLINES\n0 0 4000 2000\n"
    assert parse_map(text).bounds == (0.0, 0.0, 4.0, 2.0)


def test_map_inverted_minpos_is_no_data_and_bounds_cover_contents():
    text = (
        "2D-Map\nMinPos: 2147483647 2147483647\nMaxPos: -2147483648 -2147483648\n"
        "LineMinPos: 0 0\nLineMaxPos: 1000 1000\nLINES\n0 0 3000 1000\n"
    )
    # LineMaxPos understates the lines: the bounds still contain every wall
    assert parse_map(text).bounds == (0.0, 0.0, 3.0, 1.0)


def test_map_without_any_box_uses_the_default_margin():
    w = parse_map("2D-Map\nLINES\n0 0 1000 0\n0 0 0 1000\n")
    assert w.bounds == (-0.5, -0.5, 1.5, 1.5)


def test_map_start_precedence():
    home = 'Cairn: RobotHome 100 200 10 "" ICON "h"\n'
    home2 = 'Cairn: RobotHome 900 900 0 "" ICON "h2"\n'
    dock = 'Cairn: Dock 300 400 20.5 "the dock" ICON "d"\n'
    base = "2D-Map\nMinPos: 0 0\nMaxPos: 1000 1000\n{}LINES\n0 0 1000 0\n"
    assert parse_map(base.format(dock)).start == pytest.approx(
        (0.3, 0.4, math.radians(20.5))
    )
    assert parse_map(base.format(dock + home)).start == pytest.approx(
        (0.1, 0.2, math.radians(10))
    )
    assert parse_map(base.format(home + dock)).start[:2] == (0.1, 0.2)
    assert parse_map(base.format(home + home2)).start[:2] == (0.1, 0.2)
    assert parse_map(base.format(dock + dock.replace("300", "700"))).start[0] == 0.3
    assert parse_map(base.format("")).start == (0.5, 0.5, 0.0)


def test_map_box_obstacle_is_four_walls():
    text = (
        "2D-Map\nMinPos: 0 0\nMaxPos: 5000 5000\n"
        'Cairn: Sim.BoxObstacle 1500 1250 0.000000 "a box" ICON "box1" '
        "1000 1000 2000 1500\n"
        "LINES\n"
    )
    w = parse_map(text)
    assert len(w.segments) == 4
    corners = {(s[0], s[1]) for s in w.segments} | {(s[2], s[3]) for s in w.segments}
    assert corners == {(1.0, 1.0), (2.0, 1.0), (2.0, 1.5), (1.0, 1.5)}
    # each corner is the end of one wall and the start of the next: a closed loop
    assert {(s[2], s[3]) for s in w.segments} == {(s[0], s[1]) for s in w.segments}
    assert w.distance_to_walls((1.5, 1.25)) == pytest.approx(0.25)


def test_map_rotated_box_obstacle_turns_about_the_map_origin():
    text = (
        "2D-Map\nMinPos: -5000 -5000\nMaxPos: 5000 5000\n"
        'Cairn: Sim.BoxObstacle 0 0 90 "" ICON "b" 1000 0 2000 500\nLINES\n'
    )
    w = parse_map(text)
    pts = np.concatenate([w.segments[:, :2], w.segments[:, 2:]])
    np.testing.assert_allclose(pts[:, 0].min(), -0.5, atol=1e-12)
    np.testing.assert_allclose(pts[:, 0].max(), 0.0, atol=1e-12)
    np.testing.assert_allclose(pts[:, 1].min(), 1.0, atol=1e-12)
    np.testing.assert_allclose(pts[:, 1].max(), 2.0, atol=1e-12)


@pytest.mark.parametrize(
    ("text", "line", "fragment"),
    [
        ("2D-Mop\nLINES\n", 1, "2D-Map"),
        ("\n\nLINES\n0 0 1 1\n", 3, "2D-Map"),
        ("2D-Map\nMinPos: 0\n", 2, "MinPos: x y"),
        ("2D-Map\nMaxPos: 0 zero\n", 2, "MaxPos: x y"),
        ("2D-Map\nLINES\n0 0 1 1\n0 0 1\n", 4, "4 numbers"),
        ("2D-Map\nLINES\n0 0 1 x\n", 3, "4 numbers"),
        ("2D-Map\nDATA\n1 2 3\n", 3, "2 numbers"),
        ("2D-Map\nDATA\n1 nan\n", 3, "2 numbers"),
        ("2D-Map\nDATA\n5\n", 3, "2 numbers"),
        ("2D-Map\n0 0 1 1\n", 2, "section"),
        ('2D-Map\nCairn: RobotHome 1 2 "" ICON ""\n', 2, "RobotHome x y th"),
        ("2D-Map\nCairn: Dock 1 2\n", 2, "Dock x y th"),
        ('2D-Map\nCairn: RobotHome 1 2 x "" ICON ""\n', 2, "RobotHome"),
        ('2D-Map\nCairn: Sim.BoxObstacle 0 0 0 "" ICON "b" 1 2 3\n', 2, "BoxObstacle"),
        (
            '2D-Map\nCairn: Sim.BoxObstacle 0 0 0 "" ICON "b" 1 2 3 z\n',
            2,
            "BoxObstacle",
        ),
    ],
)
def test_map_malformed_records_name_file_and_line(text, line, fragment):
    with pytest.raises(WorldFileError) as err:
        parse_map(text, source="bad.map")
    assert err.value.line == line
    assert str(err.value).startswith(f"bad.map:{line}: ")
    assert fragment in str(err.value)


@pytest.mark.parametrize(
    "text", ["", "\n", "2D-Map\n", "2D-Map\nResolution: 0\nLINES\nDATA\n"]
)
def test_map_empty_is_an_error(text):
    with pytest.raises(WorldFileError):
        parse_map(text, source="empty.map")


def test_map_unknown_cairns_are_not_checked():
    text = MAP.replace("LINES\n", "Cairn: Goal not numbers at all\nCairn:\nLINES\n")
    assert parse_map(text) == parse_map(MAP)


def test_shipped_office_map_has_its_box_and_points():
    from robotlib.world import WORLDS_DIR

    w = read_world(WORLDS_DIR / "office.map")
    box = {
        (7.0, 2.5, 8.0, 2.5),
        (8.0, 2.5, 8.0, 3.5),
        (8.0, 3.5, 7.0, 3.5),
        (7.0, 3.5, 7.0, 2.5),
    }
    assert box <= {tuple(s) for s in w.segments}
    assert len(w.points) > 0
    assert w.start == (1.5, 7.5, 0.0)  # the RobotHome, although the Dock comes first


# --------------------------------------------------------------------------
# round trips


@st.composite
def worlds(draw, with_points: bool, whole_mm: bool = True):
    """Random worlds whose contents lie within their bounds."""
    x0 = draw(st.integers(-50_000, 50_000))
    y0 = draw(st.integers(-50_000, 50_000))
    w = draw(st.integers(1, 100_000))
    h = draw(st.integers(1, 100_000))
    if whole_mm:
        xs = st.integers(x0, x0 + w).map(lambda v: v / 1000)
        ys = st.integers(y0, y0 + h).map(lambda v: v / 1000)
    else:
        xs = st.floats(x0 / 1000, (x0 + w) / 1000)
        ys = st.floats(y0 / 1000, (y0 + h) / 1000)
    n = draw(st.integers(0, 8))
    segs = [[draw(xs), draw(ys), draw(xs), draw(ys)] for _ in range(n)]
    pts = []
    if with_points:
        pts = [[draw(xs), draw(ys)] for _ in range(draw(st.integers(0, 8)))]
    theta = draw(st.floats(-math.pi, math.pi, exclude_min=True))
    start = (draw(xs), draw(ys), theta)
    bounds = (x0 / 1000, y0 / 1000, (x0 + w) / 1000, (y0 + h) / 1000)
    return World(np.reshape(segs, (-1, 4)), bounds=bounds, start=start, points=pts)


@SETTINGS
@given(worlds(with_points=False))
def test_wld_round_trip(world):
    again = parse_wld(format_wld(world))
    assert again == world


@SETTINGS
@given(worlds(with_points=True))
def test_map_round_trip(world):
    again = parse_map(format_map(world))
    assert again == world


@SETTINGS
@given(worlds(with_points=True, whole_mm=False))
def test_map_round_trip_any_float(world):
    assert parse_map(format_map(world)) == world


@SETTINGS
@given(worlds(with_points=False, whole_mm=False))
def test_wld_round_trip_any_float(world):
    assert parse_wld(format_wld(world)) == world


@pytest.mark.parametrize(
    "theta", [math.pi, -math.pi / 2, 1e-300, 5e-324, math.nextafter(math.pi, 0), 2.0]
)
def test_heading_round_trips_exactly(theta):
    w = World([[0.0, 0.0, 1.0, 1.0]], start=(0.5, 0.5, theta))
    assert parse_wld(format_wld(w)).start[2] == theta
    assert parse_map(format_map(w)).start[2] == theta


def test_whole_mm_are_written_as_integers():
    w = World([[0.001, -12.345, 1e6, 0.5]], start=(0.25, 0.5, 0.0))
    text = format_wld(w)
    assert "\n1 -12345 1000000000 500\n" in text
    assert "position 250 500 0\n" in text


def test_round_trip_through_files(tmp_path):
    w = World([[0.0, 0.0, 3.0, 0.0], [0.0, 0.0, 0.0, 2.0]], start=(1.0, 1.0, 2.0))
    write_wld(w, tmp_path / "w.wld")
    write_map(w, tmp_path / "w.map")
    assert read_world(tmp_path / "w.wld") == w
    assert read_world(tmp_path / "w.map") == w
    wp = World(w.segments, bounds=w.bounds, start=w.start, points=[[0.5, 0.5]])
    write_map(wp, tmp_path / "p.map")
    assert read_world(tmp_path / "p.map") == wp


# --------------------------------------------------------------------------
# garbage in: only WorldFileError (or a valid World) comes out


def _parse_or_error(parse, text):
    try:
        w = parse(text, source="fuzz")
    except WorldFileError as exc:
        assert exc.path == "fuzz"
        assert (
            exc.line is None or 1 <= exc.line <= text.count("\n") + text.count("\r") + 1
        )
        return None
    assert isinstance(w, World)
    assert np.all(np.isfinite(w.segments)) and np.all(np.isfinite(w.points))
    assert all(math.isfinite(b) for b in w.bounds)
    assert -math.pi < w.start[2] <= math.pi
    return w


ALPHABET = st.sampled_from(
    list('0123456789 -+.eE;:"\n\r\tabcxyzLINESDATA_') + ["\x00", "é"]
)


@pytest.mark.slow
@SETTINGS
@given(st.text(ALPHABET, max_size=200) | st.text(max_size=200))
def test_random_text(text):
    _parse_or_error(parse_wld, text)
    _parse_or_error(parse_map, text)
    _parse_or_error(parse_map, "2D-Map\n" + text)


@SETTINGS
@given(st.binary(max_size=200))
def test_random_bytes(data):
    for enc in ("latin-1", "utf-8"):
        text = data.decode(enc, errors="replace")
        _parse_or_error(parse_wld, text)
        _parse_or_error(parse_map, "2D-Map-Ex2\n" + text)


TOKENS = st.sampled_from(
    [
        "0",
        "-1",
        "1.5",
        "1e3",
        "nan",
        "inf",
        "x",
        '""',
        "ICON",
        "LINES",
        "DATA",
        ":",
        "Cairn:",
        "RobotHome",
        "Dock",
        "Sim.BoxObstacle",
        "MinPos:",
        "width",
        "position",
        "1e999",
        "99999999999999999999999",
        "1e-99999999999999999999999",
        "1e99999999999999999999999",
        "-0",
        "0.000000000000000000000000000000000001",
    ]
)


@st.composite
def mutated(draw, base: str):
    lines = base.split("\n")
    for _ in range(draw(st.integers(1, 4))):
        k = draw(st.integers(0, len(lines) - 1))
        op = draw(
            st.sampled_from(["delete", "duplicate", "token", "insert", "truncate"])
        )
        if op == "delete" and len(lines) > 1:
            del lines[k]
        elif op == "duplicate":
            lines.insert(k, lines[k])
        elif op == "token":
            toks = lines[k].split() or [""]
            j = draw(st.integers(0, len(toks) - 1))
            toks[j] = draw(TOKENS)
            lines[k] = " ".join(toks)
        elif op == "insert":
            lines.insert(k, " ".join(draw(st.lists(TOKENS, max_size=12))))
        else:
            lines[k] = lines[k][: draw(st.integers(0, len(lines[k])))]
    return "\n".join(lines)


@SETTINGS
@given(mutated(WLD))
def test_mutated_wld(text):
    _parse_or_error(parse_wld, text)


@SETTINGS
@given(
    mutated(
        MAP.replace(
            "LINES\n", 'Cairn: Sim.BoxObstacle 0 0 30 "" ICON "b" 1 2 300 400\nLINES\n'
        )
    )
)
def test_mutated_map(text):
    _parse_or_error(parse_map, text)


def test_error_is_a_value_error_and_pickles():
    import pickle

    err = WorldFileError("f.wld", 3, "expected something")
    assert isinstance(err, ValueError)
    again = pickle.loads(pickle.dumps(err))
    assert (again.path, again.line, str(again)) == (
        "f.wld",
        3,
        "f.wld:3: expected something",
    )
