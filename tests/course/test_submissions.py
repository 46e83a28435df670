"""Finding each student's notebook in the layouts students really hand in."""

from __future__ import annotations

import os

from robotlib.course.submissions import copies, find_submissions


def _nb(path, mtime=None):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("{}")
    if mtime is not None:
        os.utime(path, (mtime, mtime))
    return path


def test_the_newest_copy_untitled_sections_outputs_links_and_names(tmp_path):
    subs = tmp_path / "subs"
    old = _nb(subs / "ann" / "tiny.ipynb", mtime=1_000_000)
    new = _nb(subs / "ann" / "tiny (1).ipynb", mtime=2_000_000)
    _nb(subs / "bob" / "Untitled.ipynb")
    bob = _nb(subs / "bob" / "tiny-Copy1.ipynb")
    _nb(subs / "section2" / "cy" / "tiny.ipynb")
    _nb(subs / "section2" / "dee" / "work" / "tiny.ipynb")
    out = subs / "gb.csv"
    out.write_text("student\n")
    _nb(subs / "gb-records" / "x.ipynb")  # the grader's outputs inside the folder
    (subs / "x.ipynb").symlink_to(old)
    latin = os.fsdecode(b"Jos\xe9")
    _nb(subs / latin / "tiny.ipynb")
    listed = find_submissions(subs, "tiny", (out, subs / "gb-records"))
    found = {s: (p, st) for s, p, st in listed}
    assert found["ann"] == (new, "")
    assert copies(new, "tiny") == [old]
    assert found["bob"] == (bob, "")
    assert found["section2/cy"][0].parent.name == "cy"
    assert found["section2/dee"][0].parent.name == "work"
    assert found["x"] == (None, "a symbolic link, not graded")
    assert found["José"][0] is not None
    assert "gb-records" not in found and "gb" not in found
    assert set(found) == {"ann", "bob", "section2/cy", "section2/dee", "x", "José"}
