"""The `.map` reader's fast path for runs of plain integer records.

`robotlib.world.mapfile._int_run` reads runs of DATA/LINES records made of
plain integers without `decimal`; every map must read to the very same
floats (signed zeros included), points and walls in the same order, and the
same errors, as the record-by-record path gives.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robotlib.world import WorldFileError, mapfile, parse_map

SPACE = st.sampled_from([" ", "  ", "\t", " \t"])
PAD = st.sampled_from(["", " ", "\t"])
INT = st.one_of(
    st.integers(-4_000_000, 4_000_000).map(str),  # within the 10 km a world may span
    st.sampled_from(["-0", "+0", "0", "+12", "-0007", "00000001", "4000000"]),
)
# lines the fast path must leave to the full path: read there, or rejected
VALID = st.sampled_from(
    ["", "   ", "1.5 2.25 3 4", "3e2 4 0 1", "1.0 -0.0 2 2",
     'Cairn: RobotHome 100 0 0 "" ICON "h"', "Resolution: 20"]
)  # fmt: skip
WRONG = st.sampled_from(
    [
        "1 2 3",
        "5",
        "x y",
        "1\u22122 3",
        "\u0661 2",
        "1,2 3",
        "10000001 0",
        "0 -123456789",
    ]
)


@st.composite
def records(draw, n):
    return draw(PAD) + draw(SPACE).join(draw(INT) for _ in range(n)) + draw(PAD)


@st.composite
def map_text(draw):
    lines = ["2D-Map", "MinPos: -5000 -5000", "MaxPos: 5000 5000"]
    for _ in range(draw(st.integers(1, 3))):
        section, n = draw(st.sampled_from([("DATA", 2), ("LINES", 4)]))
        lines.append(section)
        valid = VALID.map(
            lambda v, n=n: " ".join(v.split()[:n]) if v[:1].isdigit() else v
        )
        lines += draw(st.lists(st.one_of(records(n), records(n), valid), max_size=60))
        if draw(st.integers(0, 9)) == 0:  # now and then a record the reader refuses
            lines.insert(draw(st.integers(1, len(lines))), draw(WRONG))
    return draw(st.sampled_from(["\n", "\r\n", "\r"])).join(lines) + "\n"


def parsed(text):
    try:
        w = parse_map(text)
    except WorldFileError as e:
        return ("error", str(e))
    return (
        np.asarray(w.segments, dtype=float).tobytes(),
        np.asarray(w.points, dtype=float).tobytes(),
        w.bounds,
    )


@settings(max_examples=150, deadline=None)
@given(map_text())
def test_runs_read_as_the_record_by_record_path(text):
    fast = parsed(text)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mapfile, "_int_run", lambda lines, first, n: ([], 0))
        slow = parsed(text)
    assert fast == slow


def test_a_long_run_with_records_interleaved_reads_whole():
    rows = [f"{k} {-k}" if k % 97 else f"{k}.5 {-k}" for k in range(5000)]
    rows[0] = "0 -0"
    w = parse_map("2D-Map\nDATA\n" + "\n".join(rows) + "\n")
    pts = np.asarray(w.points)
    assert pts.shape == (5000, 2)
    np.testing.assert_array_equal(pts[:, 1], -np.arange(5000) / 1000.0)
    assert pts[97, 0] == 97.5 / 1000.0 and np.signbit(pts[0, 1])  # "-0": -0.0
