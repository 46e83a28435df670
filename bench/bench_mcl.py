"""The MCL step per particle count: robotlib, its exact path, a plain pipeline, a peer.

Run ``python bench/bench_mcl.py [--json FILE]`` (the same as
``robotlib bench mcl``). Prints milliseconds per step and the ratios
robotlib / plain (``bench/plain_mcl.py``) and Robotics Toolbox / robotlib,
the cone table's build time and memory for the office world (21 m x 16 m)
and a 20 m x 20 m square of rooms, and the time to the end of the first
step of a filter in a fresh process (numba's cache warm). ``--help`` lists
the options (``--n``, ``--reps``, ``--table-world``, ``--no-first-step``,
``--no-peers``).
"""

import sys

from robotlib.cli import main

if __name__ == "__main__":
    sys.exit(main(["bench", "mcl", *sys.argv[1:]]))
