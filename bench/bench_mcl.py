"""MCL step per particle count: fast path, exact path and plain NumPy.

Run ``python bench/bench_mcl.py [--json FILE]`` (the same as
``robotlib bench mcl``). Prints milliseconds per step and ratios, and the
cone table's build time and memory for the office world (21 m x 16 m).
"""

import sys

from robotlib.cli import main

if __name__ == "__main__":
    sys.exit(main(["bench", "mcl", *sys.argv[1:]]))
