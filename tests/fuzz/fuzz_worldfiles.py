"""Coverage-guided fuzzing of the world-file parsers (atheris), for a longer run.

The parsers must raise nothing but `robotlib.world.WorldFileError` on any
bytes, and whatever they accept must be a valid `World`. The bounded
property tests (``tests/world/test_robust_worlds.py``) run in every test run; this
target is for a developer with time::

    pip install -e ".[fuzz]"
    python tests/fuzz/fuzz_worldfiles.py -max_total_time=600 -rss_limit_mb=4096

libFuzzer's options follow the script (``-runs=N``, ``-jobs=2``) and then
corpus folders: the first one receives the new inputs, so give a scratch
folder first and ``worlds/`` (read only as seeds) after it::

    mkdir -p .fuzz-corpus
    python tests/fuzz/fuzz_worldfiles.py -max_total_time=600 .fuzz-corpus worlds/
 A crash writes the input to ``crash-*``:
replay it with ``python tests/fuzz/fuzz_worldfiles.py crash-...``.
"""

from __future__ import annotations

import io
import math
import sys


def check_bytes(data: bytes) -> None:
    """Parse ``data`` as both formats; only `WorldFileError` may come out.

    A world that parses has finite walls, bounds and start, within the limit.
    """
    # imported here, so that `main` can instrument robotlib before its import
    from robotlib.world import WorldFileError, read_map, read_wld

    for reader in (read_wld, read_map):
        try:
            world = reader(io.BytesIO(data))
        except WorldFileError:
            continue
        xmin, ymin, xmax, ymax = world.bounds
        assert all(math.isfinite(v) for v in (xmin, ymin, xmax, ymax))
        assert xmin < xmax and ymin < ymax
        assert all(math.isfinite(v) for v in world.start)


def main(argv: list[str]) -> None:
    """Run the atheris target (the ``fuzz`` extra) with libFuzzer's ``argv``."""
    import atheris  # the `fuzz` extra: only this script needs it

    with atheris.instrument_imports(include=["robotlib.world"]):
        import robotlib.world  # noqa: F401
    atheris.Setup(argv, check_bytes)
    atheris.Fuzz()


if __name__ == "__main__":
    main(sys.argv)
